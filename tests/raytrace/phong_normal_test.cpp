// Checks <cdp/raytrace/phong_normal.h>: barycentric blending and area-weighted vertex normals.
#include <cdp/raytrace/phong_normal.h>
#include "common/reference_meshes.h"

#include <cdp/core/errors.h>
#include <cdp/core/models/analytic.h>
#include <cdp/core/models/expression.h>

#include <gtest/gtest.h>

namespace cdp {
namespace {

TEST(PhongNormal, BlendsVertexNormalsWithEmbreeBarycentrics) {
  Mesh m;
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  m.triangles = {{0, 1, 2}};
  m.normals = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
  EXPECT_EQ(phong_normal(m, 0, 0, 0), Vec3::UnitX());
  EXPECT_EQ(phong_normal(m, 0, 1, 0), Vec3::UnitY());
  EXPECT_EQ(phong_normal(m, 0, 0, 1), Vec3::UnitZ());
  EXPECT_TRUE(phong_normal(m, 0, 1.0 / 3, 1.0 / 3).isApprox(Vec3(1, 1, 1).normalized(), 1e-15));
  EXPECT_TRUE(phong_normal(m, 0, 0.5, 0).isApprox(Vec3(1, 1, 0).normalized(), 1e-15));
  m.normals[1] = -Vec3::UnitX();
  EXPECT_EQ(phong_normal(m, 0, 0.5, 0), Vec3::Zero());
  m.normals.clear();
  EXPECT_THROW(phong_normal(m, 0, 0, 0), InvalidInputError);
}

TEST(PhongNormal, AreaWeightedNormalsOfAnIcosphereAreNearlyRadial) {
  const Mesh m = icosphere(3);
  const auto n = area_weighted_normals(m);
  ASSERT_EQ(n.size(), m.positions.size());
  for (std::size_t i = 0; i < n.size(); ++i) {
    EXPECT_NEAR(n[i].norm(), 1.0, 1e-14);
    EXPECT_GT(n[i].dot(m.normals[i]), 0.999);
  }
  // The area weighting: one tiny triangle hardly tilts a vertex shared with a big one.
  Mesh two;
  two.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(-1e-3, 0, 1e-3)};
  two.triangles = {{0, 1, 2}, {0, 2, 3}};
  EXPECT_GT(area_weighted_normals(two)[0].z(), 0.999);
}

TEST(FieldNormals, AreTheNormalizedGradientAtEachVertex) {
  // On a sphere's icosphere every vertex lies on the surface: the field's normal is radial.
  const Sphere sphere(Vec3(0.5, 0, 0), 2.0);
  const Mesh m = icosphere(2, Vec3(0.5, 0, 0), 2.0);
  const auto n = field_normals(sphere, m);
  ASSERT_EQ(n.size(), m.positions.size());
  for (std::size_t i = 0; i < n.size(); ++i) EXPECT_LT((n[i] - m.normals[i]).norm(), 1e-12);
  // Where the gradient vanishes (the centre of the sphere x^2+y^2+z^2-1 as an expression with a
  // zero gradient at the origin), the normal is zero rather than NaN.
  Mesh centre;
  centre.positions = {Vec3(0.5, 0, 0)};
  const Expression f("(x-0.5)^2 + y^2 + z^2 - 4", {}, Box{Vec3(-3, -3, -3), Vec3(3, 3, 3)});
  EXPECT_EQ(field_normals(f, centre)[0], Vec3::Zero());
}

TEST(PhongNormal, CornerNormalsGiveEachSideOfACreaseItsOwnNormal) {
  // A cube mesh on its exact creases: every vertex is a corner of the cube, where the vertex
  // normal (the field's gradient, one face's) blends across faces; the corner normals are each
  // triangle's own face normal, so the Phong normal is the face's everywhere.
  const Expression cube("max(abs(x),max(abs(y),abs(z)))-1", {}, Box{Vec3::Constant(-1.5), Vec3::Constant(1.5)});
  Mesh m;
  for (int i = 0; i < 8; ++i) m.positions.push_back(Vec3(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1));
  m.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                 {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  m.normals = field_normals(cube, m);
  bool blended = false;
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const auto& tri = m.triangles[t];
    const Vec3 face = (m.positions[tri[1]] - m.positions[tri[0]]).cross(m.positions[tri[2]] - m.positions[tri[0]]).normalized();
    blended = blended || !phong_normal(m, static_cast<int>(t), 1.0 / 3, 1.0 / 3).isApprox(face, 1e-12);
  }
  EXPECT_TRUE(blended);  // vertex normals alone cannot be right on every face
  m.corner_normals = field_corner_normals(cube, m, m.normals);
  ASSERT_EQ(m.corner_normals.size(), m.triangles.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const auto& tri = m.triangles[t];
    const Vec3 face = (m.positions[tri[1]] - m.positions[tri[0]]).cross(m.positions[tri[2]] - m.positions[tri[0]]).normalized();
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(m.corner_normals[t][k].isApprox(face, 1e-12)) << t << " " << k;
    EXPECT_TRUE(phong_normal(m, static_cast<int>(t), 0.2, 0.3).isApprox(face, 1e-12));
  }
  // A smooth field has no creases: no corner normals.
  const Sphere sphere(Vec3::Zero(), 1.0);
  EXPECT_TRUE(field_corner_normals(sphere, m, m.normals).empty());
}

}  // namespace
}  // namespace cdp
