// The checks stage (polygonizer/src/adaptive/stage_checks.h) on meshes made by hand.
#include <gtest/gtest.h>

#include "src/adaptive/stage_checks.h"

#include <cdp/core/cancel.h>
#include <cdp/core/errors.h>
#include <cdp/core/models/analytic.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <utility>

namespace cdp::adaptive {
namespace {

TEST(AdaptiveStages, TheChecksRefuseAnOpenMeshAndCountTheQualityBoundsMissed) {
  Mesh tetra;
  tetra.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tetra.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  const CancelToken cancel;
  EXPECT_EQ(check_mesh(tetra, 1, true, 1, cancel), 1u);
  EXPECT_THROW(check_mesh(tetra, 2, true, 1, cancel), NoSurfaceError);  // one component from two seeds
  Mesh open = tetra;
  open.triangles.pop_back();
  try {
    check_mesh(open, 1, true, 1, cancel);
    ADD_FAILURE() << "no error";
  } catch (const NoSurfaceError& e) {
    EXPECT_NE(std::string(e.what()).find("3 boundary"), std::string::npos) << e.what();
  }
  // The tetrahedron's faces: three right isosceles triangles (45 degrees, edge ratio 1.41) and
  // one equilateral: none under 30 degrees, a mean edge ratio of 1.31 (over 1.25); triangles
  // beyond the tolerance are a bound missed too.
  EXPECT_EQ(missed_bounds(tetra, 0), 1);
  EXPECT_EQ(missed_bounds(tetra, 5), 2);
  Mesh sliver = tetra;
  sliver.positions[3] = {0.5, 0.5, 0.01};  // the faces at vertex 3 nearly flat: angles near 0
  EXPECT_EQ(missed_bounds(sliver, 0), 3);
  EXPECT_NEAR(min_angle_degrees(tetra), 45, 1e-9);
}

// The octahedron with its vertices on the unit sphere, each triangle split in four `levels` times
// with the new vertices pushed out onto the sphere.
Mesh sphere_octahedron(int levels) {
  Mesh m;
  m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int, int>, int> middle;
    const auto at = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      if (const auto it = middle.find(key); it != middle.end()) return it->second;
      m.positions.push_back((m.positions[static_cast<std::size_t>(a)] + m.positions[static_cast<std::size_t>(b)]).normalized());
      return middle[key] = static_cast<int>(m.positions.size()) - 1;
    };
    std::vector<std::array<int, 3>> finer;
    for (const auto& t : m.triangles) {
      const int ab = at(t[0], t[1]), bc = at(t[1], t[2]), ca = at(t[2], t[0]);
      finer.insert(finer.end(), {{t[0], ab, ca}, {ab, t[1], bc}, {ca, bc, t[2]}, {ab, bc, ca}});
    }
    m.triangles = std::move(finer);
  }
  return m;
}

TEST(AdaptiveStages, TheBendCheckRefusesTrianglesCuttingAcrossABendFinerThanTheirEdges) {
  // A unit sphere at factor 8 asks for edges of about 1/8: the octahedron's faces (edges 1.41,
  // middles 0.42 inside) cut across it, the octahedron split three times (edges about 0.18)
  // follows it; at factor 1 (edges of about 1) the octahedron is what the sizing asks for.
  const Sphere sphere(Vec3::Zero(), 1);
  Sizing sizing;
  sizing.factor = 8;
  sizing.min_edge = 1e-3;
  sizing.max_edge = 2;
  try {
    check_bends_kept(sphere, sphere_octahedron(0), sizing);
    ADD_FAILURE() << "no error";
  } catch (const NoSurfaceError& e) {
    EXPECT_NE(std::string(e.what()).find("cuts across a bend"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(check_bends_kept(sphere, sphere_octahedron(3), sizing));
  sizing.factor = 1;
  EXPECT_NO_THROW(check_bends_kept(sphere, sphere_octahedron(0), sizing));
}

TEST(AdaptiveStages, TheSmallestAngleIsThatOfEveryCornerMeasured) {
  // Random triangles, a few of them slivers, with every corner's angle measured as the
  // reference: min_angle_degrees takes an arctangent only for the triangles that may hold the
  // smallest, and must find the same.
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-1, 1);
  Mesh mesh;
  for (int t = 0; t < 2000; ++t) {
    const int first = static_cast<int>(mesh.positions.size());
    for (int k = 0; k < 3; ++k) mesh.positions.push_back({coordinate(random), coordinate(random), coordinate(random)});
    if (t % 97 == 0)  // a sliver: the third corner near the middle of the first edge
      mesh.positions.back() = 0.5 * (mesh.positions[first] + mesh.positions[first + 1]) + Vec3::Constant(1e-4 * t);
    mesh.triangles.push_back({first, first + 1, first + 2});
  }
  double reference = 180;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const Vec3 u = mesh.positions[t[(k + 1) % 3]] - mesh.positions[t[k]];
      const Vec3 v = mesh.positions[t[(k + 2) % 3]] - mesh.positions[t[k]];
      reference = std::min(reference, std::atan2(u.cross(v).norm(), u.dot(v)) * 180 / std::numbers::pi);
    }
  EXPECT_LT(reference, 1);
  EXPECT_NEAR(min_angle_degrees(mesh), reference, 1e-9);
  // A zero-area triangle anywhere: 0.
  mesh.positions.push_back(mesh.positions[0]);
  mesh.triangles.push_back({0, 1, static_cast<int>(mesh.positions.size()) - 1});
  EXPECT_EQ(min_angle_degrees(mesh), 0);
}

}  // namespace
}  // namespace cdp::adaptive
