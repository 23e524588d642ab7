#include <cdp/core/errors.h>
#include <cdp/core/models/blobs.h>

#include <algorithm>
#include <cmath>

namespace cdp {

namespace {

// Kernel k as a function of s = a^2 = |x - c|^2 / R^2, with dk/ds and d2k/ds2.
struct KernelValue {
  double k, dk, d2k;
};

inline KernelValue wyvill(double s) {
  if (s >= 1.0) return {0, 0, 0};
  // k = 1 - 4/9 s^3 + 17/9 s^2 - 22/9 s
  return {1.0 + s * (-22.0 / 9.0 + s * (17.0 / 9.0 - 4.0 / 9.0 * s)), -22.0 / 9.0 + s * (34.0 / 9.0 - 12.0 / 9.0 * s),
          34.0 / 9.0 - 24.0 / 9.0 * s};
}

inline KernelValue blinn(double s) {
  const double e = std::exp(-s);
  return {e, -e, e};
}

inline KernelValue kernel(BlobKernel kind, double s) { return kind == BlobKernel::Wyvill ? wyvill(s) : blinn(s); }

// The support grid (Blobs::blobs_near) from this many blobs on: below it a loop over every blob
// costs about what finding the cell does.
constexpr std::size_t kGridBlobs = 32;
// This many cells per mean blob diameter (at most kMaxGridCells along a side): a cell then meets
// a few blobs' supports.
constexpr double kCellsPerDiameter = 2;
constexpr int kMaxGridCells = 64;
// A blob's support box is widened by this share of its radius, far beyond the rounding of
// |p - c|^2 / R^2 < 1 next to the sphere of radius R.
constexpr double kSupportMargin = 1e-9;

// max over a >= 0 of |d k(a) / d a|: Wyvill's polynomial peaks at a ~ 0.5035 (about 1.58343);
// Blinn's Gaussian at a = 1/sqrt(2) (sqrt(2) e^-1/2). Rounded up.
double kernel_slope_bound(BlobKernel kind) { return kind == BlobKernel::Wyvill ? 1.5835 : 0.8578; }

}  // namespace

Blobs::Blobs(BlobKernel kernel, double threshold, std::vector<Blob> blobs)
    : kernel_(kernel), threshold_(threshold), blobs_(std::move(blobs)) {
  if (blobs_.empty()) throw InvalidInputError("blobs: needs at least one blob");
  if (!(threshold > 0)) throw InvalidInputError("blobs: threshold must be positive");
  double total_strength = 0;
  for (const auto& b : blobs_) {
    if (!(b.radius > 0)) throw InvalidInputError("blobs: every radius must be positive");
    if (!b.center.allFinite() || !std::isfinite(b.strength)) throw InvalidInputError("blobs: non-finite blob");
    total_strength += std::abs(b.strength);
    lipschitz_ += std::abs(b.strength) * kernel_slope_bound(kernel) / b.radius;
  }
  // The surface lies where sum s_i k_i reaches T. Wyvill kernels vanish beyond R. For Blinn's
  // Gaussian every blob with |s_i| e^{-a^2} < T / sum|s| cannot lift the sum to T alone: the
  // box of radius R sqrt(ln(sum|s| / T)) around each centre contains the surface.
  Box box{Vec3::Constant(HUGE_VAL), Vec3::Constant(-HUGE_VAL)};
  for (const auto& b : blobs_) {
    double reach = b.radius;
    if (kernel == BlobKernel::Blinn) reach = b.radius * std::sqrt(std::max(0.0, std::log(total_strength / threshold)));
    reach = std::max(reach, 1e-3 * b.radius) * 1.05 + 0.05 * b.radius;
    box.min = box.min.cwiseMin(b.center - Vec3::Constant(reach));
    box.max = box.max.cwiseMax(b.center + Vec3::Constant(reach));
  }
  set_bounds(box);
  all_.resize(blobs_.size());
  for (std::uint32_t i = 0; i < all_.size(); ++i) all_[i] = i;
  if (kernel == BlobKernel::Wyvill && blobs_.size() >= kGridBlobs) build_support_grid(box);
}

void Blobs::build_support_grid(const Box& box) {
  double mean_radius = 0;
  for (const auto& b : blobs_) mean_radius += b.radius;
  mean_radius /= static_cast<double>(blobs_.size());
  const Vec3 size = box.size();
  const double cell = std::max(size.maxCoeff() / kMaxGridCells, 2 * mean_radius / kCellsPerDiameter);
  inv_cell_ = 1 / cell;
  grid_origin_ = box.min;
  for (int a = 0; a < 3; ++a) cells_[a] = std::clamp(static_cast<int>(std::ceil(size[a] * inv_cell_)), 1, kMaxGridCells);
  // The cell range of [lo, hi] along each axis: floor((x - origin) / cell) is monotone in x, so
  // every point of the box falls in a cell of the range.
  const auto range = [&](const Blob& b, int a) {
    const double reach = b.radius * (1 + kSupportMargin);
    const auto at = [&](double x) {
      return std::clamp(static_cast<int>(std::floor((x - grid_origin_[a]) * inv_cell_)), 0, cells_[a] - 1);
    };
    return std::pair{at(b.center[a] - reach), at(b.center[a] + reach)};
  };
  const std::size_t n = static_cast<std::size_t>(cells_[0]) * cells_[1] * cells_[2];
  // Two passes: counts, then the lists, each blob's index written in order.
  cell_start_.assign(n + 1, 0);
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<std::uint32_t> fill;
    if (pass == 1) {
      for (std::size_t c = 0; c < n; ++c) cell_start_[c + 1] += cell_start_[c];
      cell_blobs_.assign(cell_start_[n], 0);
      fill.assign(cell_start_.begin(), cell_start_.end() - 1);
    }
    for (std::uint32_t i = 0; i < blobs_.size(); ++i) {
      const auto [x0, x1] = range(blobs_[i], 0);
      const auto [y0, y1] = range(blobs_[i], 1);
      const auto [z0, z1] = range(blobs_[i], 2);
      for (int z = z0; z <= z1; ++z)
        for (int y = y0; y <= y1; ++y)
          for (int x = x0; x <= x1; ++x) {
            if (pass == 0) ++cell_start_[cell_index(x, y, z) + 1];
            else cell_blobs_[fill[cell_index(x, y, z)]++] = i;
          }
    }
  }
}

