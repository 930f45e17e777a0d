// libFuzzer target: hmsm::parse_treeqsm on arbitrary bytes (see fuzz_import_checks.h).
#include "fuzz_import_checks.h"

#include <cstdio>
#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::string failure = hmsm::fuzz::check_treeqsm(data, size);
    if (!failure.empty()) {
        std::fprintf(stderr, "fuzz_treeqsm: %s\n", failure.c_str());
        std::abort();
    }
    return 0;
}
