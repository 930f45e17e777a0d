// hmsm bench: the markdown tables, rendered from the JSON document (docs/benchmarks/README.md),
// so a run's stdout and `hmsm bench --render FILE.json` print the same thing.
#pragma once

#include <nlohmann/json.hpp>

#include <string>

namespace hmsm::cli::bench {

std::string render_markdown(const nlohmann::json& document);

}  // namespace hmsm::cli::bench
