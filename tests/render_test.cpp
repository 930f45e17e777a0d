// The offscreen renderer and `hmsm render`: deterministic pictures, a plausible tree, motion
// under wind and none without it, a silent validation layer, and the CLI's all-or-nothing
// outputs. Without a Vulkan device the device tests skip with the reason.
#include "render/renderer.h"
#include "render/skinned.h"
#include "vulkan/validation.h"

#include "cli_fixture.h"
#include "test_trees.h"

#include <hmsm/hmsm.h>

#include <gtest/gtest.h>

#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#define STBI_ONLY_GIF
#include <stb/stb_image.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <string>
#include <vector>

namespace hmsm::test {
namespace {

namespace fs = std::filesystem;

// --- validation: every message while a test runs fails it ------------------------------------

struct Messages {
    std::mutex mutex;
    std::vector<std::string> list;
    bool enabled = false;
} g_messages;

std::vector<std::string> take_messages() {
    std::lock_guard lock(g_messages.mutex);
    return std::exchange(g_messages.list, {});
}

class RenderTest : public ::testing::Test {
protected:
    void SetUp() override { take_messages(); }
    void TearDown() override {
        auto messages = take_messages();
        EXPECT_TRUE(messages.empty()) << messages.size() << " validation message(s), first: "
                                      << messages.front();
    }
};

const Scene& test_scene() {
    static const Scene scene = single_tree_scene(*generate_preset("paper-5"));
    return scene;
}

render::RenderSettings small_settings() {
    render::RenderSettings settings;
    settings.width = 96;
    settings.height = 72;
    return settings;
}

/// A session, or null with `skip` set when this machine has no Vulkan device.
std::unique_ptr<render::Session> open_or_skip(const Scene& scene, SimulationConfig config,
                                              const render::RenderSettings& settings,
                                              std::string& skip) {
    config.profile_passes = false;
    auto session = render::open_session(scene, config, settings);
    if (!session.ok()) {
        if (session.status().code() == ErrorCode::no_device) skip = session.status().message();
        else ADD_FAILURE() << session.status().message();
        return nullptr;
    }
    return std::move(session).value();
}

#define OPEN_OR_SKIP(var, scene, config, settings)                    \
    std::string var##_skip;                                           \
    auto var = open_or_skip(scene, config, settings, var##_skip);     \
    if (!var) {                                                       \
        if (!var##_skip.empty()) GTEST_SKIP() << var##_skip;          \
        return;                                                       \
    }

/// `frames` pictures, `steps` simulation steps apart (the first after `steps` too).
std::vector<render::Image> render_frames(render::Session& session, int frames, uint32_t steps) {
    std::vector<render::Image> images(frames);
    for (auto& image : images) {
        Status drawn = session.renderer->render(steps, image);
        EXPECT_TRUE(drawn.ok()) << drawn.message();
    }
    return images;
}

/// Share of pixels whose colour differs between two pictures of one size.
double differing_share(const render::Image& a, const render::Image& b) {
    if (a.rgba.size() != b.rgba.size() || a.rgba.empty()) return -1.0;
    size_t differ = 0;
    for (size_t p = 0; p < a.rgba.size(); p += 4)
        differ += std::memcmp(&a.rgba[p], &b.rgba[p], 3) != 0;
    return double(differ) / double(a.rgba.size() / 4);
}

// --- without a device ------------------------------------------------------------------------

TEST(RenderSettings, RejectsBadValuesNamingTheFlag) {
    render::RenderSettings s;
    EXPECT_TRUE(render::validate(s).ok());
    auto bad = [](auto change, const char* flag) {
        render::RenderSettings s;
        change(s);
        Status status = render::validate(s);
        EXPECT_EQ(status.code(), ErrorCode::invalid_argument) << flag;
        EXPECT_NE(status.message().find(flag), std::string::npos) << status.message();
    };
    bad([](auto& s) { s.width = 4; }, "--width");
    bad([](auto& s) { s.height = 100000; }, "--height");
    bad([](auto& s) { s.msaa = 3; }, "--msaa");
    bad([](auto& s) { s.camera.distance = -1.0; }, "--camera-distance");
    bad([](auto& s) { s.camera.pitch_degrees = 90.0; }, "--camera-pitch");
    bad([](auto& s) { s.camera.fov_degrees = 1.0; }, "--fov");
    bad([](auto& s) { s.leaf_scale = 50.0; }, "--leaf-scale");
}

TEST(RenderCamera, DefaultFramingKeepsTheBoundsInsideThePicture) {
    render::Bounds bounds{{-3.0, 0.0, -2.0}, {4.0, 15.0, 2.5}};
    for (double yaw : {0.0, 40.0, 180.0, -75.0}) {
        render::CameraSettings settings;
        settings.yaw_degrees = yaw;
        const render::Camera camera = render::frame_camera(bounds, settings, 4.0 / 3.0, false);
        const glm::dmat4 vp = camera.view_projection();
        double widest = 0.0;
        for (int k = 0; k < 8; ++k) {
            glm::dvec4 corner((k & 1) ? bounds.max.x : bounds.min.x, (k & 2) ? bounds.max.y : bounds.min.y,
                              (k & 4) ? bounds.max.z : bounds.min.z, 1.0);
            glm::dvec4 clip = vp * corner;
            ASSERT_GT(clip.w, 0.0);
            const double x = clip.x / clip.w, y = clip.y / clip.w, z = clip.z / clip.w;
            EXPECT_LE(std::abs(x), 0.9 + 1e-9) << "yaw " << yaw;
            EXPECT_LE(std::abs(y), 0.9 + 1e-9) << "yaw " << yaw;
            EXPECT_GT(z, 0.0);
            EXPECT_LT(z, 1.0);
            widest = std::max({widest, std::abs(x), std::abs(y)});
        }
        EXPECT_GT(widest, 0.85) << "the bounds should fill the picture, yaw " << yaw;
    }
}

TEST(RenderImages, PngRoundTripsThroughADecoder) {
    render::Image image{7, 5, {}};
    for (uint32_t i = 0; i < 7 * 5; ++i)
        image.rgba.insert(image.rgba.end(), {uint8_t(i * 7), uint8_t(255 - i), uint8_t(i * 3), 255});
    auto png = render::encode_png(image);
    ASSERT_TRUE(png.ok()) << png.status().message();
    int w = 0, h = 0, channels = 0;
    stbi_uc* decoded = stbi_load_from_memory(png->data(), int(png->size()), &w, &h, &channels, 4);
    ASSERT_NE(decoded, nullptr);
    EXPECT_EQ(w, 7);
    EXPECT_EQ(h, 5);
    EXPECT_EQ(channels, 3);  // RGB: alpha dropped
    EXPECT_EQ(std::vector<uint8_t>(decoded, decoded + 7 * 5 * 4), image.rgba);
    stbi_image_free(decoded);
}

TEST(RenderImages, GifHoldsEveryFrameWithItsColours) {
    std::vector<uint8_t> bytes;
    auto gif = render::GifWriter::create(16, 8, [&](const uint8_t* data, size_t count) {
        bytes.insert(bytes.end(), data, data + count);
        return Status{};
    });
    ASSERT_TRUE(gif.ok());
    const uint8_t colours[3][3] = {{200, 30, 30}, {30, 200, 30}, {30, 30, 200}};
    for (const auto& colour : colours) {
        render::Image image{16, 8, {}};
        for (int p = 0; p < 16 * 8; ++p) image.rgba.insert(image.rgba.end(), {colour[0], colour[1], colour[2], 255});
        if (&colour == &colours[0])  // the palette comes from the first frame: give it all three
            for (int p = 0; p < 3; ++p) std::memcpy(&image.rgba[4 * p], colours[p], 3);
        ASSERT_TRUE(gif.value()->add_frame(image, 4).ok());
    }
    ASSERT_TRUE(gif.value()->finish().ok());
    int* delays = nullptr;
    int w = 0, h = 0, frames = 0, channels = 0;
    stbi_uc* decoded = stbi_load_gif_from_memory(bytes.data(), int(bytes.size()), &delays, &w, &h,
                                                 &frames, &channels, 4);
    ASSERT_NE(decoded, nullptr);
    EXPECT_EQ(w, 16);
    EXPECT_EQ(h, 8);
    ASSERT_EQ(frames, 3);
    for (int f = 0; f < 3; ++f) {
        EXPECT_EQ(delays[f], 40);  // milliseconds
        const stbi_uc* pixel = decoded + (size_t(f) * 16 * 8 + 16 * 8 - 1) * 4;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(pixel[c], colours[f][c], 8) << "frame " << f;
    }
    stbi_image_free(decoded);
    stbi_image_free(delays);
}

// --- on the device ---------------------------------------------------------------------------

TEST_F(RenderTest, SameRenderTwiceIsBitwiseIdentical) {
    SimulationConfig config;
    config.backend = BackendKind::vulkan;
    std::vector<render::Image> runs[2];
    for (auto& run : runs) {
        OPEN_OR_SKIP(session, test_scene(), config, small_settings());
        EXPECT_EQ(session->renderer->vertex_source(), render::VertexSource::device_buffers);
        run = render_frames(*session, 3, 12);
    }
    for (int f = 0; f < 3; ++f) EXPECT_EQ(runs[0][f].rgba, runs[1][f].rgba) << "frame " << f;
}

TEST_F(RenderTest, TreeCoversAPlausibleShareOfThePicture) {
    SimulationConfig config;
    config.backend = BackendKind::vulkan;
    render::RenderSettings settings = small_settings();
    settings.shadows = false;  // compare against the same picture without trees
    OPEN_OR_SKIP(with_tree, test_scene(), config, settings);
    settings.draw_trees = false;
    OPEN_OR_SKIP(empty, test_scene(), config, settings);
    render::Image tree, backdrop;
    ASSERT_TRUE(with_tree->renderer->render(0, tree).ok());
    ASSERT_TRUE(empty->renderer->render(0, backdrop).ok());
    const double share = differing_share(tree, backdrop);
    EXPECT_GT(share, 0.02);
    EXPECT_LT(share, 0.60);
    // The framing centres the tree: its pixels reach neither the left nor the right edge.
    for (uint32_t y = 0; y < tree.height; ++y)
        for (uint32_t x : {0u, tree.width - 1}) {
            const size_t p = (size_t(y) * tree.width + x) * 4;
            EXPECT_EQ(std::memcmp(&tree.rgba[p], &backdrop.rgba[p], 3), 0) << "x " << x << " y " << y;
        }
}

TEST_F(RenderTest, FramesDifferUnderWindAndNotWithout) {
    SimulationConfig windy;
    windy.backend = BackendKind::vulkan;
    windy.wind.strength = 2.0;
    OPEN_OR_SKIP(moving, test_scene(), windy, small_settings());
    auto frames = render_frames(*moving, 3, 30);
    EXPECT_GT(differing_share(frames[0], frames[1]), 0.001);
    EXPECT_GT(differing_share(frames[1], frames[2]), 0.001);

    SimulationConfig calm = windy;
    calm.wind.profile = WindProfile::none;
    OPEN_OR_SKIP(still, test_scene(), calm, small_settings());
    auto calm_frames = render_frames(*still, 3, 30);
    EXPECT_EQ(calm_frames[0].rgba, calm_frames[1].rgba);
    EXPECT_EQ(calm_frames[1].rgba, calm_frames[2].rgba);
}

TEST_F(RenderTest, HostUploadDrawsWhatTheDeviceBuffersDraw) {
    SimulationConfig config;
    config.backend = BackendKind::vulkan;
    OPEN_OR_SKIP(device, test_scene(), config, small_settings());
    config.backend = BackendKind::cpu64;
    OPEN_OR_SKIP(host, test_scene(), config, small_settings());
    EXPECT_EQ(host->renderer->vertex_source(), render::VertexSource::host_upload);
    auto a = render_frames(*device, 2, 20);
    auto b = render_frames(*host, 2, 20);
    // float32 on the device against double on the host: a few edge pixels may differ.
    for (int f = 0; f < 2; ++f) EXPECT_LT(differing_share(a[f], b[f]), 0.01) << "frame " << f;
}

TEST_F(RenderTest, PackedVertexLayoutDrawsWhatTheSeparateLayoutDraws) {
    // Device buffers decoded in the vertex shader (Vulkan) and the host upload of decoded
    // normals (CPU), both against the separate layout: only the snorm16 quantization of the
    // normals (< 1e-4 rad) may flip a pixel's colour by a step.
    SimulationConfig config;
    config.backend = BackendKind::vulkan;
    config.wind.strength = 2.0;
    OPEN_OR_SKIP(separate, test_scene(), config, small_settings());
    config.vertex_layout = VertexLayout::packed;
    OPEN_OR_SKIP(packed, test_scene(), config, small_settings());
    EXPECT_EQ(packed->renderer->vertex_source(), render::VertexSource::device_buffers);
    config.backend = BackendKind::cpu;
    OPEN_OR_SKIP(host, test_scene(), config, small_settings());
    EXPECT_EQ(host->renderer->vertex_source(), render::VertexSource::host_upload);
    auto a = render_frames(*separate, 2, 20);
    auto b = render_frames(*packed, 2, 20);
    auto c = render_frames(*host, 2, 20);
    for (int f = 0; f < 2; ++f) {
        EXPECT_LT(differing_share(a[f], b[f]), 0.003) << "frame " << f;
        EXPECT_LT(differing_share(a[f], c[f]), 0.01) << "frame " << f;
    }
}

TEST_F(RenderTest, ValidationLayerIsSilentForAForestWithoutAndWithMsaa) {
    if (!g_messages.enabled) GTEST_SKIP() << "VK_LAYER_KHRONOS_validation is not installed";
    Scene forest = *grid_scene(small_tree(), 4, 6.0, 3);
    for (uint32_t msaa : {1u, 4u}) {
        render::RenderSettings settings = small_settings();
        settings.msaa = msaa;
        settings.leaf_scale = 2.0;
        SimulationConfig config;
        config.backend = BackendKind::vulkan;
        OPEN_OR_SKIP(session, forest, config, settings);
        render_frames(*session, 2, 3);
        config.backend = BackendKind::cpu;
        OPEN_OR_SKIP(upload, forest, config, settings);
        render_frames(*upload, 2, 3);
    }
    // TearDown fails the test on any message; say so here too for a clearer report.
    EXPECT_TRUE(g_messages.enabled);
}

// --- --draw skinned -----------------------------------------------------------------------------

/// A tree with leaves and a forest of four with yaws.
std::vector<std::pair<const char*, Scene>> skinning_scenes() {
    return {{"tree", test_scene()}, {"forest", *grid_scene(*generate_preset("paper-5"), 4, 8.0, 3)}};
}

TEST(RenderSkin, HostSkinningOfTheBindMeshEqualsPass7) {
    for (auto& [name, scene] : skinning_scenes()) {
        SimulationConfig config;
        config.backend = BackendKind::cpu;
        config.wind.strength = 2.0;
        auto simulation = Simulation::create(scene, config);
        ASSERT_TRUE(simulation.ok()) << simulation.status().message();
        Simulation& sim = *simulation.value();
        ASSERT_TRUE(sim.step(25).ok());
        std::vector<float> joints, pass7, skinned;
        ASSERT_TRUE(sim.read(Output::joint_matrices, joints).ok());
        ASSERT_TRUE(sim.read(Output::vertex_positions, pass7).ok());
        const auto skins = render::build_skins(sim);
        ASSERT_TRUE(render::skin_on_host(sim, skins, joints, skinned).ok());
        ASSERT_EQ(skinned.size(), pass7.size()) << name;
        float low = 1e30f, high = -1e30f, worst = 0.0f;
        for (size_t i = 0; i < pass7.size(); ++i) {
            if (i % 3 == 1) low = std::min(low, pass7[i]), high = std::max(high, pass7[i]);
            worst = std::max(worst, std::abs(skinned[i] - pass7[i]));
        }
        EXPECT_LE(worst, 1e-5f * (high - low)) << name << ": tree height " << high - low;
        EXPECT_FALSE(render::skin_on_host(sim, skins, std::span(joints).first(12), skinned).ok());
    }
}

TEST_F(RenderTest, SkinnedDrawsWhatTheVerticesDraw) {
    for (auto& [name, scene] : skinning_scenes()) {
        ASSERT_GT(scene.models[0].leaves.size(), 0u);
        // The simulation's own joint buffer (vulkan) and the uploaded Output::joint_matrices.
        for (BackendKind backend : {BackendKind::vulkan, BackendKind::cpu}) {
            SimulationConfig config;
            config.backend = backend;
            config.wind.strength = 2.0;
            render::RenderSettings settings = small_settings();
            OPEN_OR_SKIP(vertices, scene, config, settings);
            settings.draw = render::DrawMode::skinned;
            OPEN_OR_SKIP(skinned, scene, config, settings);
            EXPECT_EQ(skinned->renderer->draw_mode(), render::DrawMode::skinned);
            EXPECT_EQ(skinned->simulation->config().outputs, Outputs::joints);
            EXPECT_EQ(skinned->renderer->vertex_source(), vertices->renderer->vertex_source());
            auto a = render_frames(*vertices, 2, 20);
            auto b = render_frames(*skinned, 2, 20);
            EXPECT_NE(a[0].rgba, a[1].rgba) << name << ": the wind moves the tree";
            for (int f = 0; f < 2; ++f)
                EXPECT_LT(differing_share(a[f], b[f]), 0.005) << name << " " << to_string(backend) << " frame " << f;
        }
    }
}

// --- hmsm render ------------------------------------------------------------------------------

class RenderCli : public CliFixture {
protected:
    RenderCli() : CliFixture(/*small_tree=*/false) {}
    /// Runs `hmsm render ARGS`.
    CliRun run_render(const std::string& arguments, const std::string& environment = "") {
        return run("render " + arguments, environment);
    }
};

TEST_F(RenderCli, BadArgumentsExitTwoWithOneLineAndNoOutput) {
    const std::string outs = " --out " + path("frames") + " --gif " + path("a.gif") + " --strip " + path("s.png");
    for (const std::string args : {"--preset paper-5 --frames 0", "--preset paper-5 --fps -1",
                                   "--preset paper-5 --width 2", "--preset paper-5 --msaa 3",
                                   "--preset paper-5 --camera-pitch 95", "--preset nope",
                                   "--preset paper-5 --wind gale", "--preset paper-5 --look-at 1,2",
                                   "--preset paper-5 --leaf-scale big", "--preset paper-5 --draw bones",
                                   "--frames 2"}) {
        expect_bad_input("render " + args + outs, "hmsm: error: ");
    }
    std::ofstream(path("file")) << "x";
    CliRun r = run_render("--preset paper-5 --frames 1 --out " + path("file"));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    CliRun missing_parent = run_render("--preset paper-5 --frames 1 --out " + path("no/such/dir"));
    EXPECT_EQ(missing_parent.exit_code, 2) << missing_parent.err;
    EXPECT_EQ(entries(), std::vector<std::string>{"file"});
}

TEST_F(RenderCli, DeviceErrorExitsOneWithoutOutput) {
    CliRun r = run_render("--preset paper-5 --frames 1 --width 32 --height 32 --out " + path("frames") + " --gif " +
                              path("a.gif"),
                          "HMSM_VULKAN_DEVICE=no-such-device-anywhere");
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_TRUE(entries().empty());
}

TEST_F(RenderCli, DrawSkinnedWritesWhatDrawVerticesWrites) {
    render::Image images[2];
    for (int i = 0; i < 2; ++i) {
        const std::string out = path(i ? "skinned" : "vertices");
        CliRun r = run_render("--preset paper-5 --wind turbulent --width 64 --height 48 --frames 2 --no-progress --draw " +
                              std::string(i ? "skinned" : "vertices") + " --out " + out);
        if (r.exit_code == 1 && r.err.find("vulkan") != std::string::npos)
            GTEST_SKIP() << r.err;
        ASSERT_EQ(r.exit_code, 0) << r.err;
        EXPECT_NE(r.err.find(i ? "skinned draw" : "vertices draw"), std::string::npos) << r.err;
        int w = 0, h = 0, n = 0;
        stbi_uc* pixels = stbi_load((out + "/frame_0001.png").c_str(), &w, &h, &n, 4);
        ASSERT_NE(pixels, nullptr);
        images[i] = {uint32_t(w), uint32_t(h), std::vector<uint8_t>(pixels, pixels + size_t(w) * h * 4)};
        stbi_image_free(pixels);
    }
    EXPECT_LT(differing_share(images[0], images[1]), 0.005);
}

TEST_F(RenderCli, WritesFramesGifAndStripAndReplacesAnEarlierRender) {
    const std::string common = "--preset paper-5 --width 48 --height 36 --fps 10 --no-progress --out " + path("frames");
    fs::create_directories(dir_ / "frames");
    std::ofstream(dir_ / "frames" / "frame_0007.png") << "stale";
    std::ofstream(dir_ / "frames" / "notes.txt") << "kept";
    CliRun r = run_render(common + " --frames 3 --gif " + path("anim.gif") + " --strip " + path("strip.png"));
    if (r.exit_code == 1 && r.err.find("vulkan") != std::string::npos)
        GTEST_SKIP() << r.err;
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::vector<std::string> frames;
    for (const auto& e : fs::directory_iterator(dir_ / "frames")) frames.push_back(e.path().filename().string());
    std::sort(frames.begin(), frames.end());
    EXPECT_EQ(frames, (std::vector<std::string>{"frame_0000.png", "frame_0001.png", "frame_0002.png", "notes.txt"}));
    EXPECT_EQ(entries(), (std::vector<std::string>{"anim.gif", "frames", "strip.png"}));

    int w = 0, h = 0, channels = 0;
    stbi_uc* strip = stbi_load(path("strip.png").c_str(), &w, &h, &channels, 4);
    ASSERT_NE(strip, nullptr);
    EXPECT_EQ(w, 3 * 48 + 2 * 2);  // --strip-frames 4 capped at 3 frames, 2-pixel gaps
    EXPECT_EQ(h, 36);
    stbi_image_free(strip);
    std::ifstream gif_file(path("anim.gif"), std::ios::binary);
    std::vector<uint8_t> gif((std::istreambuf_iterator<char>(gif_file)), {});
    int* delays = nullptr;
    int frames_in_gif = 0;
    stbi_uc* decoded = stbi_load_gif_from_memory(gif.data(), int(gif.size()), &delays, &w, &h,
                                                 &frames_in_gif, &channels, 4);
    ASSERT_NE(decoded, nullptr);
    EXPECT_EQ(frames_in_gif, 3);
    EXPECT_EQ(delays[0], 100);
    stbi_image_free(decoded);
    stbi_image_free(delays);
}

}  // namespace
}  // namespace hmsm::test

int main(int argc, char** argv) {
    ::testing::InitGoogleTest(&argc, argv);
    using hmsm::test::g_messages;
    if (hmsm::detail::vulkan_validation_layer_available()) {
        hmsm::detail::vulkan_set_validation(true, [](const std::string& message) {
            std::lock_guard lock(g_messages.mutex);
            g_messages.list.push_back(message);
        });
        g_messages.enabled = true;
    } else {
        std::fprintf(stderr, "note: VK_LAYER_KHRONOS_validation is not installed; the render "
                             "tests run without validation\n");
    }
    return RUN_ALL_TESTS();
}
