// hmsm: the command-line tool (docs/model.md 5). Exit 0 on success, 2 on bad input or arguments,
// 1 on an internal or device error.
#include "cli_common.h"
#include "export_gltf.h"

#include <exception>

int main(int argc, char** argv) {
    using namespace hmsm::cli;
    CLI::App app{"hmsm: physically based tree animation in wind (HMSM, Yang & Wu 2011)"};
    app.require_subcommand(1);
    app.set_help_all_flag("--help-all", "help for every subcommand");
    CLI::App* generate = app.add_subcommand("generate", "write a preset tree to an hmsm-tree file");
    CLI::App* info = app.add_subcommand("info", "print the counts of a tree's hierarchy and mesh");
    CLI::App* simulate = app.add_subcommand("simulate", "run the simulation and dump its outputs");
    CLI::App* bench = app.add_subcommand("bench", "benchmark the backends: Table 1, passes, forests");
    CLI::App* import = app.add_subcommand("import", "turn a laser-scan cylinder model into an hmsm-tree file");
    CLI::App* analyze = app.add_subcommand("analyze", "how a tree sways: frequencies, deflection, step response, spectrum");
    CLI::App* export_ = app.add_subcommand("export", "write the animation as a skinned glTF 2.0 clip");
    int (*run)(CLI::App&) = nullptr;
    CLI::App* chosen = nullptr;
    generate->callback([&] { run = run_generate; chosen = generate; });
    info->callback([&] { run = run_info; chosen = info; });
    simulate->callback([&] { run = run_simulate; chosen = simulate; });
    bench->callback([&] { run = run_bench; chosen = bench; });
    import->callback([&] { run = run_import; chosen = import; });
    analyze->callback([&] { run = run_analyze; chosen = analyze; });
    export_->callback([&] { run = run_export; chosen = export_; });
#ifdef HMSM_HAVE_RENDER
    CLI::App* render = app.add_subcommand("render", "draw the animated tree offscreen to PNG frames and a GIF");
    render->callback([&] { run = run_render; chosen = render; });
    register_render_flags(*render);
#endif
    // Each subcommand registers its own flags; run_* with a null app only registers them.
    register_generate_flags(*generate);
    register_info_flags(*info);
    register_simulate_flags(*simulate);
    register_bench_flags(*bench);
    register_import_flags(*import);
    register_analyze_flags(*analyze);
    register_export_flags(*export_);
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::fprintf(stderr, "hmsm: error: %s (see --help)\n", e.what());
        return kExitBadInput;
    }
    try {
        return run(*chosen);
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "hmsm: error: out of host memory\n");
        return kExitInternal;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "hmsm: internal error: %s\n", e.what());
        return kExitInternal;
    }
}
