// An engine's frame loop on its own Vulkan device (docs/vulkan.md, "An engine's frame"): the
// engine creates the instance and device, runs three frames in flight, and per frame sets the
// wind and moves a force field, records hmsm's steps into its own command buffer
// (hmsm::vulkan::record_steps), then draws the tree with a skinning vertex shader that reads
// hmsm's joint matrices straight from the simulation's device buffer, into an offscreen image.
// A few frames are written as PNG files.
//
// Run: hmsm_example_engine_loop [output folder]. It checks what it drew and exits non-zero on
// any failure or validation message (77 when there is no usable Vulkan device):
// - the skinned positions the vertex shader wrote in the last frame equal hmsm::skin_vertices
//   on the CPU from the joint matrices read back after the frame;
// - the triangles they make, projected, fall on tree pixels of the last image;
// - every saved image has tree pixels, and the first and last differ (the tree moved).
#include "../common/engine_vulkan.h"
#include "tree_pass.h"

#include <hmsm/hmsm.h>
#include <hmsm/vulkan.h>

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>

namespace {

constexpr uint32_t kFramesInFlight = 3;
constexpr uint32_t kFrames = 8;
constexpr uint32_t kStepsPerFrame = 12;  // 0.1 s of simulated time at dt = 1/120 s

bool write_png(const std::string& path, const uint8_t* rgba, uint32_t width, uint32_t height) {
    FILE* file = std::fopen(path.c_str(), "wb");
    if (!file) return false;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!info || setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, info ? &info : nullptr);
        std::fclose(file);
        return false;
    }
    png_init_io(png, file);
    png_set_IHDR(png, info, width, height, 8, PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    for (uint32_t y = 0; y < height; ++y) png_write_row(png, rgba + size_t(y) * width * 4);
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    return std::fclose(file) == 0;
}

/// An orthographic camera looking along -z at the tree's rest bounds, with room to sway:
/// column-major, Vulkan clip space (y down, z in [0, 1]).
std::array<float, 16> camera(const hmsm::SkinTemplate& skin) {
    double lo[2] = {1e30, 1e30}, hi[2] = {-1e30, -1e30};
    for (const hmsm::SkinVertex& v : skin.vertices)
        for (int k = 0; k < 2; ++k) {
            lo[k] = std::min(lo[k], v.position[k]);
            hi[k] = std::max(hi[k], v.position[k]);
        }
    const double half = 0.65 * std::max(hi[0] - lo[0], hi[1] - lo[1]);
    const double cx = 0.5 * (lo[0] + hi[0]), cy = 0.5 * (lo[1] + hi[1]);
    return {float(1 / half), 0, 0, 0, 0, float(-1 / half), 0, 0, 0, 0, 0, 0, float(-cx / half), float(cy / half), 0.5f, 1};
}

bool is_background(const uint8_t* pixel) {
    return std::equal(pixel, pixel + 4, engine::TreePass::kBackground.begin());
}

uint64_t tree_pixels(const std::vector<uint8_t>& image) {
    uint64_t count = 0;
    for (size_t i = 0; i < image.size(); i += 4) count += !is_background(&image[i]);
    return count;
}

int fail(const std::string& message) {
    std::fprintf(stderr, "engine_loop: %s\n", message.c_str());
    return 1;
}

/// The engine's per-frame changes: a wind that strengthens and turns, and a radial force field
/// (say a character) walking through the crown.
hmsm::Status change_for_frame(hmsm::Simulation& sim, uint32_t frame, double height) {
    hmsm::Wind wind = sim.wind();
    wind.strength = 8.0 + 1.5 * double(frame);
    const double heading = 0.1 * double(frame);
    wind.direction = hmsm::Vec3(std::cos(heading), 0.0, std::sin(heading));
    if (hmsm::Status s = sim.set_wind(wind); !s) return s;
    hmsm::ForceField field;
    field.kind = hmsm::ForceField::Kind::radial;
    field.center = hmsm::Vec3(-0.3 * height + 0.08 * height * double(frame), 0.6 * height, 0.0);
    field.radius = 0.3 * height;
    field.radial = 20.0;
    return sim.set_force_fields({&field, 1});
}

