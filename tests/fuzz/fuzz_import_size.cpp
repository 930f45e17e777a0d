// libFuzzer target: the importers' size handling (docs/model.md 3.11). The first two bytes pick
// small limits (input bytes 16..4111, tree nodes 2..257); the rest is written to a file and
// imported through import_treeqsm or import_simpleforest (the third byte's low bit), so the
// file reader's size cap and the row count run on every input. A file past the byte limit must
// be refused as too large, one with more lines than nodes allowed as over the limit, before
// anything per line is built; any other input must give what fuzz_import_checks.h requires.
#include "fuzz_import_checks.h"

#include "model/input_limits.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include <unistd.h>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 3) return 0;
    hmsm::detail::SizeLimits limits = hmsm::detail::kDefaultSizeLimits;
    limits.input_bytes = 16 + uint64_t(data[0]) * 16;
    limits.tree_nodes = 2 + data[1];
    const bool simpleforest = data[2] & 1;
    const std::string_view body(reinterpret_cast<const char*>(data + 3), size - 3);
    hmsm::detail::ScopedSizeLimits scoped(limits);

    static const std::string path = "/tmp/hmsm_fuzz_import_size_" + std::to_string(::getpid());
    {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(body.data(), std::streamsize(body.size()));
    }
    auto imported = simpleforest ? hmsm::import_simpleforest(path) : hmsm::import_treeqsm(path);
    std::string failure = hmsm::fuzz::check_imported(imported);
    const uint64_t lines = uint64_t(std::count(body.begin(), body.end(), '\n')) + 1;
    if (failure.empty() && body.size() > limits.input_bytes &&
        (imported.ok() || imported.status().message().find("larger than") == std::string::npos))
        failure = "a file past the byte limit was not refused as too large";
    if (failure.empty() && body.size() <= limits.input_bytes && lines > limits.tree_nodes + 1 &&
        (imported.ok() || imported.status().message().find("more than the limit") == std::string::npos))
        failure = "a file of more lines than nodes allowed was not refused by its count";
    if (!failure.empty()) {
        std::fprintf(stderr, "fuzz_import_size: %s\n", failure.c_str());
        std::abort();
    }
    return 0;
}
