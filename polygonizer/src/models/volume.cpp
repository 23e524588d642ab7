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

// Only the orders up to Order are filled in: a value alone needs neither derivative's weights.
template <int Order>
AxisWeights axis_weights(double u, std::size_t n, double spacing) {
  AxisWeights a;
  const double cell = std::floor(u);
  const double t = u - cell;
  const auto first = static_cast<long long>(cell) - 1;
  // Inside the axis (nearly always) the indices need no mirroring, and no division.
  if (first >= 0 && first + 3 < static_cast<long long>(n))
    for (int m = 0; m < 4; ++m) a.index[m] = static_cast<std::size_t>(first + m);
  else
    for (int m = 0; m < 4; ++m) a.index[m] = mirror(first + m, n);
  const double s = 1.0 - t, t2 = t * t, t3 = t2 * t;
  a.w[0][0] = s * s * s / 6.0;
  a.w[0][1] = (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0;
  a.w[0][2] = (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0;
  a.w[0][3] = t3 / 6.0;
  if constexpr (Order >= 1) {
    const double h1 = 1.0 / spacing;
    a.w[1][0] = -0.5 * s * s * h1;
    a.w[1][1] = (1.5 * t2 - 2.0 * t) * h1;
    a.w[1][2] = (-1.5 * t2 + t + 0.5) * h1;
    a.w[1][3] = 0.5 * t2 * h1;
  }
  if constexpr (Order >= 2) {
    const double h1 = 1.0 / spacing, h2 = h1 * h1;
    a.w[2][0] = s * h2;
    a.w[2][1] = (3.0 * t - 2.0) * h2;
    a.w[2][2] = (1.0 - 3.0 * t) * h2;
    a.w[2][3] = t * h2;
  }
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
  far_corner_ = origin_ + ((Eigen::Array3d() << dims_[0] - 1.0, dims_[1] - 1.0, dims_[2] - 1.0).finished() *
                           spacing_.array()).matrix();
  set_bounds({origin_, far_corner_});

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

  // The interpolant on a face of the grid is a convex combination of the coefficients of the two
  // layers next to it (the B-spline's weights at a node, 1/6 4/6 1/6, with the mirrored neighbour
  // the inner one): with all of those outside, the whole boundary is, and the surface stays
  // inside the grid. Samples alone would not do: the spline dips between outside samples next
  // to a deep inside. The coefficients ring next to a steep jump (by 0.27 of it per sample away,
  // from the pole sqrt(3) - 2): a brain scan cut through the brain, padded by three constant
  // layers, still had a second-layer coefficient above its level, and by five none.
  for (std::size_t f = 0; f < total; ++f) {
    const std::size_t k = f % dims_[2], j = f / dims_[2] % dims_[1], i = f / (dims_[1] * dims_[2]);
    const auto near_face = [](std::size_t m, std::size_t n) { return m <= 1 || m + 2 >= n; };
    if ((near_face(i, dims_[0]) || near_face(j, dims_[1]) || near_face(k, dims_[2])) &&
        !(sign_ * (coefficients_[f] - level_) > 0))
      throw InvalidInputError("volume: the interpolant reaches the level on the grid's faces near sample " + where(f) +
                              " (the surface reaches the edge of the data, or the spline rings next to a steep "
                              "jump in the data); pad the volume with layers of outside values: two at least, "
                              "five next to a scan's cut edge");
  }

  double slope[3] = {0, 0, 0};
  for (std::size_t f = 0; f < total; ++f)
    for (int a = 0; a < 3; ++a) {
      const std::size_t m = f / stride[a] % dims_[a];
      if (m + 1 < dims_[a])
        slope[a] = std::max(slope[a], std::abs(coefficients_[f + stride[a]] - coefficients_[f]) / spacing_[a]);
    }
  // Outside the grid the distance to it is added (slope 1 across the clamped axes).
  lipschitz_ = std::sqrt(slope[0] * slope[0] + slope[1] * slope[1] + slope[2] * slope[2] + 1.0);
}

template <int Order>
double Volume::evaluate(const Vec3& p, Vec3* gradient, Mat3* hessian) const {
  if (!p.allFinite()) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    if constexpr (Order >= 1) gradient->setConstant(nan);
    if constexpr (Order >= 2) hessian->setConstant(nan);
    return nan;
  }
  // Beyond the grid, F at the nearest point of the grid's box plus the distance to it: positive
  // (the faces are outside), so no copy of the surface appears out there, as the mirrored
  // spline would make one every 2 (n - 1) samples.
  const Vec3 q = p.cwiseMax(origin_).cwiseMin(far_corner_);
  const Vec3 off = p - q;
  AxisWeights ax[3];
  for (int a = 0; a < 3; ++a) ax[a] = axis_weights<Order>((q[a] - origin_[a]) / spacing_[a], dims_[a], spacing_[a]);
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
  const double value = sign_ * (sum[0][0][0] - level_);
  const double distance = off.norm();
  if (distance == 0) return value;
  // Along a clamped axis the first term is constant; the distance |p - q| adds n = off / |off|
  // to the gradient and (I - n n^T) / |off|, on the clamped axes, to the Hessian.
  const Vec3 n = off / distance;
  if constexpr (Order >= 1) {
    for (int a = 0; a < 3; ++a)
      if (off[a] != 0) (*gradient)[a] = 0;
    *gradient += n;
  }
  if constexpr (Order >= 2) {
    Mat3 clamped = Mat3::Zero();
    for (int a = 0; a < 3; ++a)
      if (off[a] != 0) {
        hessian->row(a).setZero();
        hessian->col(a).setZero();
        clamped(a, a) = 1;
      }
    *hessian += (clamped - n * n.transpose()) / distance;
  }
  return value + distance;
}

double Volume::eval_value(const Vec3& p) const { return evaluate<0>(p, nullptr, nullptr); }

double Volume::eval_value_gradient(const Vec3& p, Vec3& gradient) const { return evaluate<1>(p, &gradient, nullptr); }

double Volume::eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const {
  return evaluate<2>(p, &gradient, &hessian);
}

std::array<std::pair<long long, long long>, 3> Volume::support_meeting(const Vec3& lo_point,
                                                                     const Vec3& hi_point) const {
  std::array<std::pair<long long, long long>, 3> span;
  for (int a = 0; a < 3; ++a)
    span[a] = {static_cast<long long>(std::floor((lo_point[a] - origin_[a]) / spacing_[a])) - 1,
               static_cast<long long>(std::floor((hi_point[a] - origin_[a]) / spacing_[a])) + 2};
  return span;
}

std::optional<std::pair<double, double>> Volume::value_range(const Box& region) const {
  if (!(region.min.allFinite() && region.max.allFinite())) return std::nullopt;
  // The part of the region inside the grid's box (its nearest points, where the region lies
  // beyond): the distance term adds between 0 and the region's farthest reach beyond the box.
  const Vec3 lo_point = region.min.cwiseMax(origin_).cwiseMin(far_corner_);
  const Vec3 hi_point = region.max.cwiseMax(origin_).cwiseMin(far_corner_);
  const double beyond = (region.min - lo_point).cwiseAbs().cwiseMax((region.max - hi_point).cwiseAbs()).norm();
  // The mirrored coefficients beyond the ends are layers 1 and n - 2, within the range already.
  const auto span = support_meeting(lo_point, hi_point);
  std::array<std::size_t, 3> first{}, last{};
  for (int a = 0; a < 3; ++a) {
    first[a] = static_cast<std::size_t>(std::max(0LL, span[a].first));
    last[a] = static_cast<std::size_t>(std::min(static_cast<long long>(dims_[a]) - 1, span[a].second));
  }
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t i = first[0]; i <= last[0]; ++i)
    for (std::size_t j = first[1]; j <= last[1]; ++j)
      for (std::size_t k = first[2]; k <= last[2]; ++k) {
        const double c = coefficient(i, j, k);
        lo = std::min(lo, c);
        hi = std::max(hi, c);
      }
  if (sign_ > 0) return std::make_pair(lo - level_, hi - level_ + beyond);
  return std::make_pair(level_ - hi, level_ - lo + beyond);
}