int run(const std::string& folder) {
    std::error_code error;
    std::filesystem::create_directories(folder, error);
    if (error) return fail("cannot create the output folder " + folder + ": " + error.message());
    const char* require = std::getenv("HMSM_VULKAN_REQUIRE_VALIDATION");
    engine::DeviceOptions options;
    options.require_validation = require && std::string(require) == "1";
    engine::Device device(options);

    // A small preset, one tree at the origin (yaw 0: world = the skin's bind space).
    auto tree = hmsm::generate_preset("paper-5");
    if (!tree) return fail(tree.status().message());
    const double height = hmsm::tree_height(*tree);
    hmsm::Scene scene = hmsm::single_tree_scene(std::move(tree).value());
    hmsm::SimulationConfig config;
    config.outputs = hmsm::Outputs::joints;  // passes 1-5: the engine skins the mesh itself

    hmsm::vulkan::ExternalContext context;
    context.instance = device.instance();
    context.physical_device = device.physical_device();
    context.device = device.handle();
    context.queue = device.queue();
    context.queue_family_index = device.queue_family();
    context.get_instance_proc_addr = vkGetInstanceProcAddr;
    context.frames_in_flight = kFramesInFlight;
    auto created = hmsm::vulkan::create_simulation(scene, config, context);
    if (!created) return fail(created.status().message());
    hmsm::Simulation& sim = **created;

    // The skinned vertex buffer, built once: bind pose, two joints and weights per vertex.
    const hmsm::SkinTemplate skin = hmsm::build_skin(scene.models[0], sim.hierarchy(0), sim.mesh(0), sim.config().model);
    std::vector<engine::SkinnedVertex> vertices;
    for (const hmsm::SkinVertex& v : skin.vertices)
        vertices.push_back({{float(v.position.x), float(v.position.y), float(v.position.z)},
                            {v.joints[0], v.joints[1]},
                            {float(v.weights[0]), float(v.weights[1])}});
    std::vector<float> inverse_binds;
    for (const auto& m : skin.inverse_bind) inverse_binds.insert(inverse_binds.end(), m.begin(), m.end());
    const std::vector<uint32_t>& indices = sim.mesh(0).indices;

    auto buffers = hmsm::vulkan::shared_buffers(sim);
    if (!buffers) return fail(buffers.status().message());
    const hmsm::vulkan::BufferRange joints = buffers->joint_matrices;
    const std::array<float, 16> view_proj = camera(skin);
    std::vector<std::vector<uint8_t>> saved;  // the images written, in frame order
    std::vector<float> last_skinned;
    {
        engine::TreePass pass(device, vertices, indices, inverse_binds, joints.buffer, joints.offset, joints.size,
                              kFramesInFlight);
        engine::Frames frames(device, kFramesInFlight);
        // Collects frame `f` once its fence has signalled: every third frame and the last
        // become PNG files.
        auto collect = [&](uint32_t f) -> bool {
            const uint32_t slot = f % kFramesInFlight;
            const size_t bytes = size_t(engine::TreePass::kWidth) * engine::TreePass::kHeight * 4;
            if (f == kFrames - 1)
                last_skinned.assign(pass.skinned(slot), pass.skinned(slot) + 4 * vertices.size());
            if (f % 3 != 0 && f != kFrames - 1) return true;
            saved.emplace_back(pass.pixels(slot), pass.pixels(slot) + bytes);
            char name[32];
            std::snprintf(name, sizeof name, "/frame_%02u.png", f);
            std::printf("frame %u: %s%s\n", f, folder.c_str(), name);
            return write_png(folder + name, pass.pixels(slot), engine::TreePass::kWidth, engine::TreePass::kHeight);
        };
        for (uint32_t f = 0; f < kFrames; ++f) {
            if (hmsm::Status s = change_for_frame(sim, f, height); !s) return fail(s.message());
            VkCommandBuffer cmd = frames.begin(f);  // waits for frame f - 3
            if (f >= kFramesInFlight && !collect(f - kFramesInFlight)) return fail("cannot write a PNG in " + folder);
            if (hmsm::Status s = hmsm::vulkan::record_steps(sim, cmd, kStepsPerFrame); !s) {
                frames.submit(f);
                return fail("frame " + std::to_string(f) + ": " + s.message());
            }
            pass.record(cmd, f % kFramesInFlight, view_proj);
            frames.submit(f);
        }
        frames.wait_all();
        for (uint32_t f = kFrames - kFramesInFlight; f < kFrames; ++f)
            if (!collect(f)) return fail("cannot write a PNG in " + folder);
    }

    // The last frame's skinned vertices against the CPU skinning of the joint matrices.
    std::vector<float> palette, cpu(3 * vertices.size());
    if (hmsm::Status s = sim.read(hmsm::Output::joint_matrices, palette); !s) return fail(s.message());
    if (hmsm::Status s = hmsm::skin_vertices(skin, palette, cpu); !s) return fail(s.message());
    const std::set<uint32_t> drawn(indices.begin(), indices.end());
    double worst = 0.0, rest = 0.0;
    uint64_t off_tree = 0;
    const std::vector<uint8_t>& last = saved.back();
    for (uint32_t v : drawn) {
        for (int k = 0; k < 3; ++k) {
            const double d = std::abs(double(last_skinned[4 * v + k]) - cpu[3 * v + k]);
            worst = std::max(worst, std::isfinite(d) ? d : INFINITY);
            rest = std::max(rest, std::abs(double(cpu[3 * v + k]) - skin.vertices[v].position[k]));
        }
    }
    // The silhouette: the centre of every triangle at least 2 pixels large, as the CPU skins
    // it, falls on a drawn pixel (or a neighbour, for rounding at the edges).
    const auto pixel_of = [&](uint32_t v) {
        return std::array<double, 2>{
            (view_proj[0] * cpu[3 * v] + view_proj[12] + 1.0) * 0.5 * engine::TreePass::kWidth,
            (view_proj[5] * cpu[3 * v + 1] + view_proj[13] + 1.0) * 0.5 * engine::TreePass::kHeight};
    };
    uint64_t checked = 0;
    for (size_t t = 0; t + 2 < indices.size(); t += 3) {
        const auto a = pixel_of(indices[t]), b = pixel_of(indices[t + 1]), c = pixel_of(indices[t + 2]);
        const double area = 0.5 * std::abs((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
        if (area < 2.0) continue;
        ++checked;
        const int x = int((a[0] + b[0] + c[0]) / 3.0), y = int((a[1] + b[1] + c[1]) / 3.0);
        bool covered = false;
        for (int dy = -1; dy <= 1 && !covered; ++dy)
            for (int dx = -1; dx <= 1 && !covered; ++dx) {
                const int px = x + dx, py = y + dy;
                if (px < 0 || py < 0 || px >= int(engine::TreePass::kWidth) || py >= int(engine::TreePass::kHeight))
                    continue;
                covered = !is_background(&last[(size_t(py) * engine::TreePass::kWidth + px) * 4]);
            }
        off_tree += !covered;
    }
    std::printf("%zu vertices drawn: largest GPU - CPU skinning difference %.3g m, largest displacement from "
                "rest %.3g m; %llu of %llu triangles off the tree's pixels\n",
                drawn.size(), worst, rest, (unsigned long long)off_tree, (unsigned long long)checked);
    if (!(worst <= 1e-5 * height)) return fail("the vertex shader's skinning differs from skin_vertices");
    if (!(rest > 1e-3 * height)) return fail("the tree did not move");
    if (checked < 50) return fail("too few triangles large enough to check the silhouette");
    if (off_tree) return fail(std::to_string(off_tree) + " skinned triangles fall outside the drawn tree");
    for (const auto& image : saved)
        if (tree_pixels(image) < 200) return fail("an image has almost no tree pixels");
    uint64_t changed = 0;
    for (size_t i = 0; i < last.size(); i += 4)
        changed += is_background(&saved.front()[i]) != is_background(&last[i]);
    std::printf("tree pixels: first %llu, last %llu; %llu pixels changed\n",
                (unsigned long long)tree_pixels(saved.front()), (unsigned long long)tree_pixels(last),
                (unsigned long long)changed);
    if (changed < 20) return fail("the first and last images hardly differ");
    created.value().reset();  // before the engine's device
    if (device.validation_messages()) return fail(std::to_string(device.validation_messages()) + " validation message(s)");
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    const std::string folder = argc > 1 ? argv[1] : ".";
    try {
        return run(folder);
    } catch (const engine::NoDevice& e) {
        std::fprintf(stderr, "engine_loop: skipped: %s\n", e.what());
        return 77;
    } catch (const std::exception& e) {
        return fail(e.what());
    }
}
