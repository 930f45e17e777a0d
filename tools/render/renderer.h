// Offscreen rendering of a simulation with a Vulkan graphics pipeline: no window, no swapchain
// (runs on lavapipe). Each frame advances the simulation and draws sky, ground, planar shadows,
// the branch mesh and the leaf cards into an MSAA colour target, resolves it and reads it back.
//
// Where the vertices come from (docs/render.md):
// - a Vulkan simulation on the renderer's own device (the default): the steps are recorded into
//   the frame's command buffer (hmsm::vulkan::record_steps) and the simulation's output buffers
//   are bound directly as vertex buffers; nothing crosses to the host but the picture;
// - any other backend (cpu, cpu64, cuda): Simulation::read() to the host and an upload into
//   host-visible vertex buffers every frame.
//
// What is drawn (RenderSettings::draw): `vertices` draws pass 7's mesh vertices as above;
// `skinned` draws each model's bind-pose mesh skinned in the vertex shader from the joint
// matrices (tools/render/skinned.cpp), and the simulation only produces Outputs::joints.
#pragma once

#include "render/camera.h"
#include "render/image_io.h"

#include <hmsm/simulation.h>
#include <hmsm/status.h>

#include <memory>
#include <optional>
#include <string_view>

namespace hmsm::detail::vk {
class Device;
}

namespace hmsm::render {

/// `vertices`: pass 7's vertex buffers; `skinned`: the bind mesh skinned from the joint buffer.
enum class DrawMode { vertices, skinned };
const char* to_string(DrawMode mode);
/// "vertices" or "skinned".
std::optional<DrawMode> parse_draw_mode(std::string_view name);

struct RenderSettings {
    uint32_t width = 640, height = 480;
    uint32_t msaa = 4;     ///< samples per pixel: 1, 2, 4 or 8, lowered to what the device has
    CameraSettings camera;
    bool shadows = true;   ///< planar shadows on the ground (needs a stencil format)
    bool draw_trees = true;  ///< false: sky and ground only (tests measure the trees' coverage)
    /// Leaf cards drawn this many times their size, about their centres (1 = true size): a
    /// real leaf is smaller than a pixel when a whole tree fills a small picture. 0 = auto:
    /// a leaf's side becomes at least 1.1% of the view's height (scale 1..6).
    double leaf_scale = 0.0;
    DrawMode draw = DrawMode::vertices;
};

enum class VertexSource { device_buffers, host_upload };
const char* to_string(VertexSource source);

/// Checks sizes and camera settings (invalid_argument names the setting).
Status validate(const RenderSettings& settings);

class Renderer {
public:
    /// `device` is the Vulkan device to draw on; when `simulation` runs on the Vulkan backend it
    /// must be the same device (see open_session). The camera is framed on the simulation's
    /// current pose.
    static Result<std::unique_ptr<Renderer>> create(std::shared_ptr<detail::vk::Device> device,
                                                    Simulation& simulation,
                                                    const RenderSettings& settings);
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    /// Advances the simulation by `steps` (may be 0) and draws the resulting pose into `image`.
    Status render(uint32_t steps, Image& image);

    VertexSource vertex_source() const;
    DrawMode draw_mode() const;
    const Camera& camera() const;
    uint32_t samples() const;
    bool shadows() const;
    double leaf_scale() const;  ///< the scale applied (1 when the device cannot apply another)

    struct State;

private:
    explicit Renderer(std::unique_ptr<State> state);
    std::unique_ptr<State> state_;
};

/// A device, a simulation and a renderer, torn down in that order's reverse.
struct Session {
    std::shared_ptr<detail::vk::Device> device;
    std::unique_ptr<Simulation> simulation;
    std::unique_ptr<Renderer> renderer;
};

/// Creates hmsm's Vulkan device (HMSM_VULKAN_DEVICE picks one, as for the backend), the
/// simulation and the renderer. `config.backend` automatic or vulkan simulates on that device
/// and draws from its buffers; cpu, cpu64 and cuda simulate there and upload each frame.
/// `settings.draw` skinned sets `config.outputs` to Outputs::joints (nothing else is drawn from).
Result<std::unique_ptr<Session>> open_session(const Scene& scene, SimulationConfig config,
                                              const RenderSettings& settings);

}  // namespace hmsm::render
