// Variational implicit surface (Turk & O'Brien 1999, 2002): the interpolant of the 3-D
// variational problem, F(x) = sum_j w_j |x - c_j|^3 + a0 + a . x, through oriented points.
//
// Every point p_i gives two constraints: F(p_i) = 0 on the surface, and F(p_i + d n_i) = d at a
// small offset d along its outward normal (positive outside). The weights solve the dense
// symmetric system [Phi P; P^T 0] [w; a] = [b; 0]. phi(r) = r^3 is conditionally positive definite
// of order 2 in 3-D, so the system is solved by the null-space method: a Householder QR of P
// (N x 4) gives Q = [Q1 Q2]; w = Q2 u with Q2^T Phi Q2 (positive definite for distinct,
// non-coplanar points) factorized by Eigen's Cholesky (LLT), half the work of an LU of the full
// indefinite matrix; then R a = Q1^T (b - Phi w). The fit is made in coordinates centred on the
// points' box and scaled by its half diagonal, for conditioning; values stay in model units.
//
// Evaluation runs over the centres in structure-of-arrays form, four at a time with Eigen's
// fixed-size arrays (SIMD packets); value(), value_gradient(), gradient_hessian() and values()
// share that kernel (gradient_hessian runs it as two halves of two lanes each, for registers),
// and sum in the same order, so a value is the same bit for bit whichever path computes it, or
// whichever thread sums which lanes (a helper thread lent to the caller sums half of them for a
// large model: kSplitGradientHessianCentres). The
// *_scalar functions are a plain one-centre-at-a-time reference (for tests and the benchmark's
// comparison); they agree to rounding, not bit for bit.
#pragma once

