// Colour maps for per-vertex scalars on rendered meshes. The tables are matplotlib's "coolwarm"
// (diverging) and "viridis" (sequential) sampled at 17 points and interpolated linearly, so a
// script can draw a matching colour bar with matplotlib from the map name and the range.
#pragma once

#include <cdp/core/field.h>

#include <string>
#include <vector>

namespace cdp {

enum class ColorMapKind { Coolwarm, Viridis };
enum class ColorScale { Linear, Log };

const char* to_string(ColorMapKind kind);  // matplotlib's name
const char* to_string(ColorScale scale);

// The colour (components in [0, 1]) at t in [0, 1]; t outside is clamped, NaN gives grey.
Vec3 color_at(ColorMapKind kind, double t);

// How values become colours: t = (s(value) - s(lo)) / (s(hi) - s(lo)) with s = identity or log10.
struct ColorMapping {
  ColorMapKind kind = ColorMapKind::Viridis;
  ColorScale scale = ColorScale::Linear;
  double lo = 0.0, hi = 1.0;  // in the value's units (log scale: both > 0)
  Vec3 operator()(double value) const;
};

// The mapping the renderer uses for a named scalar: "shape_index" diverging over [-1, 1];
// "mac" sequential on a log scale; anything else sequential, linear. The range of the last two
// is the 2nd to 98th percentile of the finite (for log: positive) values, so a few extreme
// vertices do not wash the map out, widened to at least 0.02 decades (log) or 2% of its
// magnitude (linear) so that a constant scalar shows one colour, not its rounding noise.
// Throws InvalidInputError when no value is usable.
ColorMapping default_color_mapping(const std::string& name, const std::vector<double>& values);

}  // namespace cdp
