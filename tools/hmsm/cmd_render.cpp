// hmsm render: simulates at a fixed time step and draws the animated tree (or forest) offscreen
// with Vulkan, writing DIR/frame_0000.png... and optionally an animated GIF and a strip of frames.
// Frames are rendered into a temporary folder beside DIR and moved in only when every frame is
// done, so a failed render leaves no partial output.
#include "cli_common.h"

#include "render/renderer.h"

#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <unistd.h>

namespace hmsm::cli {
namespace {

namespace fs = std::filesystem;

struct RenderFlags {
    SourceFlags source;
    ModelFlags model;
    Parameters parameters;
    WindFlags wind;
    std::string backend = "auto";
    int64_t frames = 60;
    double fps = 30.0;
    double warmup = 0.0;
    uint32_t width = 640, height = 480, msaa = 4;
    std::string out, gif, strip;
    uint32_t strip_frames = 4;
    std::string leaf_scale = "auto";
    std::string draw = "vertices";
    std::optional<double> camera_distance, camera_pitch;
    double camera_yaw = 0.0, fov = 35.0;
    std::string look_at;
    bool no_shadows = false, no_progress = false;
} flags;

/// A folder that is removed with its contents unless released.
class TemporaryFolder {
public:
    explicit TemporaryFolder(fs::path path) : path_(std::move(path)) {}
    ~TemporaryFolder() {
        if (path_.empty()) return;
        std::error_code ec;
        fs::remove_all(path_, ec);
    }
    const fs::path& path() const { return path_; }
    void release() { path_.clear(); }

private:
    fs::path path_;
};

bool is_frame_name(const std::string& name) {
    // frame_NNNN.png (four or more digits)
    if (name.size() < 14 || name.rfind("frame_", 0) != 0 || name.substr(name.size() - 4) != ".png")
        return false;
    const std::string digits = name.substr(6, name.size() - 10);
    return digits.size() >= 4 &&
           std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; });
}

std::string frame_name(int64_t index) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04" PRId64 ".png", index);
    return name;
}

/// Moves the rendered frames into `out`: a rename when `out` does not exist; otherwise frame by
/// frame, and frame_*.png files of an earlier render that this one did not write are removed,
/// so the folder holds exactly this animation.
Status commit_frames(const fs::path& temporary, const fs::path& out, int64_t frames) {
    std::error_code ec;
    if (!fs::exists(out, ec)) {
        fs::rename(temporary, out, ec);
        if (ec) return {ErrorCode::io, "--out " + out.string() + ": cannot create (" + ec.message() + ")"};
        return {};
    }
    std::set<std::string> written;
    for (int64_t k = 0; k < frames; ++k) {
        const std::string name = frame_name(k);
        fs::rename(temporary / name, out / name, ec);
        if (ec) return {ErrorCode::io, "--out " + out.string() + ": cannot write " + name + " (" + ec.message() + ")"};
        written.insert(name);
    }
    for (const fs::directory_entry& entry : fs::directory_iterator(out, ec)) {
        const std::string name = entry.path().filename().string();
        if (is_frame_name(name) && !written.count(name)) fs::remove(entry.path(), ec);
    }
    return {};
}

Status write_file(const fs::path& path, const std::vector<uint8_t>& bytes) {
    std::ofstream file(path, std::ios::binary);
    if (file) file.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    if (!file) return {ErrorCode::io, path.string() + ": write error"};
    return {};
}

class Progress {
public:
    Progress(int64_t total, bool enabled) : total_(total), enabled_(enabled && isatty(2)) {}
    void update(int64_t done, double seconds) {
        if (!enabled_) return;
        constexpr int kWidth = 30;
        const int filled = int(kWidth * done / std::max<int64_t>(total_, 1));
        const double rate = seconds > 0.0 ? double(done) / seconds : 0.0;
        const double eta = rate > 0.0 ? double(total_ - done) / rate : 0.0;
        std::fprintf(stderr, "\rhmsm: [%.*s%*s] %" PRId64 "/%" PRId64 " frames  %.1f fps  eta %.0f s ",
                     filled, "##############################", kWidth - filled, "", done, total_,
                     rate, eta);
        if (done == total_) std::fputc('\n', stderr);
        std::fflush(stderr);
    }

private:
    int64_t total_;
    bool enabled_;
};

}  // namespace

