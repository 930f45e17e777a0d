// A small plotting module for `hmsm analyze`: line charts (linear or log axes) and stacked
// histograms, drawn into an RGB raster with stb_easy_font's bitmap text and encoded as PNG by
// libpng. Tool-side only; no Python or plotting package at run time.
#pragma once

#include <hmsm/status.h>

#include <cstdint>
#include <string>
#include <vector>

namespace hmsm::cli::plot {

struct Color {
    uint8_t r = 0, g = 0, b = 0;
};
/// Distinct colours for series and depths (cycled).
Color palette(size_t index);

struct Axes {
    std::string title, x_label, y_label;
    bool log_x = false, log_y = false;  ///< log axes drop points <= 0
};

struct Series {
    std::vector<double> x, y;
    Color color;
    std::string label;  ///< shown in the legend when non-empty
};

/// Polylines on common axes, ranges fitted to the data (plus optional horizontal `marks`).
Result<std::vector<uint8_t>> line_chart_png(const Axes& axes, const std::vector<Series>& series,
                                            uint32_t width = 800, uint32_t height = 500);

/// Bars over bins [edges[k], edges[k+1]); layers[j][k] stacked bottom to top in layer order.
struct Stacks {
    std::vector<double> edges;
    std::vector<std::vector<double>> layers;
    std::vector<std::string> labels;  ///< one per layer
};
Result<std::vector<uint8_t>> stacked_histogram_png(const Axes& axes, const Stacks& stacks,
                                                   uint32_t width = 800, uint32_t height = 500);

}  // namespace hmsm::cli::plot
