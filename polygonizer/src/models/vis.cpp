#include <cdp/core/errors.h>
#include <cdp/core/models/vis.h>

#include "../helper_thread.h"

#include <Eigen/Cholesky>
#include <Eigen/Householder>
#include <Eigen/QR>

#include <chrono>
#include <cmath>
#include <limits>

namespace cdp {

namespace {

using A4 = Eigen::Array4d;
using A2 = Eigen::Array2d;

// Lanes are summed in a fixed order, so every kernel gives the same bits for the same sums.
inline double lane_sum(const A4& a) { return (a[0] + a[1]) + (a[2] + a[3]); }

std::string fmt(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

}  // namespace

Vis::Vis(const OrientedPoints& points, double normal_offset, std::string source) {
  const std::size_t n = points.positions.size();
  if (points.normals.size() != n) throw InvalidInputError(source + ": positions and normals differ in number");
  if (n < 4) throw InvalidInputError(source + ": a variational implicit needs at least 4 points, got " + std::to_string(n));
  if (!(normal_offset > 0) || !std::isfinite(normal_offset))
    throw InvalidInputError(source + ": normal_offset must be positive and finite");
  for (std::size_t i = 0; i < n; ++i) {
    if (!points.positions[i].allFinite() || !points.normals[i].allFinite() ||
        std::abs(points.normals[i].norm() - 1) > 1e-6)
      throw InvalidInputError(source + ": point " + std::to_string(i) + " has a non-finite position or a non-unit normal");
  }
  // Minimum spacing of the data points, and offset points that sit nearer another data point than
  // their own (the offset then crosses the surface and the constraints contradict each other).
  double min_d2 = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 off = points.positions[i] + normal_offset * points.normals[i];
    for (std::size_t j = 0; j < n; ++j) {
      if (j == i) continue;
      const double d2 = (points.positions[j] - points.positions[i]).squaredNorm();
      if (d2 == 0)
        throw InvalidInputError(source + ": points " + std::to_string(std::min(i, j)) + " and " +
                                std::to_string(std::max(i, j)) + " coincide (the system would be singular)");
      min_d2 = std::min(min_d2, d2);
      if ((points.positions[j] - off).norm() < normal_offset * (1 - 1e-9))
        throw InvalidInputError(source + ": normal_offset " + fmt(normal_offset) + " is too large: the offset point of point " +
                                std::to_string(i) + " is nearer to point " + std::to_string(j) + " than to its own");
    }
  }
  spacing_ = std::sqrt(min_d2);

  n_ = 2 * n;
  centres_.reserve(n_);
  values_.reserve(n_);
  for (std::size_t i = 0; i < n; ++i) {
    centres_.push_back(points.positions[i]);
    values_.push_back(0.0);
  }
  for (std::size_t i = 0; i < n; ++i) {
    centres_.push_back(points.positions[i] + normal_offset * points.normals[i]);
    values_.push_back(normal_offset);
  }
  info_.constraints = n_;
  info_.unknowns = n_ + 4;
  info_.normal_offset = normal_offset;