void register_render_flags(CLI::App& app) {
    add_source_flags(app, flags.source, true);
    add_model_flags(app, flags.model);
    add_parameter_flags(app, flags.parameters);
    add_wind_flags(app, flags.wind);
    app.add_option("--backend", flags.backend,
                   "auto (default) or vulkan: simulate on the rendering device and draw from its buffers; " +
                       choices(kBackendKindNames, Spelling::as_is, std::nullopt,
                               {BackendKind::automatic, BackendKind::vulkan}) +
                       ": read back and upload each frame");
    add_integer_option(app, "--frames", flags.frames, "frames to render (default 60)");
    app.add_option("--fps", flags.fps, "frames per second of simulated time (default 30)");
    app.add_option("--warmup", flags.warmup, "seconds simulated before the first frame (default 0)");
    add_integer_option(app, "--width", flags.width, "picture width in pixels (default 640)");
    add_integer_option(app, "--height", flags.height, "picture height in pixels (default 480)");
    add_integer_option(app, "--msaa", flags.msaa, "samples per pixel: 1, 2, 4 (default) or 8");
    app.add_option("--out", flags.out, "folder for frame_0000.png, frame_0001.png, ...")->required();
    app.add_option("--gif", flags.gif, "also write an animated GIF of all frames");
    app.add_option("--strip", flags.strip, "also write one PNG with frames side by side");
    add_integer_option(app, "--strip-frames", flags.strip_frames, "frames in the strip, evenly spaced (default 4)");
    app.add_option("--camera-distance", flags.camera_distance,
                   "metres from the look-at point (default: frame the trees)");
    app.add_option("--camera-yaw", flags.camera_yaw,
                   "degrees about +y; 0 (default) looks along -z with x to the right");
    app.add_option("--camera-pitch", flags.camera_pitch,
                   "degrees above the horizon (default 8, forests 15)");
    app.add_option("--look-at", flags.look_at, "point X,Y,Z the camera aims at (default: centre of the trees)");
    app.add_option("--fov", flags.fov, "vertical field of view in degrees (default 35)");
    app.add_option("--leaf-scale", flags.leaf_scale,
                   "draw leaf cards this many times their size, or auto (default): large enough to "
                   "see at the picture's scale; 1 = true size");
    app.add_option("--draw", flags.draw,
                   "vertices (default): draw pass 7's mesh vertices; skinned: skin each model's bind "
                   "mesh from the joint matrices in the vertex shader (the simulation then produces "
                   "only the joints)");
    app.add_flag("--no-shadows", flags.no_shadows, "no shadows on the ground");
    app.add_flag("--no-progress", flags.no_progress, "no progress bar on stderr");
}

