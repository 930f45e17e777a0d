// libFuzzer target: hmsm::parse_tree on arbitrary bytes (see fuzz_checks.h for the properties).
#include "fuzz_checks.h"

#include <cstdio>
#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::string failure = hmsm::fuzz::check_schedule(data, size);
    if (!failure.empty()) {
        std::fprintf(stderr, "fuzz_schedule: %s\n", failure.c_str());
        std::abort();
    }
    return 0;
}