void Volume::eval_values_on_lattice(const Vec3& origin, double step, int n, double* out) const {
  // Partial sums held for the separable contraction, in doubles: beyond this the points go one
  // by one (a lattice over a whole large volume).
  constexpr std::size_t kMaxPartialSums = std::size_t{1} << 22;
  const Vec3 far = origin + step * Vec3::Constant(n - 1);
  const std::size_t count = static_cast<std::size_t>(n);
  if (!(origin.allFinite() && far.allFinite() && (origin.array() >= origin_.array()).all() &&
        (far.array() <= far_corner_.array()).all())) {
    Field::eval_values_on_lattice(origin, step, n, out);
    return;
  }
  // Per axis: each lattice coordinate's four coefficient indices and weights, and the range of
  // indices they reach.
  std::array<std::vector<AxisWeights>, 3> ax;
  std::array<std::size_t, 3> lo{}, span{};
  for (int a = 0; a < 3; ++a) {
    ax[a].resize(count);
    std::size_t first = dims_[a], last = 0;
    for (std::size_t i = 0; i < count; ++i) {
      const double coordinate = origin[a] + step * static_cast<double>(i);  // as Vec3 arithmetic gives it
      ax[a][i] = axis_weights<0>((coordinate - origin_[a]) / spacing_[a], dims_[a], spacing_[a]);
      for (std::size_t m : ax[a][i].index) first = std::min(first, m), last = std::max(last, m);
    }
    lo[a] = first, span[a] = last - first + 1;
  }
  if (span[0] * span[1] * count > kMaxPartialSums || span[0] * count * count > kMaxPartialSums) {
    Field::eval_values_on_lattice(origin, step, n, out);
    return;
  }
  // z_sum[(x * span1 + y) * n + c]: the sum along z at lattice z-coordinate c of coefficient row
  // (x, y).
  std::vector<double> z_sum(span[0] * span[1] * count);
  for (std::size_t x = 0; x < span[0]; ++x)
    for (std::size_t y = 0; y < span[1]; ++y) {
      const double* row = &coefficients_[((lo[0] + x) * dims_[1] + lo[1] + y) * dims_[2]];
      for (std::size_t c = 0; c < count; ++c) {
        double z = 0;
        for (int m = 0; m < 4; ++m) z += ax[2][c].w[0][m] * row[ax[2][c].index[m]];
        z_sum[(x * span[1] + y) * count + c] = z;
      }
    }
  // yz_sum[(x * n + b) * n + c]: then along y at lattice y-coordinate b.
  std::vector<double> yz_sum(span[0] * count * count);
  for (std::size_t x = 0; x < span[0]; ++x)
    for (std::size_t b = 0; b < count; ++b)
      for (std::size_t c = 0; c < count; ++c) {
        double yz = 0;
        for (int m = 0; m < 4; ++m)
          yz += ax[1][b].w[0][m] * z_sum[(x * span[1] + ax[1][b].index[m] - lo[1]) * count + c];
        yz_sum[(x * count + b) * count + c] = yz;
      }
  for (std::size_t a = 0; a < count; ++a)
    for (std::size_t b = 0; b < count; ++b)
      for (std::size_t c = 0; c < count; ++c) {
        double sum = 0;
        for (int m = 0; m < 4; ++m)
          sum += ax[0][a].w[0][m] * yz_sum[((ax[0][a].index[m] - lo[0]) * count + b) * count + c];
        out[(c * count + b) * count + a] = sign_ * (sum - level_);
      }
}