int run_render(CLI::App& app) {
    // --- everything the user can get wrong is checked before any file is touched ---
    SimulationConfig config;
    config.profile_passes = false;
    auto backend = parse_backend(flags.backend, "--backend");
    if (!backend) return fail(backend.status());
    config.backend = *backend;
    if (flags.frames < 1 || flags.frames > 100000)
        return fail_input("--frames " + std::to_string(flags.frames) + ": must be within 1..100000");
    if (!(std::isfinite(flags.fps) && flags.fps > 0.0 && flags.fps <= 1000.0))
        return fail_input("--fps must be a number within (0, 1000]");
    if (!(std::isfinite(flags.warmup) && flags.warmup >= 0.0 && flags.warmup <= 3600.0))
        return fail_input("--warmup must be within 0..3600 seconds");
    if (flags.strip_frames < 1 || flags.strip_frames > 64)
        return fail_input("--strip-frames must be within 1..64");
    auto options = model_options(flags.model);
    if (!options) return fail(options.status());
    config.model = *options;
    config.parameters = flags.parameters;
    Status parameters_ok = validate(config.parameters);
    if (!parameters_ok) return fail(parameters_ok);
    auto wind = wind_options(flags.wind);
    if (!wind) return fail(wind.status());
    config.wind = *wind;

    render::RenderSettings settings;
    settings.width = flags.width;
    settings.height = flags.height;
    settings.msaa = flags.msaa;
    settings.shadows = !flags.no_shadows;
    auto draw = render::parse_draw_mode(flags.draw);
    if (!draw) return fail_input("--draw '" + detail::quote_input(flags.draw) + "': expected vertices or skinned");
    settings.draw = *draw;
    if (flags.leaf_scale == "auto") {
        settings.leaf_scale = 0.0;
    } else {
        char* end = nullptr;
        settings.leaf_scale = std::strtod(flags.leaf_scale.c_str(), &end);
        if (flags.leaf_scale.empty() || *end != '\0' || settings.leaf_scale == 0.0)
            return fail_input("--leaf-scale '" + detail::quote_input(flags.leaf_scale) + "': expected auto or a number within 0.1..20");
    }
    settings.camera.distance = flags.camera_distance;
    settings.camera.yaw_degrees = flags.camera_yaw;
    settings.camera.pitch_degrees = flags.camera_pitch;
    settings.camera.fov_degrees = flags.fov;
    if (!flags.look_at.empty()) {
        auto look_at = parse_vec3(flags.look_at, "--look-at");
        if (!look_at) return fail(look_at.status());
        settings.camera.look_at = *look_at;
    }
    Status settings_ok = render::validate(settings);
    if (!settings_ok) return fail(settings_ok);
    if (!flags.gif.empty() && (flags.width > 65535 || flags.height > 65535))
        return fail_input("--gif: frames larger than 65535 pixels");

    fs::path out = fs::path(flags.out).lexically_normal();
    if (!out.has_filename()) out = out.parent_path();
    std::error_code ec;
    if (out.empty()) return fail_input("--out: give a folder");
    if (fs::exists(out, ec) && !fs::is_directory(out, ec))
        return fail(Status{ErrorCode::io, "--out " + out.string() + ": exists and is not a folder"});
    const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
    if (!fs::is_directory(parent, ec))
        return fail(Status{ErrorCode::io, "--out " + out.string() + ": folder " + parent.string() +
                                              " does not exist"});

    auto schedule = read_schedule_option(flags.wind);
    if (!schedule) return fail(schedule.status());
    auto scene = load_scene(flags.source, app, &config.model, scheduled_models(*schedule));
    if (!scene) return fail(scene.status());
    if (Status valid = check_schedule_option(flags.wind, *schedule, *scene, config.wind); !valid) return fail(valid);
    if (*schedule)
        for (const ScheduleEvent& e : (*schedule)->events)
            if (!e.remove.empty() || !e.add.empty())
                return fail_input("--wind-schedule " + flags.wind.schedule + ": step " + std::to_string(e.step) +
                                  ": render draws a fixed instance list; a schedule may change the wind, forces "
                                  "and instance settings, not add or remove instances");

    StagedOutputs outputs;
    outputs.add_inputs({flags.source.tree, flags.source.forest, flags.wind.schedule});
    std::optional<size_t> gif_file, strip_file;
    for (auto [path, flag, slot] : {std::tuple{&flags.gif, "--gif", &gif_file},
                                    std::tuple{&flags.strip, "--strip", &strip_file}}) {
        if (path->empty()) continue;
        auto staged = outputs.stage(*path, flag);
        if (!staged) return fail(staged.status());
        *slot = *staged;
    }
    const fs::path temporary_path =
        parent / ("." + out.filename().string() + ".hmsm-render-" + std::to_string(getpid()));
    if (!fs::create_directory(temporary_path, ec) || ec)
        return fail(Status{ErrorCode::io, "--out " + out.string() + ": cannot create a folder in " +
                                              parent.string()});
    TemporaryFolder temporary(temporary_path);

    // --- the device, the simulation and the renderer ---
    auto opened = render::open_session(*scene, config, settings);
    if (!opened) return fail(opened.status());
    render::Session& session = **opened;
    Simulation& sim = *session.simulation;
    render::Renderer& renderer = *session.renderer;

    std::unique_ptr<render::GifWriter> gif;
    if (gif_file) {
        auto created = render::GifWriter::create(
            settings.width, settings.height, [&](const uint8_t* bytes, size_t count) {
                return outputs.write(*gif_file, bytes, count);
            });
        if (!created) return fail(created.status());
        gif = std::move(created).value();
    }
    std::vector<int64_t> strip_indices;
    const int64_t strip_count = std::min<int64_t>(flags.strip_frames, flags.frames);
    for (int64_t j = 0; strip_file && j < strip_count; ++j)
        strip_indices.push_back(strip_count == 1 ? 0 : (j * (flags.frames - 1) + (strip_count - 1) / 2) / (strip_count - 1));
    std::vector<render::Image> strip_images;

    // Frame k shows simulated time warmup + k / fps, rounded to whole steps of dt.
    const double dt = config.parameters.dt;
    auto step_of = [&](int64_t k) {
        return int64_t(std::llround((flags.warmup + double(k) / flags.fps) / dt));
    };
    const auto start = std::chrono::steady_clock::now();
    Progress progress(flags.frames, !flags.no_progress);
    render::Image image;
    int64_t steps_done = 0;
    for (int64_t k = 0; k < flags.frames; ++k) {
        int64_t steps = step_of(k) - steps_done;
        // Long warm-ups in chunks (a frame's steps fit one call); schedule events apply before
        // their step, so the steps up to the frame's last event run here.
        for (;;) {
            uint64_t chunk = uint64_t(std::min<int64_t>(steps, 100000));
            if (*schedule && steps > 0) {
                Status applied = apply_schedule_events(**schedule, uint64_t(steps_done) + 1, sim);
                if (!applied) return fail(applied);
                if (auto next = next_schedule_step(**schedule, uint64_t(steps_done) + 1))
                    if (*next <= uint64_t(steps_done + steps)) chunk = *next - uint64_t(steps_done) - 1;
            }
            if (chunk == uint64_t(steps) && steps <= 100000) break;  // the renderer runs the rest
            Status stepped = sim.step(uint32_t(chunk));
            if (!stepped) return fail(stepped);
            steps -= int64_t(chunk);
            steps_done += int64_t(chunk);
        }
        Status drawn = renderer.render(uint32_t(steps), image);
        if (!drawn) return fail(drawn);
        steps_done += steps;
        auto png = render::encode_png(image);
        if (!png) return fail(png.status());
        Status written = write_file(temporary.path() / frame_name(k), *png);
        if (!written) return fail(written);
        if (gif) {
            const uint32_t delay = uint32_t(std::llround(100.0 * double(k + 1) / flags.fps) -
                                            std::llround(100.0 * double(k) / flags.fps));
            Status added = gif->add_frame(image, std::max<uint32_t>(delay, 1));
            if (!added) return fail(added);
        }
        if (std::find(strip_indices.begin(), strip_indices.end(), k) != strip_indices.end())
            strip_images.push_back(image);
        progress.update(k + 1, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    if (gif) {
        Status finished = gif->finish();
        if (!finished) return fail(finished);
    }
    if (strip_file) {
        const uint8_t white[3] = {255, 255, 255};
        auto png = render::encode_png(render::side_by_side(strip_images, 2, white));
        if (!png) return fail(png.status());
        Status written = outputs.write(*strip_file, png->data(), png->size());
        if (!written) return fail(written);
    }
    Status committed = outputs.commit();
    if (!committed) return fail(committed);
    Status moved = commit_frames(temporary.path(), out, flags.frames);
    if (!moved) return fail(moved);
    if (!fs::exists(temporary.path(), ec)) temporary.release();

    std::fprintf(stderr,
                 "hmsm: %" PRId64 " frames %ux%u (%ux MSAA) of %" PRIu64 " instance(s), %s on %s, "
                 "leaf scale %.2g, %s draw from %s, in %.2f s -> %s\n",
                 flags.frames, settings.width, settings.height, renderer.samples(), sim.instance_count(),
                 to_string(sim.backend_kind()), sim.device_name().c_str(), renderer.leaf_scale(),
                 render::to_string(renderer.draw_mode()), render::to_string(renderer.vertex_source()), wall, out.string().c_str());
    return kExitOk;
}

}  // namespace hmsm::cli
