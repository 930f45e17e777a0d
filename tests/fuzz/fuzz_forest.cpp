// libFuzzer target: hmsm::parse_forest on arbitrary bytes, with relative model paths resolving
// into tests/fuzz/models (see fuzz_checks.h for the properties).
#include "fuzz_checks.h"

#include <cstdio>
#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::string failure = hmsm::fuzz::check_forest(data, size, HMSM_FUZZ_MODELS_DIR);
    if (!failure.empty()) {
        std::fprintf(stderr, "fuzz_forest: %s\n", failure.c_str());
        std::abort();
    }
    return 0;
}
