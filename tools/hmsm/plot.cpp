// Raster plotting for `hmsm analyze` (see plot.h).
#include "plot.h"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wsign-compare"
#include <stb/stb_easy_font.h>
#pragma GCC diagnostic pop

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace hmsm::cli::plot {

namespace {

constexpr int kTextScale = 2;  // stb_easy_font glyphs are ~6x7 px; doubled for legibility

class Canvas {
public:
    Canvas(uint32_t w, uint32_t h) : w_(int(w)), h_(int(h)), rgb_(size_t(w) * h * 3, 255) {}

    void pixel(int x, int y, Color c) {
        if (x < 0 || y < 0 || x >= w_ || y >= h_) return;
        uint8_t* p = &rgb_[(size_t(y) * w_ + x) * 3];
        p[0] = c.r, p[1] = c.g, p[2] = c.b;
    }
    void rect(int x0, int y0, int x1, int y1, Color c) {
        for (int y = std::max(0, y0); y < std::min(h_, y1); ++y)
            for (int x = std::max(0, x0); x < std::min(w_, x1); ++x) pixel(x, y, c);
    }
    /// A line `thick` pixels wide (Bresenham with a square pen).
    void line(double x0, double y0, double x1, double y1, Color c, int thick = 2) {
        const double steps = std::max(std::fabs(x1 - x0), std::fabs(y1 - y0));
        const int n = int(std::ceil(std::min(steps, 1e5))) + 1;
        for (int i = 0; i < n; ++i) {
            const double t = n == 1 ? 0.0 : double(i) / (n - 1);
            const int x = int(std::lround(x0 + t * (x1 - x0))), y = int(std::lround(y0 + t * (y1 - y0)));
            rect(x - thick / 2, y - thick / 2, x - thick / 2 + thick, y - thick / 2 + thick, c);
        }
    }
    int text_width(const std::string& s) const {
        return kTextScale * stb_easy_font_width(const_cast<char*>(s.c_str()));
    }
    /// Text with its top-left corner at (x, y); `vertical` turns it 90 degrees (reads upwards).
    void text(int x, int y, const std::string& s, Color c, bool vertical = false) {
        std::vector<char> buffer(s.size() * 2048 + 2048);  // up to ~30 quads of 64 bytes a glyph
        const int quads = stb_easy_font_print(0, 0, const_cast<char*>(s.c_str()), nullptr,
                                              buffer.data(), int(buffer.size()));
        const int width = text_width(s);
        for (int q = 0; q < quads; ++q) {
            const float* v0 = reinterpret_cast<const float*>(buffer.data() + (4 * q) * 16);
            const float* v2 = reinterpret_cast<const float*>(buffer.data() + (4 * q + 2) * 16);
            const int qx0 = int(v0[0] * kTextScale), qy0 = int(v0[1] * kTextScale);
            const int qx1 = int(v2[0] * kTextScale), qy1 = int(v2[1] * kTextScale);
            if (!vertical) rect(x + qx0, y + qy0, x + qx1, y + qy1, c);
            else rect(x + qy0, y + width - qx1, x + qy1, y + width - qx0, c);
        }
    }
    Result<std::vector<uint8_t>> png() const {
        png_image image{};
        image.version = PNG_IMAGE_VERSION;
        image.width = png_uint_32(w_);
        image.height = png_uint_32(h_);
        image.format = PNG_FORMAT_RGB;
        png_alloc_size_t size = 0;
        if (!png_image_write_to_memory(&image, nullptr, &size, 0, rgb_.data(), 0, nullptr))
            return Status{ErrorCode::internal, std::string("PNG encoding failed: ") + image.message};
        std::vector<uint8_t> bytes(size);
        if (!png_image_write_to_memory(&image, bytes.data(), &size, 0, rgb_.data(), 0, nullptr))
            return Status{ErrorCode::internal, std::string("PNG encoding failed: ") + image.message};
        bytes.resize(size);
        return bytes;
    }
    int width() const { return w_; }
    int height() const { return h_; }

private:
    int w_, h_;
    std::vector<uint8_t> rgb_;
};

constexpr Color kInk{30, 30, 30}, kGrid{225, 225, 225};

std::string number(double v) {
    char s[32];
    if (v != 0.0 && (std::fabs(v) < 1e-3 || std::fabs(v) >= 1e5)) std::snprintf(s, sizeof s, "%.0e", v);
    else std::snprintf(s, sizeof s, "%g", v);
    return s;
}

/// Tick positions: "nice" steps (1, 2, 5 x 10^k) on a linear axis, decades on a log axis.
std::vector<double> ticks(double lo, double hi, bool log) {
    std::vector<double> out;
    if (log) {
        const double every = std::max(1.0, std::ceil((hi - lo) / 8.0));  // at most ~8 labelled decades
        for (double e = std::ceil(lo / every - 1e-9) * every; e <= hi + 1e-9; e += every) out.push_back(e);
        return out;
    }
    const double raw = (hi - lo) / 6.0;
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    const double step = raw / mag < 1.5 ? mag : raw / mag < 3.5 ? 2 * mag : raw / mag < 7.5 ? 5 * mag : 10 * mag;
    for (double t = std::ceil(lo / step) * step; t <= hi + 1e-9 * step; t += step)
        out.push_back(std::fabs(t) < 1e-12 * step ? 0.0 : t);
    return out;
}

struct Frame {
    int left = 90, right = 20, top = 50, bottom = 70;
    double x0 = 0, x1 = 1, y0 = 0, y1 = 1;  // data range (log10 on log axes)
    bool log_x = false, log_y = false;
    int w = 0, h = 0;
    double px(double x) const {
        const double v = log_x ? std::log10(x) : x;
        return left + (v - x0) / (x1 - x0) * (w - left - right);
    }
    double py(double y) const {
        const double v = log_y ? std::log10(y) : y;
        return h - bottom - (v - y0) / (y1 - y0) * (h - top - bottom);
    }
};

void pad_range(double& lo, double& hi, bool log) {
    if (!(hi > lo)) {
        const double d = log ? 0.5 : std::max(1e-12, std::fabs(lo) * 0.1 + 1e-12);
        lo -= d, hi += d;
    } else if (!log) {
        const double d = 0.05 * (hi - lo);
        lo -= d, hi += d;
    }
}

void draw_frame(Canvas& c, const Frame& f, const Axes& axes) {
    const auto xt = ticks(f.x0, f.x1, f.log_x), yt = ticks(f.y0, f.y1, f.log_y);
    for (double t : xt) {
        const double v = f.log_x ? std::pow(10.0, t) : t;
        const int x = int(std::lround(f.px(v)));
        c.rect(x, f.top, x + 1, f.h - f.bottom, kGrid);
        const std::string s = f.log_x ? "1e" + number(t) : number(t);
        c.text(x - c.text_width(s) / 2, f.h - f.bottom + 8, s, kInk);
    }
    for (double t : yt) {
        const double v = f.log_y ? std::pow(10.0, t) : t;
        const int y = int(std::lround(f.py(v)));
        c.rect(f.left, y, f.w - f.right, y + 1, kGrid);
        const std::string s = f.log_y ? "1e" + number(t) : number(t);
        c.text(f.left - 8 - c.text_width(s), y - 7, s, kInk);
    }
    c.rect(f.left, f.top, f.left + 2, f.h - f.bottom, kInk);
    c.rect(f.left, f.h - f.bottom - 1, f.w - f.right, f.h - f.bottom + 1, kInk);
    c.text((f.w - c.text_width(axes.title)) / 2, 14, axes.title, kInk);
    c.text(f.left + (f.w - f.left - f.right - c.text_width(axes.x_label)) / 2, f.h - 30, axes.x_label, kInk);
    c.text(8, f.top + (f.h - f.top - f.bottom - c.text_width(axes.y_label)) / 2, axes.y_label, kInk, true);
}

void legend(Canvas& c, const Frame& f, const std::vector<std::pair<std::string, Color>>& items) {
    int y = f.top + 8;
    for (const auto& [label, color] : items) {
        if (label.empty()) continue;
        const int x = f.w - f.right - 20 - c.text_width(label) - 30;
        c.rect(x, y + 4, x + 22, y + 10, color);
        c.text(x + 28, y, label, kInk);
        y += 22;
    }
}

}  // namespace

Color palette(size_t index) {
    static constexpr Color colors[] = {{31, 119, 180}, {214, 39, 40},  {44, 160, 44}, {255, 127, 14},
                                       {148, 103, 189}, {140, 86, 75}, {227, 119, 194}, {127, 127, 127},
                                       {188, 189, 34}, {23, 190, 207}};
    return colors[index % 10];
}

Result<std::vector<uint8_t>> line_chart_png(const Axes& axes, const std::vector<Series>& series,
                                            uint32_t width, uint32_t height) {
    Canvas c(width, height);
    Frame f;
    f.w = int(width), f.h = int(height), f.log_x = axes.log_x, f.log_y = axes.log_y;
    double xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
    auto usable = [&](double x, double y) {
        return std::isfinite(x) && std::isfinite(y) && (!axes.log_x || x > 0) && (!axes.log_y || y > 0);
    };
    for (const Series& s : series)
        for (size_t i = 0; i < s.x.size(); ++i) {
            if (!usable(s.x[i], s.y[i])) continue;
            const double x = axes.log_x ? std::log10(s.x[i]) : s.x[i];
            const double y = axes.log_y ? std::log10(s.y[i]) : s.y[i];
            xmin = std::min(xmin, x), xmax = std::max(xmax, x), ymin = std::min(ymin, y), ymax = std::max(ymax, y);
        }
    if (!std::isfinite(xmin)) xmin = 0, xmax = 1, ymin = 0, ymax = 1;
    pad_range(xmin, xmax, axes.log_x);
    pad_range(ymin, ymax, axes.log_y);
    f.x0 = xmin, f.x1 = xmax, f.y0 = ymin, f.y1 = ymax;
    draw_frame(c, f, axes);
    std::vector<std::pair<std::string, Color>> items;
    for (const Series& s : series) {
        bool have = false;
        double lx = 0, ly = 0;
        for (size_t i = 0; i < s.x.size(); ++i) {
            if (!usable(s.x[i], s.y[i])) {
                have = false;
                continue;
            }
            const double x = f.px(s.x[i]), y = f.py(s.y[i]);
            if (have) c.line(lx, ly, x, y, s.color);
            else if (s.x.size() == 1) c.rect(int(x) - 3, int(y) - 3, int(x) + 4, int(y) + 4, s.color);
            lx = x, ly = y, have = true;
        }
        items.emplace_back(s.label, s.color);
    }
    legend(c, f, items);
    return c.png();
}

Result<std::vector<uint8_t>> stacked_histogram_png(const Axes& axes, const Stacks& stacks,
                                                   uint32_t width, uint32_t height) {
    Canvas c(width, height);
    Frame f;
    f.w = int(width), f.h = int(height);
    const size_t bins = stacks.edges.size() < 2 ? 0 : stacks.edges.size() - 1;
    double top = 0;
    for (size_t k = 0; k < bins; ++k) {
        double sum = 0;
        for (const auto& layer : stacks.layers) sum += k < layer.size() ? layer[k] : 0.0;
        top = std::max(top, sum);
    }
    f.x0 = bins ? stacks.edges.front() : 0, f.x1 = bins ? stacks.edges.back() : 1;
    f.y0 = 0, f.y1 = top > 0 ? top * 1.08 : 1;
    draw_frame(c, f, axes);
    std::vector<std::pair<std::string, Color>> items;
    for (size_t k = 0; k < bins; ++k) {
        double base = 0;
        for (size_t j = 0; j < stacks.layers.size(); ++j) {
            const double v = k < stacks.layers[j].size() ? stacks.layers[j][k] : 0.0;
            if (v <= 0) continue;
            const int x0 = int(std::lround(f.px(stacks.edges[k]))) + 1;
            const int x1 = int(std::lround(f.px(stacks.edges[k + 1])));
            c.rect(x0, int(std::lround(f.py(base + v))), x1, int(std::lround(f.py(base))), palette(j));
            base += v;
        }
    }
    for (size_t j = 0; j < stacks.layers.size(); ++j)
        items.emplace_back(j < stacks.labels.size() ? stacks.labels[j] : "", palette(j));
    legend(c, f, items);
    return c.png();
}

}  // namespace hmsm::cli::plot
