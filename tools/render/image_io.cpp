#include "render/image_io.h"

#include <gif_lib.h>
#include <png.h>

#include <algorithm>
#include <array>
#include <csetjmp>
#include <cstring>
#include <limits>
#include <new>
#include <string>

namespace hmsm::render {
namespace {

struct PngSink {
    std::vector<uint8_t>* bytes;
    bool out_of_memory = false;
};

void png_write_bytes(png_structp png, png_bytep data, png_size_t length) {
    auto* sink = static_cast<PngSink*>(png_get_io_ptr(png));
    try {
        sink->bytes->insert(sink->bytes->end(), data, data + length);
    } catch (const std::bad_alloc&) {
        sink->out_of_memory = true;
        png_error(png, "out of memory");
    }
}

void png_flush_nothing(png_structp) {}

// libpng reports errors by longjmp; this frame holds no C++ object with a destructor.
bool write_png_rows(png_structp png, png_infop info, const Image& image, png_bytep* rows) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_set_IHDR(png, info, image.width, image.height, 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_write_info(png, info);
    png_set_filler(png, 0, PNG_FILLER_AFTER);  // drop alpha: RGBA rows in, RGB out
    png_write_image(png, rows);
    png_write_end(png, info);
    return true;
}

}  // namespace

Result<std::vector<uint8_t>> encode_png(const Image& image) {
    if (image.width == 0 || image.height == 0 ||
        image.rgba.size() != size_t(image.width) * image.height * 4)
        return Status{ErrorCode::internal, "png: image size does not match its pixels"};
    std::vector<uint8_t> bytes;
    std::vector<png_bytep> rows(image.height);
    for (uint32_t y = 0; y < image.height; ++y)
        rows[y] = const_cast<png_bytep>(image.rgba.data() + size_t(y) * image.width * 4);
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    if (!png) return Status{ErrorCode::out_of_memory, "png: cannot create a writer"};
    png_infop info = png_create_info_struct(png);
    if (!info) {
        png_destroy_write_struct(&png, nullptr);
        return Status{ErrorCode::out_of_memory, "png: cannot create a writer"};
    }
    PngSink sink{&bytes};
    png_set_write_fn(png, &sink, &png_write_bytes, &png_flush_nothing);
    const bool ok = write_png_rows(png, info, image, rows.data());
    png_destroy_write_struct(&png, &info);
    if (sink.out_of_memory) return Status{ErrorCode::out_of_memory, "png: out of memory"};
    if (!ok) return Status{ErrorCode::internal, "png: libpng failed to encode the image"};
    return bytes;
}

Image side_by_side(const std::vector<Image>& images, uint32_t gap, const uint8_t gap_rgb[3]) {
    Image strip;
    if (images.empty()) return strip;
    strip.height = images.front().height;
    for (const Image& image : images) strip.width += image.width;
    strip.width += gap * uint32_t(images.size() - 1);
    strip.rgba.assign(size_t(strip.width) * strip.height * 4, 255);
    for (size_t p = 0; p < size_t(strip.width) * strip.height; ++p)
        std::memcpy(&strip.rgba[4 * p], gap_rgb, 3);
    uint32_t x0 = 0;
    for (const Image& image : images) {
        for (uint32_t y = 0; y < std::min(image.height, strip.height); ++y)
            std::memcpy(&strip.rgba[(size_t(y) * strip.width + x0) * 4],
                        &image.rgba[size_t(y) * image.width * 4], size_t(image.width) * 4);
        x0 += image.width + gap;
    }
    return strip;
}

// --- GIF -----------------------------------------------------------------------------------

struct GifWriter::State {
    uint32_t width = 0, height = 0;
    Sink sink;
    Status sink_status;
    GifFileType* gif = nullptr;
    bool have_palette = false;
    std::array<GifColorType, 256> palette{};
    int palette_size = 256;
    std::vector<int16_t> lookup;  // 15-bit colour (5 bits per channel) -> palette index, -1 unset
    std::vector<GifByteType> indices;
};

namespace {

int gif_output(GifFileType* gif, const GifByteType* data, int length) {
    auto* state = static_cast<GifWriter::State*>(gif->UserData);
    if (!state->sink_status.ok()) return 0;
    state->sink_status = state->sink(data, size_t(length));
    return state->sink_status.ok() ? length : 0;
}

Status gif_failure(const GifWriter::State& state, int code, const char* what) {
    if (!state.sink_status.ok()) return state.sink_status;
    const char* text = GifErrorString(code);
    return {ErrorCode::internal, std::string("gif: ") + what + ": " + (text ? text : "giflib error")};
}

}  // namespace

GifWriter::GifWriter(std::unique_ptr<State> state) : state_(std::move(state)) {}

GifWriter::~GifWriter() {
    if (state_ && state_->gif) {
        int error = 0;
        EGifCloseFile(state_->gif, &error);
    }
}

Result<std::unique_ptr<GifWriter>> GifWriter::create(uint32_t width, uint32_t height, Sink sink) {
    if (width == 0 || height == 0 || width > 65535 || height > 65535)
        return Status{ErrorCode::invalid_argument, "gif: frames must be 1..65535 pixels wide and high"};
    auto state = std::make_unique<State>();
    state->width = width;
    state->height = height;
    state->sink = std::move(sink);
    int error = 0;
    state->gif = EGifOpen(state.get(), &gif_output, &error);
    if (!state->gif) return gif_failure(*state, error, "cannot start the file");
    EGifSetGifVersion(state->gif, true);  // GIF89a: delays and looping
    return std::unique_ptr<GifWriter>(new GifWriter(std::move(state)));
}

Status GifWriter::add_frame(const Image& image, uint32_t delay_cs) {
    State& s = *state_;
    if (!s.gif) return {ErrorCode::internal, "gif: add_frame after finish"};
    if (image.width != s.width || image.height != s.height)
        return {ErrorCode::internal, "gif: every frame must have the size of the first"};
    const size_t pixels = size_t(s.width) * s.height;
    if (!s.have_palette) {
        // giflib's median cut over the first frame; the palette is global for the animation.
        std::vector<GifByteType> r(pixels), g(pixels), b(pixels);
        for (size_t p = 0; p < pixels; ++p) {
            r[p] = image.rgba[4 * p];
            g[p] = image.rgba[4 * p + 1];
            b[p] = image.rgba[4 * p + 2];
        }
        std::vector<GifByteType> scratch(pixels);
        s.palette_size = 256;
        if (GifQuantizeBuffer(s.width, s.height, &s.palette_size, r.data(), g.data(), b.data(),
                              scratch.data(), s.palette.data()) == GIF_ERROR)
            return {ErrorCode::internal, "gif: GifQuantizeBuffer failed"};
        // A colour map needs a power-of-two size; unused entries stay black.
        ColorMapObject* map = GifMakeMapObject(256, s.palette.data());
        if (!map) return {ErrorCode::out_of_memory, "gif: out of memory"};
        const int screen = EGifPutScreenDesc(s.gif, int(s.width), int(s.height), 8, 0, map);
        GifFreeMapObject(map);
        if (screen == GIF_ERROR) return gif_failure(s, s.gif->Error, "screen descriptor");
        // NETSCAPE2.0: loop forever.
        const unsigned char loop[3] = {1, 0, 0};
        if (EGifPutExtensionLeader(s.gif, APPLICATION_EXT_FUNC_CODE) == GIF_ERROR ||
            EGifPutExtensionBlock(s.gif, 11, "NETSCAPE2.0") == GIF_ERROR ||
            EGifPutExtensionBlock(s.gif, 3, loop) == GIF_ERROR ||
            EGifPutExtensionTrailer(s.gif) == GIF_ERROR)
            return gif_failure(s, s.gif->Error, "loop extension");
        s.lookup.assign(1u << 15, -1);
        s.indices.resize(pixels);
        s.have_palette = true;
    }
    for (size_t p = 0; p < pixels; ++p) {
        const uint8_t* px = &image.rgba[4 * p];
        const uint32_t key = (uint32_t(px[0] >> 3) << 10) | (uint32_t(px[1] >> 3) << 5) | (px[2] >> 3);
        int16_t& entry = s.lookup[key];
        if (entry < 0) {
            // Nearest palette colour to the centre of this 5-bit cell.
            const int cr = int(px[0] & 0xF8) + 4, cg = int(px[1] & 0xF8) + 4, cb = int(px[2] & 0xF8) + 4;
            int best = 0, best_d = std::numeric_limits<int>::max();
            for (int i = 0; i < s.palette_size; ++i) {
                const int dr = cr - s.palette[i].Red, dg = cg - s.palette[i].Green,
                          db = cb - s.palette[i].Blue;
                const int d = 2 * dr * dr + 4 * dg * dg + 3 * db * db;
                if (d < best_d) best_d = d, best = i;
            }
            entry = int16_t(best);
        }
        s.indices[p] = GifByteType(entry);
    }
    GraphicsControlBlock gcb{};
    gcb.DisposalMode = DISPOSE_DO_NOT;
    gcb.UserInputFlag = false;
    gcb.DelayTime = int(std::min<uint32_t>(delay_cs, 65535));
    gcb.TransparentColor = NO_TRANSPARENT_COLOR;
    GifByteType extension[4];
    const size_t length = EGifGCBToExtension(&gcb, extension);
    if (EGifPutExtension(s.gif, GRAPHICS_EXT_FUNC_CODE, int(length), extension) == GIF_ERROR)
        return gif_failure(s, s.gif->Error, "frame delay");
    if (EGifPutImageDesc(s.gif, 0, 0, int(s.width), int(s.height), false, nullptr) == GIF_ERROR)
        return gif_failure(s, s.gif->Error, "image descriptor");
    for (uint32_t y = 0; y < s.height; ++y)
        if (EGifPutLine(s.gif, &s.indices[size_t(y) * s.width], int(s.width)) == GIF_ERROR)
            return gif_failure(s, s.gif->Error, "image data");
    return {};
}

Status GifWriter::finish() {
    State& s = *state_;
    if (!s.gif) return {};
    if (!s.have_palette) return {ErrorCode::internal, "gif: no frame was added"};
    int error = 0;
    const int closed = EGifCloseFile(s.gif, &error);
    s.gif = nullptr;
    if (closed == GIF_ERROR) return gif_failure(s, error, "trailer");
    return s.sink_status;
}

}  // namespace hmsm::render