#include <cdp/core/field.h>
#include <cdp/core/oriented_points.h>

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace cdp {

// What the solve reports; `interpolation_residual` is checked against kVisMaxResidual.
struct VisSolveInfo {
  std::size_t constraints = 0;        // 2 per point
  std::size_t unknowns = 0;           // constraints + 4
  double normal_offset = 0;           // d, model units
  double interpolation_residual = 0;  // max_i |F(x_i) - b_i| / d over all constraints (F recomputed)
  double polynomial_residual = 0;     // |P^T w|_inf / |w|_inf (the side conditions)
  double rcond = 0;                   // LLT's estimate of the reciprocal condition number of Q2^T Phi Q2
  double seconds = 0;                 // matrix assembly, factorization and check
};

// A solve whose interpolation residual exceeds this (relative to the offset d) is rejected.
inline constexpr double kVisMaxResidual = 1e-6;

struct VisOptions {
  // The paper's constraint count: two per point, so 800 constraints are 400 points, drawn from
  // the scan by farthest_point_subset (oriented_points.h). Must be even and at least 8.
  std::size_t constraints = 800;
  // d as a fraction of the scan's bounding-box diagonal.
  double normal_offset = 0.01;
};

class Vis : public Field {
 public:
  // Interpolates the points (each with its zero and its offset constraint) with offset d > 0 in
  // model units. `source` names the data in messages. InvalidInputError for fewer than 4 points,
  // non-unit or non-finite data, duplicate points, an offset point closer to another data point
  // than to its own (d too large: the offset crosses the surface), coplanar points, or a singular
  // or inaccurate solve. The box is that of all constraint points, inflated by kVisBoxMargin of
  // its diagonal: the interpolant has no data, and may have stray sheets, far from the points.
  Vis(const OrientedPoints& points, double normal_offset, std::string source = "vis");

  std::string type_name() const override { return "vis"; }
  bool thread_safe() const override { return true; }  // evaluation reads immutable data only
  bool smooth() const override { return true; }
  // C2 (its kernel r^3), and from kCostlyPointCentres centres a value and gradient costs over 70 ns
  // (1.2 ns a centre).
  bool predicts_from_hessians() const override { return n_ >= kCostlyPointCentres; }
  static constexpr std::size_t kCostlyPointCentres = 64;
  // Minimum distance between two on-surface constraint points (the data points; the offset
  // points are at distance d from their own by construction, so they would only restate d).
  std::optional<double> constraint_spacing() const override { return spacing_; }
  // None: the bound sum 3 |w_j| r^2 + |a| is valid but orders of magnitude above the true slope
  // (the weights cancel), which would make sphere tracing crawl; callers estimate one.

  const VisSolveInfo& solve_info() const { return info_; }
  // With a helper thread lent to the calling thread (as the adaptive polygonizer's tracking does
  // on two threads or more), gradient_hessian and value_gradient over at least these many
  // centres run half their lanes there, with the same bits. Handing a half over and back costs
  // about a microsecond in a run (0.6 us back to back), and a Hessian costs about 3 ns a centre,
  // a value and gradient 1.2 ns. Tracking times at factor 3 on two threads, split against not:
  // bunny VIS-800 4 % slower (its Hessians split), VIS-2000 8 % faster (Hessians; 6 % with its
  // values and gradients split too), Igea VIS-4004 23 % faster (both).
  static constexpr std::size_t kSplitGradientHessianCentres = 1024;
  static constexpr std::size_t kSplitValueGradientCentres = 3072;
  // Other centre counts from which evaluations split (for tests and benchmarks of the split; not
  // while another thread evaluates).
  void set_split_centres(std::size_t gradient_hessian, std::size_t value_gradient) {
    split_gradient_hessian_ = gradient_hessian;
    split_value_gradient_ = value_gradient;
  }
  std::size_t num_centres() const { return n_; }
  const std::vector<Vec3>& centres() const { return centres_; }       // model units
  const std::vector<double>& constraint_values() const { return values_; }

  // The plain reference loop, one centre at a time.
  double value_scalar(const Vec3& p) const;
  double value_gradient_scalar(const Vec3& p, Vec3& gradient) const;
  double gradient_hessian_scalar(const Vec3& p, Vec3& gradient, Mat3& hessian) const;

 protected:
  double eval_value(const Vec3& p) const override;
  double eval_value_gradient(const Vec3& p, Vec3& gradient) const override;
  double eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const override;
  void eval_values(const Vec3* points, double* out, std::size_t n) const override;

 private:
  void solve(const std::string& source);
  Vec3 to_local(const Vec3& p) const { return (p - shift_) * inv_scale_; }
  double rbf_sum(const Vec3& q) const;  // sum_j w_j |q - c_j|^3 in local coordinates (vectorized)

  std::size_t n_ = 0;  // centres (constraints)
  std::vector<Vec3> centres_;
  std::vector<double> values_;
  // Local coordinates: q = (p - shift_) * inv_scale_.
  Vec3 shift_ = Vec3::Zero();
  double scale_ = 1, inv_scale_ = 1;
  // Structure of arrays, padded to a multiple of 4 with zero weights.
  std::vector<double> cx_, cy_, cz_, w_;
  double a0_ = 0;
  Vec3 a_ = Vec3::Zero();
  double spacing_ = 0;
  VisSolveInfo info_;
  std::size_t split_gradient_hessian_ = kSplitGradientHessianCentres;
  std::size_t split_value_gradient_ = kSplitValueGradientCentres;
};

// Box margin, as a fraction of the constraint points' box diagonal.
inline constexpr double kVisBoxMargin = 0.1;

// The paper's VIS of a scan: `options.constraints / 2` points by farthest-point sampling, offset
// d = options.normal_offset times the diagonal of the scan's box. InvalidInputError (naming
// `source`) for an odd or too small constraint count, more points than the scan has, or a
// non-positive or too large offset (>= 0.1 of the diagonal).
std::unique_ptr<Vis> make_vis(const OrientedPoints& scan, const VisOptions& options, const std::string& source);

}  // namespace cdp
