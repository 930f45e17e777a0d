// The fixture of the tests that run the hmsm command line (HMSM_CLI_PATH): a fresh scratch
// folder per test and the binary run with its stdout and stderr captured.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

namespace hmsm::test {

/// One run of the hmsm binary.
struct CliRun {
    int exit_code = -1;  ///< -1: it did not exit normally
    std::string out;     ///< stdout
    std::string err;     ///< stderr
};

/// The whole content of a file; empty when it cannot be read.
std::string read_text(const std::filesystem::path& file);

class CliFixture : public ::testing::Test {
protected:
    /// With `small_tree`, test::small_tree() is saved in the scratch folder as small.json.
    explicit CliFixture(bool small_tree = true) : small_tree_(small_tree) {}
    /// The scratch folder: <temp>/hmsm_<suite>_<test>_<pid>, created empty.
    void SetUp() override;
    void TearDown() override;

    /// A file in the scratch folder.
    std::string path(const std::string& name) const;
    /// Names of the files and folders in the scratch folder, sorted.
    std::vector<std::string> entries() const;

    /// Runs `hmsm ARGS` with `environment` ("NAME=value ...") prefixed, as run_command.
    CliRun run(const std::string& args, const std::string& environment = "");
    /// Runs a shell command; its stdout and stderr come back in the result, which is also kept
    /// in last_ (they are captured beside the scratch folder, never in it).
    CliRun run_command(const std::string& command);

    /// Bad input: `hmsm ARGS` exits 2 with one stderr line containing `fragment` and adds nothing
    /// to the scratch folder (no output, no staged temporary).
    void expect_bad_input(const std::string& args, const std::string& fragment);

    std::filesystem::path dir_;
    CliRun last_;

private:
    std::string capture(const char* stream) const;

    bool small_tree_;
};

}  // namespace hmsm::test