std::span<const std::uint32_t> Blobs::blobs_near(const Vec3& p) const {
  if (cell_start_.empty()) return all_;
  std::array<int, 3> c{};
  for (int a = 0; a < 3; ++a) {
    const double t = std::floor((p[a] - grid_origin_[a]) * inv_cell_);
    // Outside the grid (or NaN): every blob, as without a grid.
    if (!(t >= 0 && t < cells_[a])) return all_;
    c[a] = static_cast<int>(t);
  }
  const std::size_t k = cell_index(c[0], c[1], c[2]);
  return {cell_blobs_.data() + cell_start_[k], cell_blobs_.data() + cell_start_[k + 1]};
}

std::optional<double> Blobs::lipschitz_bound(const Box& region) const {
  // Blinn's Gaussian never vanishes: every blob counts, at its steepest.
  if (kernel_ != BlobKernel::Wyvill) return lipschitz_;
  // Wyvill's |dk/da| = a |p(a^2)| is zero at a = 0 and a = 1 with one peak in between, so over the
  // distances [near, far] a blob's centre has from the region it is largest at the peak or at
  // an end.
  constexpr double kPeak = 0.5035;
  const auto slope = [](double a) {
    const double s = a * a;
    return a * std::abs(-22.0 / 9.0 * 2 + s * (68.0 / 9.0 - 24.0 / 9.0 * s));
  };
  double bound = 0;
  for (const auto& b : blobs_) {
    const Vec3 nearest = b.center.cwiseMax(region.min).cwiseMin(region.max);
    const double a0 = (nearest - b.center).norm() / b.radius;
    if (a0 >= 1) continue;
    const Vec3 farthest = (b.center - region.min).cwiseAbs().cwiseMax((b.center - region.max).cwiseAbs());
    const double a1 = std::min(1.0, farthest.norm() / b.radius);
    const double steepest = a0 <= kPeak && kPeak <= a1 ? kernel_slope_bound(kernel_) : std::max(slope(a0), slope(a1));
    bound += std::abs(b.strength) * steepest / b.radius;
  }
  return bound;
}

