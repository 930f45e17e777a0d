// Replays the fuzz seed corpus, the saved regressions and the bad-input catalog through the
// fuzz targets' property checks in the normal test suite, so a fixed fuzz finding stays fixed
// in every build (Debug, Release, sanitizer) without clang or libFuzzer.
#include "fuzz_checks.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace {

const fs::path kFuzzDir = HMSM_FUZZ_DIR;
const fs::path kBadDir = fs::path(HMSM_TEST_DATA) / "bad";

enum class Kind { tree, forest, schedule };

int replay(const std::vector<fs::path>& folders, Kind kind) {
    int files = 0;
    for (const fs::path& folder : folders) {
        if (!fs::is_directory(folder)) continue;
        for (const auto& entry : fs::directory_iterator(folder)) {
            if (!entry.is_regular_file()) continue;
            std::ifstream in(entry.path(), std::ios::binary);
            std::stringstream s;
            s << in.rdbuf();
            const std::string bytes = s.str();
            const auto* data = reinterpret_cast<const uint8_t*>(bytes.data());
            std::string failure =
                kind == Kind::forest     ? hmsm::fuzz::check_forest(data, bytes.size(), (kFuzzDir / "models").string())
                : kind == Kind::schedule ? hmsm::fuzz::check_schedule(data, bytes.size())
                                         : hmsm::fuzz::check_tree(data, bytes.size());
            EXPECT_EQ(failure, "") << entry.path();
            ++files;
        }
    }
    return files;
}

}  // namespace

TEST(FuzzReplay, TreeCorpusRegressionsAndCatalog) {
    int files = replay({kFuzzDir / "corpus" / "tree", kFuzzDir / "regressions" / "tree", kBadDir / "trees"}, Kind::tree);
    EXPECT_GE(files, 30);
}

TEST(FuzzReplay, ForestCorpusRegressionsAndCatalog) {
    int files = replay({kFuzzDir / "corpus" / "forest", kFuzzDir / "regressions" / "forest", kBadDir / "forests"}, Kind::forest);
    EXPECT_GE(files, 10);
}

TEST(FuzzReplay, ScheduleCorpusRegressionsAndCatalog) {
    int files = replay({kFuzzDir / "corpus" / "schedule", kFuzzDir / "regressions" / "schedule", kBadDir / "schedules"},
                       Kind::schedule);
    EXPECT_GE(files, 30);
}