std::optional<std::pair<Vec3, Vec3>> Volume::gradient_range(const Box& region) const {
  if (!(region.min.allFinite() && region.max.allFinite())) return std::nullopt;
  if ((region.min.array() < origin_.array()).any() || (region.max.array() > far_corner_.array()).any())
    return std::nullopt;
  const auto span = support_meeting(region.min, region.max);
  std::array<std::size_t, 3> first{}, last{};
  for (int a = 0; a < 3; ++a) {
    if (span[a].first < 1 || span[a].second + 1 >= static_cast<long long>(dims_[a])) return std::nullopt;  // mirrored
    first[a] = static_cast<std::size_t>(span[a].first);
    last[a] = static_cast<std::size_t>(span[a].second);
  }
  const std::array<std::size_t, 3> stride{dims_[1] * dims_[2], dims_[2], 1};
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t i = first[0]; i <= last[0]; ++i)
    for (std::size_t j = first[1]; j <= last[1]; ++j)
      for (std::size_t k = first[2]; k <= last[2]; ++k) {
        const std::array<std::size_t, 3> at{i, j, k};
        const std::size_t f = i * stride[0] + j * stride[1] + k;
        for (int a = 0; a < 3; ++a) {
          if (at[a] == last[a]) continue;
          const double d = (coefficients_[f + stride[a]] - coefficients_[f]) / spacing_[a];
          lo[a] = std::min(lo[a], d);
          hi[a] = std::max(hi[a], d);
        }
      }
  if (sign_ > 0) return std::make_pair(lo, hi);
  return std::make_pair(Vec3(-hi), Vec3(-lo));
}

}  // namespace cdp
