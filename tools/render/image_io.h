// Pictures out of the renderer: PNG through libpng, animated GIF through giflib (its median-cut
// quantizer builds the palette), and a strip of frames side by side.
#pragma once

#include <hmsm/status.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

namespace hmsm::render {

/// 8-bit sRGB, RGBA, rows top to bottom.
struct Image {
    uint32_t width = 0, height = 0;
    std::vector<uint8_t> rgba;
};

/// An RGB PNG (alpha dropped) in memory.
Result<std::vector<uint8_t>> encode_png(const Image& image);

/// The images left to right, `gap` pixels of `gap_rgb` between them; all of one height.
Image side_by_side(const std::vector<Image>& images, uint32_t gap, const uint8_t gap_rgb[3]);

/// An animated, looping GIF written through `sink` frame by frame. The palette (256 colours)
/// is built from the first frame by giflib's GifQuantizeBuffer and kept for every frame, so
/// colours do not flicker; later frames map each pixel to the nearest palette colour.
class GifWriter {
public:
    using Sink = std::function<Status(const uint8_t* bytes, size_t count)>;
    static Result<std::unique_ptr<GifWriter>> create(uint32_t width, uint32_t height, Sink sink);
    ~GifWriter();
    GifWriter(const GifWriter&) = delete;
    GifWriter& operator=(const GifWriter&) = delete;

    /// `delay_cs`: how long the frame shows, in hundredths of a second.
    Status add_frame(const Image& image, uint32_t delay_cs);
    /// Writes the trailer; no frame may follow.
    Status finish();

    struct State;  // giflib's callback reaches it through GifFileType::UserData

private:
    explicit GifWriter(std::unique_ptr<State> state);
    std::unique_ptr<State> state_;
};

}  // namespace hmsm::render
