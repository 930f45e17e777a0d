// hmsm export --gltf: simulates one instance and writes the clip as a skinned glTF 2.0 binary
// (docs/model.md 3.10 and 5).
#include "cli_common.h"
#include "export_gltf.h"
#include "step_progress.h"

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <optional>

namespace hmsm::cli {
namespace {
struct ExportFlags {
    SourceFlags source;
    ModelFlags model;
    Parameters parameters;
    WindFlags wind;
    std::string gltf;
    std::string backend = "cpu64";
    double seconds = 0.0;
    double fps = 0.0;
    int32_t max_joints = 0;  ///< with --max-joints: the finest level of detail within it
    bool no_progress = false;
} flags;
}  // namespace

void register_export_flags(CLI::App& app) {
    app.add_option("--gltf", flags.gltf, "output glTF 2.0 binary (.glb)")->required();
    add_source_flags(app, flags.source, false);
    // One instance: its origin and yaw go into the trunk joint (the skin's bind pose is the
    // model at the origin with yaw 0).
    app.add_option("--origin", flags.source.origin, "instance origin X,Y,Z (default 0,0,0)");
    app.add_option("--yaw", flags.source.yaw, "instance yaw in radians (default 0)");
    add_model_flags(app, flags.model);
    add_parameter_flags(app, flags.parameters);
    add_wind_flags(app, flags.wind);
    app.add_option("--seconds", flags.seconds, "clip length T in seconds")->required();
    app.add_option("--fps", flags.fps, "key frames per second F (frame k = 0 ... T*F)")->required();
    add_integer_option(app, "--max-joints", flags.max_joints,
                       "at most N joints: the finest level of detail within N (docs/export.md)");
    app.add_option("--backend", flags.backend, backend_choices(BackendKind::cpu64));
    app.add_flag("--no-progress", flags.no_progress, "no progress on stderr");
}

int run_export(CLI::App& app) {
    SimulationConfig config;
    auto backend = parse_backend(flags.backend, "--backend");
    if (!backend) return fail(backend.status());
    config.backend = *backend;
    if (!std::isfinite(flags.seconds) || flags.seconds < 0.0)
        return fail_input("--seconds " + std::to_string(flags.seconds) + ": must be finite and >= 0");
    if (!std::isfinite(flags.fps) || flags.fps <= 0.0)
        return fail_input("--fps " + std::to_string(flags.fps) + ": must be finite and > 0");
    if (flags.seconds * flags.fps > 1e7)
        return fail_input("--seconds " + std::to_string(flags.seconds) + " at --fps " + std::to_string(flags.fps) +
                          ": more than 10 million frames");
    const bool limit_joints = app.count("--max-joints") > 0;
    if (limit_joints && flags.max_joints < 1)
        return fail_input("--max-joints " + std::to_string(flags.max_joints) +
                          ": below the trunk-only level, the coarsest level there is (1 joint)");
    Status shared = apply_shared_options(config, flags.model, flags.parameters, flags.wind);
    if (!shared) return fail(shared);
    auto schedule = read_schedule_option(flags.wind);
    if (!schedule) return fail(schedule.status());
    auto scene = load_scene(flags.source, app, nullptr, scheduled_models(*schedule));
    if (!scene) return fail(scene.status());
    // A schedule may change the wind and the force fields; the clip covers one fixed instance.
    if (Status valid = check_schedule_option(flags.wind, *schedule, *scene, config.wind); !valid) return fail(valid);
    if (*schedule)
        for (const ScheduleEvent& e : (*schedule)->events)
            if (!e.instances.empty() || !e.remove.empty() || !e.add.empty())
                return fail_input("--wind-schedule: the event at step " + std::to_string(e.step) +
                                  " changes instances; an export covers one fixed instance (wind and forces only)");
    config.outputs = Outputs::joints;  // the clip needs the joint rotations alone (passes 1-5)

    StagedOutputs outputs;
    outputs.add_inputs({flags.source.tree, flags.source.forest, flags.wind.schedule});
    auto file = outputs.stage(flags.gltf, "--gltf");
    if (!file) return fail(file.status());

    auto created = Simulation::create(*scene, config);
    if (!created) return fail(created.status());
    Simulation& sim = **created;
    const Hierarchy& model_hierarchy = sim.hierarchy(0);
    const MeshTemplate& mesh = sim.mesh(0);
    // The joints: the model's chains, or those of the finest level within --max-joints, each
    // of which moves exactly as the model's chain it keeps (docs/model.md 3.12).
    std::optional<DetailLevel> level;
    if (limit_joints) {
        auto built = build_level(scene->models[0], model_hierarchy, config.parameters, flags.max_joints);
        if (!built) return fail_input("--max-joints: " + built.status().message());
        level = std::move(*built);
    }
    const Hierarchy& hierarchy = level ? level->hierarchy : model_hierarchy;
    const uint64_t frames = export_frame_count(flags.seconds, flags.fps);
    // Keys dominate the file: 16 bytes per joint and frame.
    const double key_bytes = double(frames) * double(hierarchy.chains.size()) * 16.0;
    if (key_bytes > double(1u << 30))
        return fail_input("--seconds " + std::to_string(flags.seconds) + " at --fps " + std::to_string(flags.fps) +
                          ": " + std::to_string(frames) + " frames of " + std::to_string(hierarchy.chains.size()) +
                          " joints need more than 1 GiB of keys");

    auto skin = derive_skin(level ? build_skin(scene->models[0], model_hierarchy, mesh, config.model, *level)
                                  : build_skin(scene->models[0], model_hierarchy, mesh, config.model),
                            hierarchy, mesh);
    if (!skin) return fail(skin.status());

    JointClip clip;
    clip.fps = flags.fps;
    std::vector<double> rotations, joint_rotations;
    uint64_t done = 0;
    StepProgress progress(frames, !flags.no_progress, "frame");
    for (uint64_t k = 0; k < frames; ++k) {
        const uint64_t target = export_frame_steps(k, flags.fps, config.parameters.dt);
        while (done < target) {
            uint64_t chunk = std::min<uint64_t>(target - done, 240);
            if (*schedule) {  // events apply before their step (docs/model.md 4)
                Status applied = apply_schedule_events(**schedule, done + 1, sim);
                if (!applied) return fail(applied);
                if (auto next = next_schedule_step(**schedule, done + 1)) chunk = std::min(chunk, *next - (done + 1));
            }
            Status stepped = sim.step(uint32_t(chunk));
            if (!stepped) return fail(stepped);
            done += chunk;
        }
        Status read = sim.read(Output::chain_rotations, rotations);
        if (!read) return fail(read);
        if (level) {  // each joint takes the rotation of the model's chain it keeps
            joint_rotations.clear();
            for (int32_t source : level->source_chain)
                joint_rotations.insert(joint_rotations.end(), rotations.begin() + 9 * source,
                                       rotations.begin() + 9 * source + 9);
        }
        append_clip_frame(clip, hierarchy, level ? joint_rotations : rotations);
        progress.update(k + 1);
    }
    progress.finish();

    const std::string name = flags.source.preset.empty() ? "tree" : flags.source.preset;
    auto glb = build_glb(hierarchy, mesh, *skin, clip, glm::dvec3(scene->instances[0].origin), name);
    if (!glb) return fail(glb.status());
    Status written = outputs.write(*file, glb->data(), glb->size());
    if (!written) return fail(written);
    Status committed = outputs.commit();
    if (!committed) return fail(committed);
    std::fprintf(stderr,
                 "hmsm: exported %" PRIu64 " frames (%" PRIu64 " steps on %s) of %zu joints, %zu vertices to %s\n",
                 frames, done, to_string(sim.backend_kind()), hierarchy.chains.size(), mesh.vertices.size(),
                 flags.gltf.c_str());
    return kExitOk;
}

}  // namespace hmsm::cli
