#include <cdp/render/color_map.h>

#include <cdp/core/errors.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace cdp {

namespace {

using Table = std::array<std::array<double, 3>, 17>;

// matplotlib.colormaps[name](i / 16) for i = 0..16 (matplotlib 3.6).
constexpr Table kCoolwarm = {{{0.2298, 0.2987, 0.7537}, {0.3042, 0.4069, 0.8453}, {0.3837, 0.5102, 0.9178},
                              {0.4677, 0.6056, 0.9685}, {0.5543, 0.6901, 0.9955}, {0.6408, 0.7608, 0.9978},
                              {0.7240, 0.8149, 0.9757}, {0.8006, 0.8504, 0.9300}, {0.8674, 0.8644, 0.8626},
                              {0.9256, 0.8255, 0.7711}, {0.9595, 0.7670, 0.6741}, {0.9697, 0.6905, 0.5751},
                              {0.9567, 0.5980, 0.4773}, {0.9214, 0.4914, 0.3834}, {0.8654, 0.3711, 0.2958},
                              {0.7906, 0.2314, 0.2162}, {0.7057, 0.0156, 0.1502}}};
constexpr Table kViridis = {{{0.2670, 0.0049, 0.3294}, {0.2823, 0.0950, 0.4173}, {0.2788, 0.1755, 0.4834},
                             {0.2590, 0.2515, 0.5247}, {0.2297, 0.3224, 0.5457}, {0.1994, 0.3876, 0.5546},
                             {0.1727, 0.4488, 0.5579}, {0.1490, 0.5081, 0.5573}, {0.1276, 0.5669, 0.5506},
                             {0.1206, 0.6258, 0.5335}, {0.1579, 0.6838, 0.5017}, {0.2461, 0.7389, 0.4520},
                             {0.3692, 0.7889, 0.3829}, {0.5160, 0.8312, 0.2943}, {0.6785, 0.8637, 0.1895},
                             {0.8456, 0.8873, 0.0997}, {0.9932, 0.9062, 0.1439}}};

constexpr double kMinDecades = 0.02;
constexpr double kMinRelativeSpan = 0.02;

// Nearest-rank percentile of sorted values.
double percentile(const std::vector<double>& sorted, double q) {
  const auto i = static_cast<std::size_t>(std::lround(q * static_cast<double>(sorted.size() - 1)));
  return sorted[i];
}

}  // namespace

const char* to_string(ColorMapKind kind) { return kind == ColorMapKind::Coolwarm ? "coolwarm" : "viridis"; }
const char* to_string(ColorScale scale) { return scale == ColorScale::Log ? "log" : "linear"; }

Vec3 color_at(ColorMapKind kind, double t) {
  if (std::isnan(t)) return Vec3::Constant(0.5);
  const Table& table = kind == ColorMapKind::Coolwarm ? kCoolwarm : kViridis;
  const double x = std::clamp(t, 0.0, 1.0) * 16.0;
  const int i = std::min(15, static_cast<int>(x));
  const double f = x - i;
  Vec3 c;
  for (int k = 0; k < 3; ++k) c[k] = (1 - f) * table[i][k] + f * table[i + 1][k];
  return c;
}

Vec3 ColorMapping::operator()(double value) const {
  double a = lo, b = hi, v = value;
  if (scale == ColorScale::Log) {
    a = std::log10(a);
    b = std::log10(b);
    v = value > 0 ? std::log10(value) : -std::numeric_limits<double>::infinity();
  }
  if (!std::isfinite(value)) return color_at(kind, std::numeric_limits<double>::quiet_NaN());
  // A constant field maps to the middle of the map.
  const double t = b > a ? (v - a) / (b - a) : 0.5;
  return color_at(kind, t);
}

ColorMapping default_color_mapping(const std::string& name, const std::vector<double>& values) {
  ColorMapping m;
  if (name == "shape_index") {
    m.kind = ColorMapKind::Coolwarm;
    m.lo = -1.0;
    m.hi = 1.0;
    return m;
  }
  m.kind = ColorMapKind::Viridis;
  m.scale = name == "mac" ? ColorScale::Log : ColorScale::Linear;
  std::vector<double> usable;
  for (double v : values)
    if (std::isfinite(v) && (m.scale == ColorScale::Linear || v > 0)) usable.push_back(v);
  if (usable.empty())
    throw InvalidInputError("vertex property \"" + name + "\" has no " +
                            (m.scale == ColorScale::Log ? "positive finite" : "finite") + " value to colour by");
  std::sort(usable.begin(), usable.end());
  m.lo = percentile(usable, 0.02);
  m.hi = percentile(usable, 0.98);
  // A nearly constant scalar (MAC on a torus) would stretch rounding noise over the whole map:
  // the range spans at least 0.02 decades (log) or 2% of its magnitude (linear).
  if (m.scale == ColorScale::Log) {
    const double mid = std::sqrt(m.lo * m.hi), f = std::sqrt(std::max(m.hi / m.lo, std::pow(10.0, kMinDecades)));
    m.lo = mid / f;
    m.hi = mid * f;
  } else {
    const double mid = 0.5 * (m.lo + m.hi);
    const double half = 0.5 * std::max(m.hi - m.lo, kMinRelativeSpan * std::max({std::abs(m.lo), std::abs(m.hi), 1e-300}));
    m.lo = mid - half;
    m.hi = mid + half;
  }
  return m;
}

}  // namespace cdp
