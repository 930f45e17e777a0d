// hmsm bench's result as text: every table of a result document, and a device's page
// (`--out STEM`: STEM.json and STEM.md) written from a run or from an earlier JSON file.
#pragma once

#include "cli_common.h"

#include <nlohmann/json.hpp>

#include <string>

namespace hmsm::cli::bench {

/// Every table of a result document, as a run prints them on stdout.
std::string render_tables(const nlohmann::json& document);

/// Stages STEM.json (`json_text`) and STEM.md (a header naming the device, the stem's file name,
/// with the commit and date, then the tables): both are written whole at commit, or neither.
Status write_page(StagedOutputs& outputs, const std::string& stem, const std::string& json_text,
                  const nlohmann::json& document);

/// `--render PATH`: prints the tables of an earlier --json file, and writes its page where
/// `out_stem` is not empty. Returns the process exit status.
int render_file(const std::string& path, const std::string& out_stem);

}  // namespace hmsm::cli::bench
