// hmsm analyze --whole-tree: the whole-tree report of tree_response.h on the command line.
#pragma once

#include "cli_common.h"

#include <string>

namespace hmsm::cli {

/// Registers --whole-tree and its flags (pull, release, sway speeds and seconds, plots).
void register_whole_tree_flags(CLI::App& app);
/// Whether --whole-tree was given.
bool whole_tree_requested();
/// Runs the report on every model of `scene` and prints it (text or JSON); writes the plots.
int run_whole_tree(const Scene& scene, const ModelOptions& options, const Parameters& parameters,
                   const Wind& wind, StagedOutputs& outputs, bool json, bool progress);

}  // namespace hmsm::cli