  const Box box = bounding_box(centres_);
  shift_ = box.center();
  scale_ = 0.5 * box.diagonal();
  inv_scale_ = 1.0 / scale_;
  set_bounds(box.inflated(kVisBoxMargin * box.diagonal()));
  solve(source);
}

void Vis::solve(const std::string& source) {
  const auto start = std::chrono::steady_clock::now();
  const Eigen::Index N = static_cast<Eigen::Index>(n_);
  std::vector<Vec3> q(n_);
  for (std::size_t i = 0; i < n_; ++i) q[i] = to_local(centres_[i]);

  Eigen::MatrixXd phi(N, N);
  for (Eigen::Index j = 0; j < N; ++j)
    for (Eigen::Index i = 0; i < N; ++i) {
      const double r = (q[i] - q[j]).norm();
      phi(i, j) = r * r * r;
    }
  Eigen::MatrixXd P(N, 4);
  for (Eigen::Index i = 0; i < N; ++i) P.row(i) << 1.0, q[i].x(), q[i].y(), q[i].z();
  Eigen::VectorXd b(N);
  for (Eigen::Index i = 0; i < N; ++i) b(i) = values_[i];

  // P = Q [R; 0]. The linear polynomial is determined only when the points span 3-D.
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(P);
  const Eigen::Matrix4d R = qr.matrixQR().topRows(4).triangularView<Eigen::Upper>();
  const double rmax = R.diagonal().cwiseAbs().maxCoeff();
  if (!(R.diagonal().cwiseAbs().minCoeff() > 1e-10 * rmax))
    throw InvalidInputError(source + ": the points are coplanar, the system is singular (no unique linear part)");

  // Q^T Phi Q; its trailing block Q2^T Phi Q2 is positive definite for distinct points.
  phi.applyOnTheLeft(qr.householderQ().adjoint());
  phi.applyOnTheRight(qr.householderQ());
  Eigen::Ref<Eigen::MatrixXd> block = phi.bottomRightCorner(N - 4, N - 4);
  const Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(block);
  if (llt.info() != Eigen::Success)
    throw InvalidInputError(source + ": the interpolation system is singular (nearly coincident points?)");
  info_.rcond = llt.rcond();
  const Eigen::VectorXd qb = qr.householderQ().adjoint() * b;
  Eigen::VectorXd y = Eigen::VectorXd::Zero(N);
  y.tail(N - 4) = llt.solve(qb.tail(N - 4));
  const Eigen::VectorXd w = qr.householderQ() * y;

  const std::size_t padded = (n_ + 3) / 4 * 4;
  cx_.assign(padded, 0.0);
  cy_.assign(padded, 0.0);
  cz_.assign(padded, 0.0);
  w_.assign(padded, 0.0);
  for (std::size_t i = 0; i < n_; ++i) {
    cx_[i] = q[i].x();
    cy_[i] = q[i].y();
    cz_[i] = q[i].z();
    w_[i] = w(static_cast<Eigen::Index>(i));
  }
  // R a = Q1^T (b - Phi w), with Phi w from the evaluation kernel (Phi itself was overwritten).
  Eigen::VectorXd t(N);
  for (Eigen::Index i = 0; i < N; ++i) t(i) = b(i) - rbf_sum(q[i]);
  const Eigen::VectorXd qt = qr.householderQ().adjoint() * t;
  const Eigen::Vector4d a = R.triangularView<Eigen::Upper>().solve(qt.head(4));
  a0_ = a(0);
  a_ = a.tail(3);

  double worst = 0;
  for (std::size_t i = 0; i < n_; ++i) worst = std::max(worst, std::abs(eval_value(centres_[i]) - values_[i]));
  info_.interpolation_residual = worst / info_.normal_offset;
  info_.polynomial_residual = (P.transpose() * w).cwiseAbs().maxCoeff() / std::max(w.cwiseAbs().maxCoeff(), 1e-300);
  info_.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!(info_.interpolation_residual <= kVisMaxResidual))
    throw InvalidInputError(source + ": the interpolation system is singular or ill-conditioned: residual " +
                            fmt(info_.interpolation_residual) + " of the offset (limit " + fmt(kVisMaxResidual) + ")");
}

