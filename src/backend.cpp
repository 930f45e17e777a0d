// The defaults of the backend interface (backend.h) that need more than a line.
#include "backend.h"

#include <string>
#include <vector>

namespace hmsm::detail {

Status Backend::copy_patterns(std::span<const BufferId> ids, uint64_t capacity, std::span<const MovePattern> patterns,
                              std::span<const PatternCopy> copies) {
    std::vector<std::vector<ElementMove>> expanded(ids.size());
    std::vector<BufferMoves> moves;
    for (size_t b = 0; b < ids.size(); ++b) {
        const uint32_t halves = halves_of(ids[b]);
        for (uint32_t h = 0; h < halves; ++h)
            for (const PatternCopy& copy : copies) {
                if (copy.pattern >= patterns.size())
                    return {ErrorCode::internal, "copy_patterns: pattern " + std::to_string(copy.pattern) +
                                                     " of " + std::to_string(patterns.size())};
                for (const ElementMove& m : patterns[copy.pattern].moves)
                    expanded[b].push_back({h * capacity + copy.src + m.src, h * capacity + copy.dst + m.dst, m.count});
            }
        moves.push_back({ids[b], expanded[b]});
    }
    return move_buffers(moves);
}

}  // namespace hmsm::detail
