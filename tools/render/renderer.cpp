#include "render/renderer_state.h"

#include <cmath>
#include <string>

namespace hmsm::render {

using namespace internal;

const char* to_string(VertexSource source) {
    return source == VertexSource::device_buffers ? "device buffers (no readback)"
                                                  : "host upload (readback each frame)";
}

const char* to_string(DrawMode mode) { return mode == DrawMode::skinned ? "skinned" : "vertices"; }

std::optional<DrawMode> parse_draw_mode(std::string_view name) {
    if (name == "vertices") return DrawMode::vertices;
    if (name == "skinned") return DrawMode::skinned;
    return std::nullopt;
}

Status validate(const RenderSettings& s) {
    if (s.width < 16 || s.height < 16 || s.width > 8192 || s.height > 8192)
        return {ErrorCode::invalid_argument, "--width and --height must be within 16..8192 pixels"};
    if (s.msaa != 1 && s.msaa != 2 && s.msaa != 4 && s.msaa != 8)
        return {ErrorCode::invalid_argument, "--msaa " + std::to_string(s.msaa) + ": expected 1, 2, 4 or 8"};
    const CameraSettings& c = s.camera;
    if (c.distance && !(std::isfinite(*c.distance) && *c.distance > 0.0))
        return {ErrorCode::invalid_argument, "--camera-distance must be a finite number > 0"};
    if (!std::isfinite(c.yaw_degrees))
        return {ErrorCode::invalid_argument, "--camera-yaw must be finite"};
    if (c.pitch_degrees && !(std::isfinite(*c.pitch_degrees) && std::abs(*c.pitch_degrees) <= 89.0))
        return {ErrorCode::invalid_argument, "--camera-pitch must be within -89..89 degrees"};
    if (!(std::isfinite(c.fov_degrees) && c.fov_degrees >= 5.0 && c.fov_degrees <= 120.0))
        return {ErrorCode::invalid_argument, "--fov must be within 5..120 degrees"};
    if (!(std::isfinite(s.leaf_scale) && (s.leaf_scale == 0.0 || (s.leaf_scale >= 0.1 && s.leaf_scale <= 20.0))))
        return {ErrorCode::invalid_argument, "--leaf-scale must be auto or within 0.1..20"};
    return {};
}

// --- Renderer ------------------------------------------------------------------------------

Renderer::Renderer(std::unique_ptr<State> state) : state_(std::move(state)) {}
Renderer::~Renderer() = default;

VertexSource Renderer::vertex_source() const { return state_->source; }
DrawMode Renderer::draw_mode() const { return state_->settings.draw; }
const Camera& Renderer::camera() const { return state_->camera; }
uint32_t Renderer::samples() const { return uint32_t(state_->samples); }
bool Renderer::shadows() const { return state_->shadows; }
double Renderer::leaf_scale() const { return state_->leaf_scale; }

Result<std::unique_ptr<Renderer>> Renderer::create(std::shared_ptr<Device> device,
                                                   Simulation& simulation,
                                                   const RenderSettings& settings) {
    HMSM_TRY(validate(settings));
    if (!device) return Status{ErrorCode::internal, "render: no device"};
    // Graphics needs a queue family with graphics; hmsm's device has one queue, of the family
    // chosen for compute. On every driver we know (lavapipe, NVIDIA, AMD, Intel) that is the
    // universal family 0.
    uint32_t family_count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(device->physical_device(), &family_count, nullptr);
    std::vector<VkQueueFamilyProperties> families(family_count);
    vkGetPhysicalDeviceQueueFamilyProperties(device->physical_device(), &family_count, families.data());
    if (device->queue_family() >= family_count ||
        !(families[device->queue_family()].queueFlags & VK_QUEUE_GRAPHICS_BIT))
        return Status{ErrorCode::unsupported, "render: the queue hmsm uses on " + device->name() +
                                                  " cannot draw (no graphics in its queue family)"};
    auto state = std::make_unique<State>();
    state->device = std::move(device);
    state->simulation = &simulation;
    state->settings = settings;
    HMSM_TRY(state->choose_formats());
    HMSM_TRY(state->create_targets());
    HMSM_TRY(state->create_render_pass());
    HMSM_TRY(state->create_descriptors());
    HMSM_TRY(state->create_pipelines());
    HMSM_TRY(state->create_geometry());
    HMSM_TRY(state->create_commands());
    HMSM_TRY(state->frame_scene());
    HMSM_TRY(state->device->take_validation_messages());
    return std::unique_ptr<Renderer>(new Renderer(std::move(state)));
}

Result<std::unique_ptr<Session>> open_session(const Scene& scene, SimulationConfig config,
                                              const RenderSettings& settings) {
    HMSM_TRY(validate(settings));
    if (settings.draw == DrawMode::skinned) config.outputs = Outputs::joints;
    auto session = std::make_unique<Session>();
    auto device = Device::create();
    if (!device) return device.status();
    session->device = std::move(device).value();
    if (config.backend == BackendKind::automatic || config.backend == BackendKind::vulkan) {
        hmsm::vulkan::ExternalContext context;
        context.instance = session->device->instance();
        context.physical_device = session->device->physical_device();
        context.device = session->device->handle();
        context.queue = session->device->queue();
        context.queue_family_index = session->device->queue_family();
        auto simulation = hmsm::vulkan::create_simulation(scene, config, context);
        if (!simulation) return simulation.status();
        session->simulation = std::move(simulation).value();
    } else {
        auto simulation = Simulation::create(scene, config);
        if (!simulation) return simulation.status();
        session->simulation = std::move(simulation).value();
    }
    auto renderer = Renderer::create(session->device, *session->simulation, settings);
    if (!renderer) return renderer.status();
    session->renderer = std::move(renderer).value();
    return session;
}

}  // namespace hmsm::render
