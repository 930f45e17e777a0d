// Driving hmsm from an engine (docs/driving.md): a small forest, per-frame wind with a gust ramp
// and a turn of direction, a character pushing through the branches, a blast, and instances
// streamed in, out and paused, with the joint matrices read back every frame.
// Built with the tests (HMSM_BUILD_TESTS) so that it keeps compiling; run: hmsm_example_driving.
#include <hmsm/hmsm.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace {

int fail(const hmsm::Status& status) {
    std::fprintf(stderr, "driving: %s\n", status.message().c_str());
    return 1;
}

/// A gust as a strength ramp: up over 1.5 s, hold 1 s, down over 2 s (smooth steps).
double gust(double t, double start) {
    auto smooth = [](double x) { x = std::clamp(x, 0.0, 1.0); return x * x * (3.0 - 2.0 * x); };
    return smooth((t - start) / 1.5) * (1.0 - smooth((t - start - 2.5) / 2.0));
}

}  // namespace

int main() {
    using namespace hmsm;
    auto tree = generate_preset("paper-5");
    if (!tree) return fail(tree.status());
    auto scene = grid_scene(std::move(tree).value(), 4, 12.0, 1);  // 2 x 2 trees, 12 m apart
    if (!scene) return fail(scene.status());

    SimulationConfig config;
    config.backend = BackendKind::cpu;  // or BackendKind::automatic: CUDA, Vulkan, then CPU
    config.wind.profile = WindProfile::turbulent;
    config.wind.strength = wind_strength_for_speed(5.0);  // a 5 m/s breeze
    config.wind.turbulence = 0.4;
    config.wind.front_speed = 5.0;  // gusts travel through the forest with the mean wind
    auto created = Simulation::create(*scene, config);
    if (!created) return fail(created.status());
    Simulation& sim = **created;

    const double fps = 60.0;
    const uint32_t steps_per_frame = uint32_t(std::lround(1.0 / (fps * config.parameters.dt)));
    const double base = config.wind.strength;
    const double peak = wind_strength_for_speed(14.0);  // the gust reaches 14 m/s
    std::vector<float> rotations, origins;
    for (int frame = 0; frame < 6 * int(fps); ++frame) {
        const double t = frame / fps;

        // Per-frame wind: the gust as a strength ramp, and the wind turning by 40 degrees.
        Wind wind = sim.wind();
        wind.strength = base + (peak - base) * gust(t, 1.0);
        const double heading = 0.7 * std::min(t / 6.0, 1.0);
        wind.direction = Vec3(std::cos(heading), 0.0, std::sin(heading));
        if (Status s = sim.set_wind(wind); !s) return fail(s);

        // Force fields: a character walking along x at 1.4 m/s brushes the branches within 1.5 m
        // of its chest; at t = 4 s a blast at the forest's centre pushes outwards for 0.25 s.
        std::vector<ForceField> fields;
        ForceField character;
        character.kind = ForceField::Kind::directional;
        character.center = Vec3(-8.0 + 1.4 * t, 1.3, -6.0);
        character.radius = 1.5;
        character.directional = Vec3(3.0, 0.0, 0.0);
        fields.push_back(character);
        if (t >= 4.0 && t < 4.25) {
            ForceField blast;
            blast.kind = ForceField::Kind::radial;
            blast.center = Vec3(0.0, 1.0, 0.0);
            blast.radius = 15.0;
            blast.radial = 40.0;
            fields.push_back(blast);
        }
        if (Status s = sim.set_force_fields(fields); !s) return fail(s);

        // Streaming: at t = 2 s the first tree leaves the world and one comes in farther away;
        // at t = 3 s the tree now at index 0 is paused (frozen in its pose), at t = 5 s resumed.
        if (frame == int(2 * fps)) {
            const uint64_t gone[] = {0};
            if (Status s = sim.remove_instances(gone); !s) return fail(s);
            Instance incoming;
            incoming.origin = Vec3(30.0, 0.0, 0.0);
            incoming.wind_scale = 1.3;  // an exposed forest edge
            incoming.wind_phase = 0.5;
            if (Status s = sim.add_instances({&incoming, 1}); !s) return fail(s);
        }
        if (frame == int(3 * fps))
            if (Status s = sim.set_instance_active(0, false); !s) return fail(s);
        if (frame == int(5 * fps))
            if (Status s = sim.set_instance_active(0, true); !s) return fail(s);

        if (Status s = sim.step(steps_per_frame); !s) return fail(s);

        // Skinning: chain c's joint matrix is [R_c | O_c] (R column-major, 9 floats; O 3 floats).
        if (Status s = sim.read(Output::chain_rotations, rotations); !s) return fail(s);
        if (Status s = sim.read(Output::chain_origins, origins); !s) return fail(s);
    }
    std::printf("driving: %llu steps, %llu instances, %zu joint matrices per frame, first joint origin "
                "(%.3f, %.3f, %.3f)\n",
                static_cast<unsigned long long>(sim.steps_done()),
                static_cast<unsigned long long>(sim.instances().size()), origins.size() / 3, origins[0],
                origins[1], origins[2]);
    return 0;
}
