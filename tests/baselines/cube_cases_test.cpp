// Checks the generated Marching Cubes table (<cdp/baselines/cube_cases.h>) case by case: every one of
// the 256 corner sign patterns, under every decision on its ambiguous faces, closes up, and two
// cubes sharing a face draw the same segments on it in opposite directions.
#include <cdp/baselines/cube_cases.h>

#include <cdp/core/field.h>

#include <gtest/gtest.h>

#include <map>
#include <set>
#include <utility>

namespace cdp {
namespace {

bool inside_at(int inside, int c) { return (inside >> c) & 1; }

bool crossed(int inside, int e) { return inside_at(inside, kCubeEdges[e][0]) != inside_at(inside, kCubeEdges[e][1]); }

bool edge_on_face(int e, int f) {
  int on = 0;
  for (int c : kCubeFaces[f]) on += c == kCubeEdges[e][0] || c == kCubeEdges[e][1];
  return on == 2;
}

// Directed polygon sides of a case that lie on face f, as pairs of edges.
std::set<std::pair<int, int>> sides_on_face(const CubeCase& cc, int f) {
  std::set<std::pair<int, int>> out;
  for (const auto& poly : cc.polygons)
    for (std::size_t q = 0; q < poly.size(); ++q) {
      const int a = poly[q], b = poly[(q + 1) % poly.size()];
      if (edge_on_face(a, f) && edge_on_face(b, f)) out.insert({a, b});
    }
  return out;
}

TEST(CubeCases, EveryCaseClosesUpIntoTriangulatedPolygons) {
  for (int inside = 0; inside < 256; ++inside)
    for (int join = 0; join < 64; ++join) {
      SCOPED_TRACE("inside " + std::to_string(inside) + " join " + std::to_string(join));
      const CubeCase& cc = cube_case(static_cast<std::uint8_t>(inside), static_cast<std::uint8_t>(join));
      // Each crossed edge in exactly one polygon, no other edge anywhere.
      std::map<int, int> uses;
      for (const auto& poly : cc.polygons) {
        EXPECT_GE(poly.size(), 3u);
        for (int e : poly) ++uses[e];
      }
      for (int e = 0; e < 12; ++e) EXPECT_EQ(uses[e], crossed(inside, e) ? 1 : 0) << "edge " << e;
      // Every polygon side lies on a cube face; the sides on each face pair up the face's
      // crossed edges (each crossed edge of the face in exactly one side on it).
      for (const auto& poly : cc.polygons)
        for (std::size_t q = 0; q < poly.size(); ++q) {
          const int a = poly[q], b = poly[(q + 1) % poly.size()];
          int faces = 0;
          for (int f = 0; f < 6; ++f) faces += edge_on_face(a, f) && edge_on_face(b, f);
          EXPECT_EQ(faces, 1) << "side " << a << "-" << b << " is not on a face";
        }
      for (int f = 0; f < 6; ++f) {
        std::map<int, int> on_face;
        for (auto [a, b] : sides_on_face(cc, f)) ++on_face[a], ++on_face[b];
        for (int e = 0; e < 12; ++e)
          if (edge_on_face(e, f)) {
            EXPECT_EQ(on_face[e], crossed(inside, e) ? 1 : 0);
          }
      }
      // The triangles' directed edges: polygon sides once, diagonals once each way, nothing
      // else; so the cube's surface piece is a set of disks bounded by the polygons.
      std::set<std::pair<int, int>> sides;
      for (const auto& poly : cc.polygons)
        for (std::size_t q = 0; q < poly.size(); ++q) sides.insert({poly[q], poly[(q + 1) % poly.size()]});
      std::map<std::pair<int, int>, int> directed;
      std::size_t expected_triangles = 0;
      std::set<int> centres;
      for (const auto& t : cc.triangles)
        for (int q = 0; q < 3; ++q) {
          ++directed[{t[q], t[(q + 1) % 3]}];
          if (t[q] >= kCubeCentreVertex) centres.insert(t[q] - kCubeCentreVertex);
        }
      for (std::size_t p = 0; p < cc.polygons.size(); ++p)
        expected_triangles += cc.polygons[p].size() - (centres.count(static_cast<int>(p)) ? 0 : 2);
      EXPECT_EQ(cc.triangles.size(), expected_triangles);
      for (int p : centres) EXPECT_LT(p, static_cast<int>(cc.polygons.size()));
      for (const auto& [edge, count] : directed) {
        EXPECT_EQ(count, 1);
        const bool is_side = sides.count(edge) > 0;
        const bool reversed = directed.count({edge.second, edge.first}) > 0;
        EXPECT_NE(is_side, reversed) << "edge " << edge.first << "-" << edge.second;
        if (!is_side && edge.first < kCubeCentreVertex && edge.second < kCubeCentreVertex) {
          // A diagonal lying in a face would be drawn by the cube across it too, unless only the
          // cube below the face may draw it: none lies in a face x = 0, y = 0 or z = 0.
          for (int f = 0; f < 6; f += 2) EXPECT_FALSE(edge_on_face(edge.first, f) && edge_on_face(edge.second, f));
        }
      }
      for (const auto& s : sides) EXPECT_EQ(directed.count(s), 1u);
    }
}

TEST(CubeCases, NeighboursDrawTheSameSegmentsOnASharedFaceInOppositeDirections) {
  // Cube A's face (axis, 1) is cube B's face (axis, 0); corner c of B on it is corner
  // c + (1 << axis) of A, and edge e of B on it is the edge of A between the shifted corners.
  for (int axis = 0; axis < 3; ++axis) {
    const int bit = 1 << axis;
    const auto shift_edge = [&](int e) {
      const int a = kCubeEdges[e][0] + bit, b = kCubeEdges[e][1] + bit;
      for (int g = 0; g < 12; ++g)
        if (kCubeEdges[g][0] == a && kCubeEdges[g][1] == b) return g;
      return -1;
    };
    for (int a_inside = 0; a_inside < 256; ++a_inside)
      for (int b_rest = 0; b_rest < 16; ++b_rest) {
        // B's corners on the shared face copy A's; its other four corners range over all values.
        int b_inside = 0, r = 0;
        for (int c = 0; c < 8; ++c) {
          if (c & bit) b_inside |= ((b_rest >> r++) & 1) << c;
          else b_inside |= ((a_inside >> (c + bit)) & 1) << c;
        }
        for (int decide = 0; decide < 2; ++decide) {
          const int fa = 2 * axis + 1, fb = 2 * axis;
          ASSERT_EQ(face_is_ambiguous(a_inside, fa), face_is_ambiguous(b_inside, fb));
          const CubeCase& A = cube_case(a_inside, static_cast<std::uint8_t>(decide << fa));
          const CubeCase& B = cube_case(b_inside, static_cast<std::uint8_t>(decide << fb));
          std::set<std::pair<int, int>> b_seen_from_a;
          for (auto [x, y] : sides_on_face(B, fb)) b_seen_from_a.insert({shift_edge(y), shift_edge(x)});
          EXPECT_EQ(sides_on_face(A, fa), b_seen_from_a) << "axis " << axis << " A " << a_inside << " B " << b_inside;
        }
      }
  }
}

TEST(CubeCases, TrianglesFaceAwayFromTheInside) {
  // With crossings at edge midpoints, every triangle of a case with one inside corner (or one
  // outside corner) must turn its normal away from the inside corner(s).
  const auto corner = [](int c) -> Vec3 { return Vec3(c & 1, (c >> 1) & 1, (c >> 2) & 1); };
  const auto mid = [&](int e) -> Vec3 { return 0.5 * (corner(kCubeEdges[e][0]) + corner(kCubeEdges[e][1])); };
  for (int c = 0; c < 8; ++c)
    for (bool complement : {false, true}) {
      const int inside = complement ? 255 ^ (1 << c) : 1 << c;
      const CubeCase& cc = cube_case(static_cast<std::uint8_t>(inside), 0);
      ASSERT_EQ(cc.triangles.size(), 1u);
      const auto& t = cc.triangles[0];
      const Vec3 n = (mid(t[1]) - mid(t[0])).cross(mid(t[2]) - mid(t[0]));
      const Vec3 away = (mid(t[0]) - corner(c)) * (complement ? -1 : 1);
      EXPECT_GT(n.dot(away), 0) << "corner " << c << (complement ? " outside" : " inside");
    }
  // The two-corner edge case: a quad, two triangles, normals away from the inside edge.
  const CubeCase& edge_case = cube_case(0b11, 0);
  ASSERT_EQ(edge_case.polygons.size(), 1u);
  EXPECT_EQ(edge_case.polygons[0].size(), 4u);
  for (const auto& t : edge_case.triangles) {
    const Vec3 n = (mid(t[1]) - mid(t[0])).cross(mid(t[2]) - mid(t[0]));
    EXPECT_GT(n.dot(Vec3(0, 1, 1)), 0);
  }
}

TEST(CubeCases, AmbiguousFaceDecisionChangesTheTopology) {
  // Corners 0 and 3 inside: face z = 0 is ambiguous. Separated, two small triangles; joined,
  // one hexagon around the tunnel between them.
  const std::uint8_t inside = 0b1001;
  ASSERT_TRUE(face_is_ambiguous(inside, 4));
  EXPECT_FALSE(face_is_ambiguous(inside, 5));
  const CubeCase& separate = cube_case(inside, 0);
  const CubeCase& joined = cube_case(inside, 1 << 4);
  ASSERT_EQ(separate.polygons.size(), 2u);
  EXPECT_EQ(separate.polygons[0].size(), 3u);
  ASSERT_EQ(joined.polygons.size(), 1u);
  EXPECT_EQ(joined.polygons[0].size(), 6u);
  // Decisions on faces that are not ambiguous change nothing.
  EXPECT_EQ(cube_case(inside, 1 << 5).polygons, separate.polygons);
  EXPECT_EQ(cube_case(inside, (1 << 5) | (1 << 4)).polygons, joined.polygons);
}

}  // namespace
}  // namespace cdp
