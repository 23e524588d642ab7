#include <cdp/core/curvature.h>

#include <cdp/core/errors.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

namespace cdp {

namespace {

// Any unit vector orthogonal to n.
Vec3 any_tangent(const Vec3& n) {
  const Vec3 axis = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  return n.cross(axis).normalized();
}

}  // namespace

Curvature curvature_from_derivatives(const Vec3& gradient, const Mat3& hessian) {
  const double g = gradient.norm();
  if (!(g > 0) || !std::isfinite(g) || !hessian.allFinite()) {
    std::ostringstream msg;
    if (!std::isfinite(g)) msg << "curvature: the gradient is not finite (|grad F| = " << g << ")";
    else if (!hessian.allFinite()) msg << "curvature: the Hessian is not finite (|grad F| = " << g << ")";
    else msg << "curvature: the gradient vanishes (|grad F| = " << g << ")";
    throw NoSurfaceError(msg.str());
  }
  Curvature c;
  c.normal = gradient / g;
  // C_ij = (H_ij |G| - G_i dot_j / |G|) / |G|^2 with dot_j = G . H_j (paper, section 3).
  const Vec3 dot = hessian * gradient;  // H is symmetric
  c.C = (hessian * g - gradient * dot.transpose() / g) / (g * g);

  // Shape operator on the tangent plane, in an orthonormal basis (t1, t2): S = T^T H T / |G|.
  const Vec3 t1 = any_tangent(c.normal);
  const Vec3 t2 = c.normal.cross(t1);
  Eigen::Matrix<double, 3, 2> T;
  T << t1, t2;
  const Eigen::Matrix2d S = T.transpose() * hessian * T / g;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(S);
  // Eigen sorts eigenvalues increasingly.
  c.k2 = eig.eigenvalues()(0);
  c.k1 = eig.eigenvalues()(1);
  c.dir2 = (T * eig.eigenvectors().col(0)).normalized();
  c.dir1 = (T * eig.eigenvectors().col(1)).normalized();
  c.gaussian = c.k1 * c.k2;
  c.mean = 0.5 * (c.k1 + c.k2);
  c.mac = std::max(std::abs(c.k1), std::abs(c.k2));
  c.min_radius = c.mac > 0 ? 1.0 / c.mac : std::numeric_limits<double>::infinity();
  // atan2 keeps umbilics finite: kmax = kmin > 0 gives -1, < 0 gives +1, a plane gives 0.
  c.shape_index = -(2.0 / std::numbers::pi) * std::atan2(c.k1 + c.k2, c.k1 - c.k2);
  return c;
}

Curvature curvature_at(const Field& field, const Vec3& p) {
  Vec3 g;
  Mat3 h;
  field.gradient_hessian(p, g, h);
  return curvature_from_derivatives(g, h);
}

// Points per batch of curvatures_at: a Python field's central differences take 25 points a
// point, so a batch stays near 10 MB (as the Python binding's batches).
constexpr std::size_t kCurvatureBatch = 16384;

std::vector<Curvature> curvatures_at(const Field& field, const std::vector<Vec3>& points) {
  const std::size_t batch = std::min(points.size(), kCurvatureBatch);
  std::vector<double> values(batch);
  std::vector<Vec3> g(batch);
  std::vector<Mat3> h(batch);
  std::vector<Curvature> out;
  out.reserve(points.size());
  for (std::size_t begin = 0; begin < points.size(); begin += batch) {
    const std::size_t n = std::min(batch, points.size() - begin);
    field.gradients_hessians(points.data() + begin, values.data(), g.data(), h.data(), n);
    for (std::size_t i = 0; i < n; ++i) out.push_back(curvature_from_derivatives(g[i], h[i]));
  }
  return out;
}

}  // namespace cdp
