// The public structs' layout with GLM's defaults, as the library itself is compiled.
#include "layout_fields.h"

std::vector<size_t> layout_default() { return HMSM_LAYOUT_VALUES; }
std::vector<double> simulate_default()
#include "layout_simulate.inc"
