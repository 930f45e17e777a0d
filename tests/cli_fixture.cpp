#include "cli_fixture.h"

#include "test_trees.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace hmsm::test {

std::string read_text(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void CliFixture::SetUp() {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string("hmsm_") + info->test_suite_name() + "_" + info->name() + "_" +
                       std::to_string(getpid());
    std::replace(name.begin(), name.end(), '/', '_');  // parameterized tests
    dir_ = fs::temp_directory_path() / name;
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    if (small_tree_) {
        ASSERT_TRUE(save_tree(small_tree(), path("small.json")).ok());
    }
}

void CliFixture::TearDown() {
    fs::remove_all(dir_);
    fs::remove(capture("stdout"));
    fs::remove(capture("stderr"));
}

std::string CliFixture::capture(const char* stream) const { return dir_.string() + "." + stream + ".txt"; }

std::string CliFixture::path(const std::string& name) const { return (dir_ / name).string(); }

std::vector<std::string> CliFixture::entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

CliRun CliFixture::run(const std::string& args, const std::string& environment) {
    return run_command(environment + (environment.empty() ? "" : " ") + HMSM_CLI_PATH + " " + args);
}

CliRun CliFixture::run_command(const std::string& command) {
    const std::string redirected = command + " > " + capture("stdout") + " 2> " + capture("stderr");
    const int status = std::system(redirected.c_str());
    last_ = {WIFEXITED(status) ? WEXITSTATUS(status) : -1, read_text(capture("stdout")), read_text(capture("stderr"))};
    return last_;
}

void CliFixture::expect_bad_input(const std::string& args, const std::string& fragment) {
    SCOPED_TRACE(args);
    const std::vector<std::string> before = entries();
    const CliRun r = run(args);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find(fragment), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(entries(), before) << "the run left files behind";
}

}  // namespace hmsm::test