namespace {

// What every kernel computes first for W of its four lanes (centre j goes to lane j mod 4): the
// offsets from q to centres j, j + 1, ..., their distances and the centres' weights. Each lane
// sees the same operations in the same order whatever W, so the kernels' sums have the same bits
// whether four lanes run together or two and two, on one thread or on two.
template <int W>
struct Offsets {
  using A = Eigen::Array<double, W, 1>;
  using Map = Eigen::Map<const A>;
  A dx, dy, dz, r2, r, w;
  Offsets(const Vec3& q, const double* cx, const double* cy, const double* cz, const double* weights, std::size_t j)
      : dx(q.x() - Map(cx + j)), dy(q.y() - Map(cy + j)), dz(q.z() - Map(cz + j)), r2(dx * dx + dy * dy + dz * dz),
        r(r2.sqrt()), w(Map(weights + j)) {}
};

// value_gradient's four sums, over all four lanes (W = 4, from lane 0) or two of them (W = 2,
// from lane 0 or 2: the halves a helper thread and the caller compute side by side).
template <int W>
struct GradientSums {
  using A = Eigen::Array<double, W, 1>;
  A acc = A::Zero(), gx = A::Zero(), gy = A::Zero(), gz = A::Zero();
};
template <int W>
GradientSums<W> gradient_sums(const Vec3& q, const double* cx, const double* cy, const double* cz,
                              const double* weights, std::size_t m, std::size_t first) {
  GradientSums<W> s;
  for (std::size_t j = first; j < m; j += 4) {
    const Offsets<W> d(q, cx, cy, cz, weights, j);
    s.acc += d.w * (d.r2 * d.r);
    const typename Offsets<W>::A wr = d.w * d.r;  // grad |d|^3 = 3 |d| d
    s.gx += wr * d.dx;
    s.gy += wr * d.dy;
    s.gz += wr * d.dz;
  }
  return s;
}

// lane_sum of the four lanes, from their two halves.
double lane_sum(const A2& low, const A2& high) { return (low[0] + low[1]) + (high[0] + high[1]); }

// gradient_hessian's eleven sums, for two of the four lanes (from lane 0 or 2). Two lanes at a
// time, because eleven sums of four lanes (22 SSE2 registers, with the temporaries over 30) are
// far over the 16 registers: the four-lane loop kept spilling them to memory (171 stack accesses
// in the function); two lanes spill far less. The centre arrays are padded to a multiple of four
// (solve), so both halves read whole pairs.
struct HessianLanes {
  A2 acc = A2::Zero(), gx = A2::Zero(), gy = A2::Zero(), gz = A2::Zero(), sr = A2::Zero(), hxx = A2::Zero(),
     hxy = A2::Zero(), hxz = A2::Zero(), hyy = A2::Zero(), hyz = A2::Zero(), hzz = A2::Zero();
};
HessianLanes hessian_lanes(const Vec3& q, const double* cx, const double* cy, const double* cz, const double* weights,
                           std::size_t m, std::size_t first) {
  HessianLanes s;
  for (std::size_t j = first; j < m; j += 4) {
    const Offsets<2> d(q, cx, cy, cz, weights, j);
    s.acc += d.w * (d.r2 * d.r);
    const A2 wr = d.w * d.r;
    s.gx += wr * d.dx;
    s.gy += wr * d.dy;
    s.gz += wr * d.dz;
    s.sr += wr;
    // Hessian of |d|^3: 3 (|d| I + d d^T / |d|), which tends to 0 at d = 0. Eigen 3.4's select
    // is a loop of scalar divisions and branches: it runs only where a lane sits exactly on a
    // centre (or the point is not finite), and elsewhere the packet division gives the same
    // quotients. The two changes make gradient_hessian 1.6 times faster (bench_fields_data,
    // BM_Vis): 4.1 -> 2.5 us on the bunny VIS-800, where the Hessians were a fifth of a run at
    // factor 3.
    const A2 wi = (d.r > 0.0).all() ? A2(d.w / d.r) : A2((d.r > 0.0).select(d.w / d.r, A2::Zero()));
    const A2 wx = wi * d.dx, wy = wi * d.dy;
    s.hxx += wx * d.dx;
    s.hxy += wx * d.dy;
    s.hxz += wx * d.dz;
    s.hyy += wy * d.dy;
    s.hyz += wy * d.dz;
    s.hzz += wi * d.dz * d.dz;
  }
  return s;
}

}  // namespace

double Vis::rbf_sum(const Vec3& q) const {
  A4 acc = A4::Zero();
  const std::size_t m = w_.size();
  for (std::size_t j = 0; j < m; j += 4) {
    const Offsets<4> d(q, cx_.data(), cy_.data(), cz_.data(), w_.data(), j);
    acc += d.w * (d.r2 * d.r);
  }
  return lane_sum(acc);
}

double Vis::eval_value(const Vec3& p) const {
  const Vec3 q = to_local(p);
  return rbf_sum(q) + (a0_ + a_.dot(q));
}

void Vis::eval_values(const Vec3* points, double* out, std::size_t n) const {
  for (std::size_t i = 0; i < n; ++i) out[i] = eval_value(points[i]);
}

double Vis::eval_value_gradient(const Vec3& p, Vec3& gradient) const {
  const Vec3 q = to_local(p);
  const std::size_t m = w_.size();
  if (detail::HelperThread* helper = detail::lent_helper(); helper && m >= split_value_gradient_) {
    const auto half = [this, q, m](std::size_t first) {
      return gradient_sums<2>(q, cx_.data(), cy_.data(), cz_.data(), w_.data(), m, first);
    };
    GradientSums<2> lo;
    const GradientSums<2> hi = helper->run_beside([half] { return half(2); }, [&] { lo = half(0); });
    gradient = (3.0 * Vec3(lane_sum(lo.gx, hi.gx), lane_sum(lo.gy, hi.gy), lane_sum(lo.gz, hi.gz)) + a_) * inv_scale_;
    return lane_sum(lo.acc, hi.acc) + (a0_ + a_.dot(q));
  }
  const GradientSums<4> s = gradient_sums<4>(q, cx_.data(), cy_.data(), cz_.data(), w_.data(), m, 0);
  gradient = (3.0 * Vec3(lane_sum(s.gx), lane_sum(s.gy), lane_sum(s.gz)) + a_) * inv_scale_;
  return lane_sum(s.acc) + (a0_ + a_.dot(q));
}

