#include <cdp/core/errors.h>
#include <cdp/core/models/volume.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace cdp {

namespace {

// The cubic B-spline's interpolation filter has one pole, sqrt(3) - 2, and gain 6
// (Unser, "Splines: a perfect fit for signal and image processing", 1999).
const double kPole = std::sqrt(3.0) - 2.0;
constexpr double kGain = 6.0;
// The causal filter's first value sums the mirrored signal's geometric series until its terms
// fall below this share of the first: |z|^k < 1e-17 after 30 terms, below double rounding.
constexpr double kSeriesTolerance = 1e-17;

// Index j of an axis of n samples, mirrored about the first and last sample (period 2 (n - 1)):
// the extension the prefilter's boundary conditions assume, so the spline continues smoothly.
std::size_t mirror(long long j, std::size_t n) {
  const long long period = 2 * (static_cast<long long>(n) - 1);
  j %= period;
  if (j < 0) j += period;
  return static_cast<std::size_t>(j < static_cast<long long>(n) ? j : period - j);
}

// In place: the samples of one line become the coefficients of the cubic spline through them,
// with mirror boundaries (Thevenaz, Blu and Unser, "Interpolation revisited", 2000).
void prefilter_line(std::vector<double>& c) {
  const std::size_t n = c.size();
  const double z = kPole;
  for (double& v : c) v *= kGain;
  // Causal initial value: the series over the mirrored signal, truncated where it has converged.
  const auto horizon = static_cast<std::size_t>(std::ceil(std::log(kSeriesTolerance) / std::log(std::abs(z))));
  double sum = c[0];
  if (horizon < n) {
    double zn = z;
    for (std::size_t k = 1; k < horizon; ++k, zn *= z) sum += zn * c[k];
  } else {
    double zn = z;
    const double iz = 1.0 / z;
    double z2n = std::pow(z, static_cast<double>(n - 1));
    sum += z2n * c[n - 1];
    z2n *= z2n * iz;
    for (std::size_t k = 1; k + 1 < n; ++k) {
      sum += (zn + z2n) * c[k];
      zn *= z;
      z2n *= iz;
    }
    sum /= 1.0 - zn * zn;
  }
  c[0] = sum;
  for (std::size_t k = 1; k < n; ++k) c[k] += z * c[k - 1];
  c[n - 1] = (z / (z * z - 1.0)) * (z * c[n - 2] + c[n - 1]);
  for (std::size_t k = n - 1; k-- > 0;) c[k] = z * (c[k + 1] - c[k]);
}

// The four coefficients one axis contributes at coordinate u (in samples), and their weights:
// w[0] the cubic B-spline's, w[1] its first derivative's, w[2] its second's, each divided by
// the spacing to that power so that derivatives come out per unit length.
struct AxisWeights {
  std::array<std::size_t, 4> index;
  double w[3][4];
};

AxisWeights axis_weights(double u, std::size_t n, double spacing) {
  AxisWeights a;
  const double cell = std::floor(u);
  const double t = u - cell;
  const auto first = static_cast<long long>(cell) - 1;
  for (int m = 0; m < 4; ++m) a.index[m] = mirror(first + m, n);
  const double s = 1.0 - t, t2 = t * t, t3 = t2 * t;
  a.w[0][0] = s * s * s / 6.0;
  a.w[0][1] = (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0;
  a.w[0][2] = (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0;
  a.w[0][3] = t3 / 6.0;
  const double h1 = 1.0 / spacing, h2 = h1 * h1;
  a.w[1][0] = -0.5 * s * s * h1;
  a.w[1][1] = (1.5 * t2 - 2.0 * t) * h1;
  a.w[1][2] = (-1.5 * t2 + t + 0.5) * h1;
  a.w[1][3] = 0.5 * t2 * h1;
  a.w[2][0] = s * h2;
  a.w[2][1] = (3.0 * t - 2.0) * h2;
  a.w[2][2] = (1.0 - 3.0 * t) * h2;
  a.w[2][3] = t * h2;
  return a;
}

std::string axis_name(int a) { return std::string(1, "xyz"[a]); }

}  // namespace

Volume::Volume(VolumeSamples samples, double level, VolumeInside inside)
    : dims_(samples.dims),
      origin_(samples.origin),
      spacing_(samples.spacing),
      level_(level),
      sign_(inside == VolumeInside::Below ? 1.0 : -1.0),
      coefficients_(std::move(samples.values)) {
  std::size_t total = 1;
  for (int a = 0; a < 3; ++a) {
    if (dims_[a] < kMinSamples)
      throw InvalidInputError("volume: needs at least " + std::to_string(kMinSamples) + " samples along each axis, found " +
                              std::to_string(dims_[a]) + " along " + axis_name(a));
    if (total > kMaxSamples / dims_[a])
      throw InvalidInputError("volume: more than " + std::to_string(kMaxSamples) + " samples");
    total *= dims_[a];
    if (!(std::isfinite(spacing_[a]) && spacing_[a] > 0))
      throw InvalidInputError("volume: the spacing along " + axis_name(a) + " must be positive and finite");
  }
  if (coefficients_.size() != total)
    throw InvalidInputError("volume: " + std::to_string(coefficients_.size()) + " values for a grid of " +
                            std::to_string(total) + " samples");
  if (!origin_.allFinite()) throw InvalidInputError("volume: the origin must be finite");
  if (!std::isfinite(level)) throw InvalidInputError("volume: the level must be finite");
  const auto where = [&](std::size_t flat) {
    const std::size_t k = flat % dims_[2], j = flat / dims_[2] % dims_[1], i = flat / (dims_[1] * dims_[2]);
    return "[" + std::to_string(i) + ", " + std::to_string(j) + ", " + std::to_string(k) + "]";
  };
  for (std::size_t f = 0; f < total; ++f)
    if (!std::isfinite(coefficients_[f])) throw InvalidInputError("volume: sample " + where(f) + " is not finite");
  for (std::size_t f = 0; f < total; ++f) {
    const std::size_t k = f % dims_[2], j = f / dims_[2] % dims_[1], i = f / (dims_[1] * dims_[2]);
    const bool on_face = i == 0 || j == 0 || k == 0 || i + 1 == dims_[0] || j + 1 == dims_[1] || k + 1 == dims_[2];
    if (on_face && !(sign_ * (coefficients_[f] - level_) > 0))
      throw InvalidInputError("volume: sample " + where(f) + " on the grid's faces is not outside the level " +
                              "(the surface reaches the edge of the data); pad the volume with outside values");
  }
  set_bounds({origin_, origin_ + ((Eigen::Array3d() << dims_[0] - 1.0, dims_[1] - 1.0, dims_[2] - 1.0).finished() *
                                  spacing_.array()).matrix()});

  // Prefilter along each axis in turn (the tensor product's filter is separable).
  const std::array<std::size_t, 3> stride{dims_[1] * dims_[2], dims_[2], 1};
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    std::vector<double> line(dims_[a]);
    for (std::size_t u = 0; u < dims_[b]; ++u)
      for (std::size_t v = 0; v < dims_[c]; ++v) {
        const std::size_t base = u * stride[b] + v * stride[c];
        for (std::size_t m = 0; m < dims_[a]; ++m) line[m] = coefficients_[base + m * stride[a]];
        prefilter_line(line);
        for (std::size_t m = 0; m < dims_[a]; ++m) coefficients_[base + m * stride[a]] = line[m];
      }
  }

  double slope[3] = {0, 0, 0};
  for (std::size_t f = 0; f < total; ++f)
    for (int a = 0; a < 3; ++a) {
      const std::size_t m = f / stride[a] % dims_[a];
      if (m + 1 < dims_[a])
        slope[a] = std::max(slope[a], std::abs(coefficients_[f + stride[a]] - coefficients_[f]) / spacing_[a]);
    }
  lipschitz_ = std::sqrt(slope[0] * slope[0] + slope[1] * slope[1] + slope[2] * slope[2]);
}

template <int Order>
double Volume::evaluate(const Vec3& p, Vec3* gradient, Mat3* hessian) const {
  AxisWeights ax[3];
  for (int a = 0; a < 3; ++a) ax[a] = axis_weights((p[a] - origin_[a]) / spacing_[a], dims_[a], spacing_[a]);
  // sum[ox][oy][oz]: the spline's derivative of those orders along x, y and z (ox + oy + oz <= Order),
  // contracted one axis at a time.
  double sum[3][3][3] = {};
  for (int a = 0; a < 4; ++a) {
    double yz[3][3] = {};
    for (int b = 0; b < 4; ++b) {
      const double* row = &coefficients_[(ax[0].index[a] * dims_[1] + ax[1].index[b]) * dims_[2]];
      double z[3] = {};
      for (int c = 0; c < 4; ++c) {
        const double v = row[ax[2].index[c]];
        for (int o = 0; o <= Order; ++o) z[o] += ax[2].w[o][c] * v;
      }
      for (int oy = 0; oy <= Order; ++oy)
        for (int oz = 0; oy + oz <= Order; ++oz) yz[oy][oz] += ax[1].w[oy][b] * z[oz];
    }
    for (int ox = 0; ox <= Order; ++ox)
      for (int oy = 0; ox + oy <= Order; ++oy)
        for (int oz = 0; ox + oy + oz <= Order; ++oz) sum[ox][oy][oz] += ax[0].w[ox][a] * yz[oy][oz];
  }
  if constexpr (Order >= 1) *gradient = sign_ * Vec3(sum[1][0][0], sum[0][1][0], sum[0][0][1]);
  if constexpr (Order >= 2) {
    Mat3& h = *hessian;
    h(0, 0) = sum[2][0][0], h(1, 1) = sum[0][2][0], h(2, 2) = sum[0][0][2];
    h(0, 1) = h(1, 0) = sum[1][1][0];
    h(0, 2) = h(2, 0) = sum[1][0][1];
    h(1, 2) = h(2, 1) = sum[0][1][1];
    h *= sign_;
  }
  return sign_ * (sum[0][0][0] - level_);
}

double Volume::eval_value(const Vec3& p) const { return evaluate<0>(p, nullptr, nullptr); }

double Volume::eval_value_gradient(const Vec3& p, Vec3& gradient) const { return evaluate<1>(p, &gradient, nullptr); }

double Volume::eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const {
  return evaluate<2>(p, &gradient, &hessian);
}

std::optional<std::pair<double, double>> Volume::value_range(const Box& region) const {
  // The coefficients whose support meets the region, per axis (mirrored indices beyond the grid).
  std::array<std::vector<std::size_t>, 3> used;
  for (int a = 0; a < 3; ++a) {
    const double lo = std::floor((region.min[a] - origin_[a]) / spacing_[a]) - 1;
    const double hi = std::floor((region.max[a] - origin_[a]) / spacing_[a]) + 2;
    if (!(std::isfinite(lo) && std::isfinite(hi))) return std::nullopt;
    std::vector<bool> seen(dims_[a], false);
    // A window wider than the mirror's period covers every index.
    const double width = std::min(hi - lo, 2.0 * static_cast<double>(dims_[a]));
    for (long long j = static_cast<long long>(lo); j <= static_cast<long long>(lo + width); ++j) seen[mirror(j, dims_[a])] = true;
    for (std::size_t m = 0; m < dims_[a]; ++m)
      if (seen[m]) used[a].push_back(m);
  }
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t i : used[0])
    for (std::size_t j : used[1])
      for (std::size_t k : used[2]) {
        const double c = coefficient(i, j, k);
        lo = std::min(lo, c);
        hi = std::max(hi, c);
      }
  if (sign_ > 0) return std::make_pair(lo - level_, hi - level_);
  return std::make_pair(level_ - hi, level_ - lo);
}

}  // namespace cdp
