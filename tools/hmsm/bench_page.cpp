#include "bench_page.h"

#include "bench_depth.h"
#include "bench_dynamics.h"
#include "bench_frames.h"
#include "bench_joints.h"
#include "bench_live.h"
#include "bench_open_world.h"
#include "bench_report.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace hmsm::cli::bench {

using nlohmann::json;

std::string render_tables(const json& document) {
    return render_markdown(document) + render_joint_forest(document.value("forest_joints", json::array())) +
           render_live_control(document.value("live_control", json::array())) +
           render_composition_depths(document.value("composition_depths", json::array())) +
           render_frames(document.value("frames", json::array())) +
           render_dynamics(document.value("dynamics", json::array())) +
           render_open_world(document.value("open_world", json::array()));
}

namespace {

std::string render_page(const json& document, const std::string& stem) {
    const std::string device = std::filesystem::path(stem).filename().string();
    std::string page = "# hmsm bench: " + device + "\n\n";
    page += "The newest result on this device: commit " + document.value("commit", std::string("unknown")) +
            ", " + document.value("date", std::string("unknown")) + ". Raw result: [" + device + ".json](" +
            device + ".json). Written by `hmsm bench --out`; a re-run replaces both files. The method, the "
            "byte model and the JSON schema: docs/benchmarks/README.md.\n\n";
    return page + render_tables(document);
}

}  // namespace

Status write_page(StagedOutputs& outputs, const std::string& stem, const std::string& json_text,
                  const json& document) {
    auto json_file = outputs.stage(stem + ".json", "--out");
    if (!json_file) return json_file.status();
    auto page_file = outputs.stage(stem + ".md", "--out");
    if (!page_file) return page_file.status();
    const std::string page = render_page(document, stem);
    Status written = outputs.write(*json_file, json_text.data(), json_text.size());
    if (written) written = outputs.write(*page_file, page.data(), page.size());
    return written;
}

int render_file(const std::string& path, const std::string& out_stem) {
    std::ifstream in(path);
    if (!in) return fail_input("--render '" + detail::quote_input(path) + "': cannot read the file");
    std::stringstream text;
    text << in.rdbuf();
    json document = json::parse(text.str(), nullptr, false);
    if (document.is_discarded() || !document.is_object() || document.value("format", "") != "hmsm-bench")
        return fail_input("--render '" + detail::quote_input(path) + "': not an hmsm-bench JSON document");
    StagedOutputs outputs;
    if (!out_stem.empty()) {
        Status staged = write_page(outputs, out_stem, text.str(), document);
        if (!staged) return fail(staged);
    }
    std::fputs(render_tables(document).c_str(), stdout);
    Status committed = outputs.commit();
    if (!committed) return fail(committed);
    return kExitOk;
}

}  // namespace hmsm::cli::bench
