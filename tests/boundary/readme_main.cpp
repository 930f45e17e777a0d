// Runs the README's example (readme_example.cpp, extracted verbatim from README.md at build
// time) on a generated tree written to a file, as an engine would load one.
#include <hmsm/hmsm.h>

#include <cstdio>
#include <unistd.h>
#include <filesystem>
#include <string>

void animate_tree(const std::string& tree_file);  // README.md

int main() {
    auto tree = hmsm::generate_preset("paper-1");
    if (!tree) return 1;
    const std::filesystem::path file =
        std::filesystem::temp_directory_path() / ("hmsm-readme-oak-" + std::to_string(::getpid()) + ".json");
    if (!hmsm::save_tree(*tree, file.string())) return 1;
    animate_tree(file.string());  // reports any failure on stderr as "hmsm: ..."
    std::filesystem::remove(file);
    std::printf("README example ran 600 frames\n");
    return 0;
}
