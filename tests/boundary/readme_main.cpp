// Runs the README's example (readme_example.cpp, extracted verbatim from README.md at build
// time) on a generated tree written to a file, as an engine would load one.
#include <hmsm/hmsm.h>

#include <cstdio>
#include <unistd.h>
#include <filesystem>
#include <string>

void animate_tree(const std::string& tree_file);  // README.md

int main() {
    // A small tree keeps the example's 1,200 steps quick also under the sanitizers.
    hmsm::TreeModel tree;
    tree.nodes = {{-1, {0, 0, 0}, 0.2}, {0, {0, 2, 0}, 0.15}, {1, {0.3, 4, 0}, 0.1},
                  {1, {-0.8, 3, 0.2}, 0.05}, {3, {-1.2, 3.6, 0.3}, 0.03}};
    const std::filesystem::path file = std::filesystem::temp_directory_path() /
                                       ("hmsm-readme-oak-" + std::to_string(::getpid()) + ".json");
    if (!hmsm::save_tree(tree, file.string())) return 1;
    animate_tree(file.string());  // reports any failure on stderr as "hmsm: ..."
    std::filesystem::remove(file);
    std::printf("README example ran 600 frames\n");
    return 0;
}
