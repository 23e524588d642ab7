// Curvature measures of section 3 of the paper, from the gradient G and Hessian H at a point.
//
// C = dN/dx with N = G/|G|; C's eigenvalue along N is 0, its other two are the principal
// curvatures. We take them from the symmetric shape operator restricted to the tangent plane,
// P H P / |G| with P = I - N N^T, which has the same non-zero eigenvalues. Sign: the gradient
// points outward, so a sphere has positive curvatures.
#pragma once

#include <cdp/core/field.h>

#include <vector>

namespace cdp {

struct Curvature {
  Vec3 normal = Vec3::Zero();
  Mat3 C = Mat3::Zero();       // the paper's matrix, derivative of the unit normal
  double k1 = 0, k2 = 0;       // principal curvatures, k1 >= k2
  Vec3 dir1 = Vec3::Zero(), dir2 = Vec3::Zero();  // unit principal directions, tangent
  double gaussian = 0;         // k1 k2
  double mean = 0;             // (k1 + k2) / 2
  double mac = 0;              // max(|k1|, |k2|)
  double min_radius = 0;       // 1 / mac (infinity where flat)
  // -(2/pi) atan((kmax + kmin) / (kmax - kmin)): -1 on a sphere (convex umbilic), +1 on a
  // concave one, 0 on a saddle with k1 = -k2; 0 on a plane, where it is undefined.
  double shape_index = 0;
};

// The curvatures of the level set through a point from F's gradient and Hessian there (the
// paper's matrix C: the Hessian projected on the tangent plane, over |grad F|).
// \return the normal, principal curvatures and directions, Gaussian, mean, MAC, radius, shape index.
// \throw NoSurfaceError when the gradient vanishes or is not finite.
Curvature curvature_from_derivatives(const Vec3& gradient, const Mat3& hessian);

// curvature_from_derivatives of `field` at p: one gradient_hessian evaluation.
// \throw NoSurfaceError as curvature_from_derivatives; what the field's evaluation throws.
Curvature curvature_at(const Field& field, const Vec3& p);
// curvature_at at every point, in one batched evaluation (Field::gradients_hessians): the same
// numbers, one call of a field whose calls are costly (a Python function) instead of one a point.
// \throw as curvature_at.
std::vector<Curvature> curvatures_at(const Field& field, const std::vector<Vec3>& points);

}  // namespace cdp