std::optional<std::pair<double, double>> Blobs::value_range(const Box& region) const {
  double lo = threshold_, hi = threshold_;
  for (const auto& b : blobs_) {
    const Vec3 nearest = b.center.cwiseMax(region.min).cwiseMin(region.max);
    const Vec3 farthest = (b.center - region.min).cwiseAbs().cwiseMax((b.center - region.max).cwiseAbs());
    const double inv_r2 = 1.0 / (b.radius * b.radius);
    const double k_near = kernel(kernel_, (nearest - b.center).squaredNorm() * inv_r2).k;
    const double k_far = kernel(kernel_, farthest.squaredNorm() * inv_r2).k;
    // F = T - sum s k: the term -s k lies between -s k_near and -s k_far.
    lo -= std::max(b.strength * k_near, b.strength * k_far);
    hi -= std::min(b.strength * k_near, b.strength * k_far);
  }
  // Rounding: widen by a few ulps of the largest magnitude summed.
  const double slack = 1e-12 * (std::abs(lo) + std::abs(hi) + threshold_);
  return std::pair{lo - slack, hi + slack};
}

double Blobs::eval_value(const Vec3& p) const {
  double sum = 0;
  for (const std::uint32_t i : blobs_near(p)) {
    const Blob& b = blobs_[i];
    const double inv_r2 = 1.0 / (b.radius * b.radius);
    const double s = (p - b.center).squaredNorm() * inv_r2;  // as in the derivative paths, bit for bit
    if (kernel_ == BlobKernel::Wyvill && s >= 1.0) continue;
    sum += b.strength * kernel(kernel_, s).k;
  }
  return threshold_ - sum;
}

double Blobs::eval_value_gradient(const Vec3& p, Vec3& gradient) const {
  double sum = 0;
  gradient.setZero();
  for (const std::uint32_t i : blobs_near(p)) {
    const Blob& b = blobs_[i];
    const Vec3 d = p - b.center;
    const double inv_r2 = 1.0 / (b.radius * b.radius);
    const double s = d.squaredNorm() * inv_r2;
    if (kernel_ == BlobKernel::Wyvill && s >= 1.0) continue;
    const KernelValue k = kernel(kernel_, s);
    sum += b.strength * k.k;
    gradient -= (b.strength * k.dk * 2.0 * inv_r2) * d;
  }
  return threshold_ - sum;
}

double Blobs::eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const {
  double sum = 0;
  gradient.setZero();
  hessian.setZero();
  for (const std::uint32_t i : blobs_near(p)) {
    const Blob& b = blobs_[i];
    const Vec3 d = p - b.center;
    const double inv_r2 = 1.0 / (b.radius * b.radius);
    const double s = d.squaredNorm() * inv_r2;
    if (kernel_ == BlobKernel::Wyvill && s >= 1.0) continue;
    const KernelValue k = kernel(kernel_, s);
    sum += b.strength * k.k;
    // d/dx k(s) = k' 2 d / R^2;  d2/dx2 = k'' 4 d d^T / R^4 + k' 2 I / R^2
    gradient -= (b.strength * k.dk * 2.0 * inv_r2) * d;
    hessian -= b.strength * (k.d2k * 4.0 * inv_r2 * inv_r2 * (d * d.transpose()) +
                             k.dk * 2.0 * inv_r2 * Mat3::Identity());
  }
  return threshold_ - sum;
}

}  // namespace cdp
