// crease_angles (mesh_angles.h): triangles at a field's creases and away from them, told apart by
// the field's pieces, on triangles whose angles are known in closed form.
#include <gtest/gtest.h>

#include <cdp/core/mesh_angles.h>

#include <cmath>
#include <numbers>

#include "common/test_fields.h"

namespace cdp {
namespace {

constexpr double kDegrees = 180 / std::numbers::pi;

// On the face z = 1 of the cube max(|x|, |y|, |z|) = 1 (box +-1.5, diagonal 5.2): a right
// isosceles triangle in the face (45 degrees), one with a corner on the edge x = z = 1
// (atan(0.1 / 0.5)) and one with a corner 1e-3 from that edge (atan(0.05 / 0.499)).
Mesh cube_face_triangles() {
  Mesh m;
  m.positions = {{0, 0, 1},   {0.3, 0, 1},   {0, 0.3, 1},                   // in the face
                 {1, 0, 1},   {0.5, 0, 1},   {0.5, 0.1, 1},                 // a corner on the edge
                 {0.999, 0.5, 1}, {0.5, 0.5, 1}, {0.5, 0.45, 1}};           // a corner near it
  m.triangles = {{0, 1, 2}, {3, 5, 4}, {6, 7, 8}};
  return m;
}

TEST(CreaseAngles, ATriangleIsAtACreaseWhenACornerLiesWhereTwoPiecesMeet) {
  const auto cube = test::field_from_json(test::expression("max(abs(x),abs(y),abs(z))-1", 1.5));
  const CreaseAngles a = crease_angles(*cube, cube_face_triangles());
  EXPECT_EQ(a.crease_vertices, 1u);
  EXPECT_EQ(a.triangles_at_creases, 1u);
  EXPECT_EQ(a.triangles_away, 2u);
  EXPECT_NEAR(a.min_degrees_at_creases, std::atan(0.1 / 0.5) * kDegrees, 1e-9);
  EXPECT_NEAR(a.min_degrees_away, std::atan(0.05 / 0.499) * kDegrees, 1e-9);
  EXPECT_NEAR((a.worst_away - Vec3(0.999 + 0.5 + 0.5, 0.5 + 0.5 + 0.45, 3) / 3).norm(), 0, 1e-12);
}

TEST(CreaseAngles, NearWidensWhatCountsAsOnACrease) {
  const auto cube = test::field_from_json(test::expression("max(abs(x),abs(y),abs(z))-1", 1.5));
  const CreaseAngles a = crease_angles(*cube, cube_face_triangles(), 2e-3);
  EXPECT_EQ(a.crease_vertices, 2u);
  EXPECT_EQ(a.triangles_at_creases, 2u);
  EXPECT_NEAR(a.min_degrees_at_creases, std::atan(0.05 / 0.499) * kDegrees, 1e-9);
  EXPECT_NEAR(a.min_degrees_away, 45, 1e-9);
}

TEST(CreaseAngles, AFieldWithoutPiecesHasEveryTriangleAwayFromCreases) {
  const auto ball = test::field_from_json(test::expression("sqrt(x^2+y^2+z^2)-1", 1.5));
  const CreaseAngles a = crease_angles(*ball, cube_face_triangles());
  EXPECT_EQ(a.crease_vertices, 0u);
  EXPECT_EQ(a.triangles_at_creases, 0u);
  EXPECT_EQ(a.min_degrees_at_creases, 180);
  EXPECT_NEAR(a.min_degrees_away, std::atan(0.05 / 0.499) * kDegrees, 1e-9);
}

}  // namespace
}  // namespace cdp
