#include <cdp/core/errors.h>
#include <cdp/core/models/blobs.h>

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
  for (const auto& b : blobs_) {
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
  for (const auto& b : blobs_) {
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
  for (const auto& b : blobs_) {
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