double Vis::eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const {
  const Vec3 q = to_local(p);
  const std::size_t m = w_.size();
  const auto half = [this, q, m](std::size_t first) {
    return hessian_lanes(q, cx_.data(), cy_.data(), cz_.data(), w_.data(), m, first);
  };
  HessianLanes lo, hi;
  if (detail::HelperThread* helper = detail::lent_helper(); helper && m >= split_gradient_hessian_) {
    hi = helper->run_beside([half] { return half(2); }, [&] { lo = half(0); });
  } else {
    lo = half(0);
    hi = half(2);
  }
  gradient = (3.0 * Vec3(lane_sum(lo.gx, hi.gx), lane_sum(lo.gy, hi.gy), lane_sum(lo.gz, hi.gz)) + a_) * inv_scale_;
  const double s = lane_sum(lo.sr, hi.sr);
  const double xy = lane_sum(lo.hxy, hi.hxy), xz = lane_sum(lo.hxz, hi.hxz), yz = lane_sum(lo.hyz, hi.hyz);
  hessian << s + lane_sum(lo.hxx, hi.hxx), xy, xz,  //
      xy, s + lane_sum(lo.hyy, hi.hyy), yz,             //
      xz, yz, s + lane_sum(lo.hzz, hi.hzz);
  hessian *= 3.0 * inv_scale_ * inv_scale_;
  return lane_sum(lo.acc, hi.acc) + (a0_ + a_.dot(q));
}

double Vis::value_scalar(const Vec3& p) const {
  const Vec3 q = to_local(p);
  double sum = 0;
  for (std::size_t j = 0; j < n_; ++j) {
    const double dx = q.x() - cx_[j], dy = q.y() - cy_[j], dz = q.z() - cz_[j];
    const double r2 = dx * dx + dy * dy + dz * dz;
    sum += w_[j] * (r2 * std::sqrt(r2));
  }
  return sum + (a0_ + a_.dot(q));
}

double Vis::value_gradient_scalar(const Vec3& p, Vec3& gradient) const {
  const Vec3 q = to_local(p);
  double sum = 0;
  Vec3 g = Vec3::Zero();
  for (std::size_t j = 0; j < n_; ++j) {
    const Vec3 d(q.x() - cx_[j], q.y() - cy_[j], q.z() - cz_[j]);
    const double r2 = d.squaredNorm();
    const double r = std::sqrt(r2);
    sum += w_[j] * (r2 * r);
    g += (w_[j] * r) * d;
  }
  gradient = (3.0 * g + a_) * inv_scale_;
  return sum + (a0_ + a_.dot(q));
}

double Vis::gradient_hessian_scalar(const Vec3& p, Vec3& gradient, Mat3& hessian) const {
  const Vec3 q = to_local(p);
  double sum = 0;
  Vec3 g = Vec3::Zero();
  Mat3 h = Mat3::Zero();
  for (std::size_t j = 0; j < n_; ++j) {
    const Vec3 d(q.x() - cx_[j], q.y() - cy_[j], q.z() - cz_[j]);
    const double r2 = d.squaredNorm();
    const double r = std::sqrt(r2);
    sum += w_[j] * (r2 * r);
    g += (w_[j] * r) * d;
    h.diagonal().array() += w_[j] * r;
    if (r > 0) h += (w_[j] / r) * (d * d.transpose());
  }
  gradient = (3.0 * g + a_) * inv_scale_;
  hessian = 3.0 * inv_scale_ * inv_scale_ * h;
  return sum + (a0_ + a_.dot(q));
}

std::unique_ptr<Vis> make_vis(const OrientedPoints& scan, const VisOptions& options, const std::string& source) {
  if (options.constraints < 8 || options.constraints % 2 != 0)
    throw InvalidInputError(source + ": constraints must be even and at least 8 (two per point), got " +
                            std::to_string(options.constraints));
  const std::size_t n = options.constraints / 2;
  if (n > scan.size())
    throw InvalidInputError(source + ": " + std::to_string(options.constraints) + " constraints need " +
                            std::to_string(n) + " points, the scan has " + std::to_string(scan.size()));
  if (!(options.normal_offset > 0) || !(options.normal_offset < 0.1))
    throw InvalidInputError(source + ": normal_offset must be in (0, 0.1) of the box diagonal, got " +
                            fmt(options.normal_offset));
  const double d = options.normal_offset * bounding_box(scan.positions).diagonal();
  return std::make_unique<Vis>(select_points(scan, farthest_point_subset(scan.positions, n)), d, source);
}

}  // namespace cdp
