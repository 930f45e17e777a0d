#include "level_carry.h"

#include <utility>

namespace hmsm::detail {

LevelCarry make_level_carry(const std::vector<int32_t>& old_source, const std::vector<int32_t>& new_source,
                            std::vector<glm::dmat3> new_rest) {
    std::vector<int32_t> kept_at(old_source.empty() ? 0 : size_t(old_source.back()) + 1, -1);  // sources ascend
    for (size_t c = 0; c < old_source.size(); ++c) kept_at[size_t(old_source[c])] = int32_t(c);
    LevelCarry carry;
    carry.rest_rotation = std::move(new_rest);
    carry.old_chain.reserve(new_source.size());
    for (int32_t full : new_source) carry.old_chain.push_back(size_t(full) < kept_at.size() ? kept_at[size_t(full)] : -1);
    for (size_t j = 0; j < carry.old_chain.size(); ++j) {
        const int32_t c = carry.old_chain[j];
        if (c < 0) {
            if (!carry.unfolded.empty() && carry.unfolded.back().first + carry.unfolded.back().count == j)
                ++carry.unfolded.back().count;
            else carry.unfolded.push_back({j, 1});
            continue;
        }
        ElementMove* run = carry.kept.empty() ? nullptr : &carry.kept.back();
        if (run && run->src + run->count == uint64_t(c) && run->dst + run->count == j) ++run->count;
        else carry.kept.push_back({uint64_t(c), j, 1});
    }
    return carry;
}

}  // namespace hmsm::detail
