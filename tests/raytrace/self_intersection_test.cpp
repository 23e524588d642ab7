// Checks <cdp/raytrace/self_intersection.h>: closed meshes without crossings, overlapping spheres
// against a brute-force count, every adjacency rule of the exact test, degenerate and invalid
// input, the broad phase against brute force on random boxes and triangle soups (no candidate is
// lost), and an independent floating-point test on random triangles in general position.
#include "common/reference_meshes.h"
#include <cdp/raytrace/self_intersection.h>

#include <cdp/core/errors.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <map>
#include <optional>
#include <random>

#include "common/intersection_helpers.h"

namespace cdp {
namespace {

using test::brute_force_pairs;
using test::merged;
using test::Pairs;

// A mesh of loose triangles given by their corners (no shared indices).
Mesh soup(const std::vector<std::array<Vec3, 3>>& tris) {
  Mesh m;
  for (const auto& t : tris) {
    const int base = static_cast<int>(m.positions.size());
    m.positions.insert(m.positions.end(), t.begin(), t.end());
    m.triangles.push_back({base, base + 1, base + 2});
  }
  return m;
}

// Two triangles over the given points.
Mesh two_triangles(std::vector<Vec3> positions, std::array<int, 3> a, std::array<int, 3> b) {
  Mesh m;
  m.positions = std::move(positions);
  m.triangles = {a, b};
  return m;
}

std::size_t pairs_of(const Mesh& m) { return find_self_intersections(m).pairs; }

TEST(SelfIntersection, IcosphereHasNone) {
  const Mesh sphere = icosphere(3);
  const SelfIntersectionReport r = find_self_intersections(sphere);
  EXPECT_EQ(r.pairs, 0u);
  EXPECT_TRUE(r.examples.empty());
  EXPECT_EQ(r.degenerate_triangles, 0u);
  // Every triangle's box overlaps at least those of its 12 neighbours (3 by an edge, 9 by a
  // vertex): all of them were tested and rejected.
  EXPECT_GE(r.candidate_pairs, 12 * sphere.num_triangles() / 2);
  EXPECT_EQ(find_self_intersections(regular_tetrahedron()).pairs, 0u);
}

TEST(SelfIntersection, OverlappingSpheresMatchBruteForce) {
  const Mesh m = merged(icosphere(2), icosphere(2, Vec3(0.5, 0.0, 0.0)));
  const SelfIntersectionReport r = find_self_intersections(m, 5);
  const Pairs expected = brute_force_pairs(m);
  EXPECT_GT(r.pairs, 10u);
  EXPECT_EQ(r.pairs, expected.size());
  ASSERT_EQ(r.examples.size(), 5u);
  EXPECT_EQ(r.examples, Pairs(expected.begin(), expected.begin() + 5));
  // Only pairs of one triangle from each sphere cross.
  const int first = static_cast<int>(icosphere(2).num_triangles());
  for (const auto& [f, g] : expected) {
    EXPECT_LT(f, first);
    EXPECT_GE(g, first);
  }
  // All examples when asked for more than there are; none when asked for none.
  EXPECT_EQ(find_self_intersections(m, 100000).examples, expected);
  EXPECT_TRUE(find_self_intersections(m, 0).examples.empty());
}

// Meshes of 8192 triangles or more are checked by the core on all cores (blocks of triangles,
// merged collectors): the same pairs as Embree's broad phase, an independent one.
TEST(SelfIntersection, CoreBroadPhaseOnLargeMeshesMatchesEmbrees) {
  const Mesh m = merged(icosphere(5), icosphere(5, Vec3(0.5, 0.1, 0.0)));
  ASSERT_GE(m.num_triangles(), 40000u);
  const SelfIntersectionReport r = find_self_intersections(m, 1000000);
  EXPECT_GT(r.pairs, 500u);
  EXPECT_EQ(self_intersecting_pairs(m, 1000000), r.examples);
  EXPECT_EQ(count_self_intersecting_pairs(m), r.pairs);
  // With a bound on the pairs kept: the smallest ones, whichever thread found them.
  EXPECT_EQ(self_intersecting_pairs(m, 7), Pairs(r.examples.begin(), r.examples.begin() + 7));
  EXPECT_TRUE(self_intersecting_pairs(icosphere(6)).empty());
}

TEST(SelfIntersection, SpheresFarApartHaveNone) {
  const Mesh m = merged(icosphere(2), icosphere(2, Vec3(3.0, 0.0, 0.0)));
  EXPECT_EQ(pairs_of(m), 0u);
  EXPECT_EQ(brute_force_pairs(m).size(), 0u);
}

TEST(SelfIntersection, SpheresTouchingAtOneVertex) {
  // The icosahedron is centrally symmetric, so the sphere centred at 2p has a vertex at exactly
  // p, a vertex of the first sphere: the spheres touch there only (a shared point, not counted).
  const Mesh a = icosphere(1);
  const Vec3 p = a.positions[0];
  const Mesh touching = merged(a, icosphere(1, 2.0 * p));
  EXPECT_EQ(pairs_of(touching), 0u);
  const Mesh closer = merged(a, icosphere(1, 1.99 * p));
  EXPECT_GT(pairs_of(closer), 0u);
  EXPECT_EQ(pairs_of(closer), brute_force_pairs(closer).size());
}

TEST(SelfIntersection, PushedThroughVertexCrossesTheFarSide) {
  // A vertex of an icosphere moved through the opposite side of the sphere: its fan of
  // triangles crosses the triangles there.
  Mesh m = icosphere(1);
  m.positions[0] = -1.5 * m.positions[0];
  const SelfIntersectionReport r = find_self_intersections(m);
  EXPECT_GT(r.pairs, 0u);
  EXPECT_EQ(r.pairs, brute_force_pairs(m).size());
}

// Every triangle split into four at its edge midpoints (shared midpoints).
Mesh subdivided(const Mesh& m) {
  Mesh out;
  out.positions = m.positions;
  std::map<std::pair<int, int>, int> mid;
  const auto midpoint = [&](int a, int b) {
    const auto [it, inserted] = mid.try_emplace(std::minmax(a, b), static_cast<int>(out.positions.size()));
    if (inserted) out.positions.push_back(0.5 * (m.positions[a] + m.positions[b]));
    return it->second;
  };
  for (const auto& t : m.triangles) {
    const int ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
    out.triangles.push_back({t[0], ab, ca});
    out.triangles.push_back({t[1], bc, ab});
    out.triangles.push_back({t[2], ca, bc});
    out.triangles.push_back({ab, bc, ca});
  }
  return out;
}

TEST(SelfIntersection, TetrahedronWithAVertexPushedThroughTheOppositeFace) {
  // Vertex 0 moved past the centre of the opposite face {1, 3, 2}, as far beyond it as the
  // edge midpoints are above it.
  const Mesh tet = regular_tetrahedron();
  const Vec3 base = (tet.positions[1] + tet.positions[2] + tet.positions[3]) / 3.0;
  const Vec3 pushed = base + 0.5 * (base - tet.positions[0]);
  // The plain tetrahedron only turns inside out: four points always bound a tetrahedron, and
  // every two of its faces share an edge, so there is nothing to count.
  Mesh plain = tet;
  plain.positions[0] = pushed;
  EXPECT_EQ(pairs_of(plain), 0u);
  // With every face split in four, the triangles around vertex 0 run from the midpoints of its
  // edges through the opposite face's inner triangles to the pushed vertex.
  Mesh m = subdivided(tet);
  EXPECT_EQ(pairs_of(m), 0u);
  m.positions[0] = pushed;
  const SelfIntersectionReport r = find_self_intersections(m);
  EXPECT_GT(r.pairs, 0u);
  EXPECT_EQ(r.pairs, brute_force_pairs(m).size());
}

TEST(SelfIntersection, CoplanarTrianglesWithoutSharedVerticesCount) {
  const std::array<Vec3, 3> t{Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0)};
  // Overlapping areas.
  EXPECT_EQ(pairs_of(soup({t, {Vec3(1, 1, 0), Vec3(-1, 0.5, 0), Vec3(0.5, -1, 0)}})), 1u);
  // One inside the other, no edges crossing.
  EXPECT_EQ(pairs_of(soup({t, {Vec3(0.2, 0.2, 0), Vec3(0.6, 0.2, 0), Vec3(0.2, 0.6, 0)}})), 1u);
  // A vertex touching the other's edge, and edges overlapping along a segment.
  EXPECT_EQ(pairs_of(soup({t, {Vec3(1, 0, 0), Vec3(1, -1, 0), Vec3(2, -1, 0)}})), 1u);
  EXPECT_EQ(pairs_of(soup({t, {Vec3(1, 0, 0), Vec3(3, 0, 0), Vec3(2, -1, 0)}})), 1u);
  // Apart by a hair.
  EXPECT_EQ(pairs_of(soup({t, {Vec3(1, -1e-12, 0), Vec3(1, -1, 0), Vec3(2, -1, 0)}})), 0u);
  EXPECT_EQ(pairs_of(soup({t, {Vec3(1.0000001, 1, 0), Vec3(3, 0, 0), Vec3(3, 1, 0)}})), 0u);
}

TEST(SelfIntersection, TrianglesWithoutSharedVerticesInDifferentPlanes) {
  const std::array<Vec3, 3> t{Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0)};
  // Crossing, a vertex touching the interior, an edge lying on the face, apart.
  EXPECT_EQ(pairs_of(soup({t, {Vec3(0.5, 0.5, -1), Vec3(0.5, 0.5, 1), Vec3(3, 3, 0.5)}})), 1u);
  EXPECT_EQ(pairs_of(soup({t, {Vec3(0.5, 0.5, 0), Vec3(0.5, 0.5, 1), Vec3(1, 0.5, 1)}})), 1u);
  EXPECT_EQ(pairs_of(soup({t, {Vec3(0.5, 0.5, 0), Vec3(1.5, 0.2, 0), Vec3(1, 0.5, 1)}})), 1u);
  EXPECT_EQ(pairs_of(soup({t, {Vec3(0.5, 0.5, 1e-9), Vec3(0.5, 0.5, 1), Vec3(1, 0.5, 1)}})), 0u);
  // Edge against edge in one point, (1, 0, 0), the second triangle lying in the plane x = 1 on
  // the side y <= 0; then moved away by a hair.
  EXPECT_EQ(pairs_of(soup({t, {Vec3(1, -1, 1), Vec3(1, 1, -1), Vec3(1, -5, -5)}})), 1u);
  EXPECT_EQ(pairs_of(soup({t, {Vec3(1, -1, 1 - 1e-12), Vec3(1, 1, -1 - 1e-12), Vec3(1, -5, -5)}})), 0u);
}

TEST(SelfIntersection, SharedEdgeCountsOnlyWhenFoldedFlat) {
  const Vec3 u(0, 0, 0), w(1, 0, 0), a(0.3, 1, 0);
  // Folded flat: both third vertices on the same side, in one plane.
  EXPECT_EQ(pairs_of(two_triangles({u, w, a, Vec3(0.6, 0.5, 0)}, {0, 1, 2}, {1, 0, 3})), 1u);
  EXPECT_EQ(pairs_of(two_triangles({u, w, a, Vec3(2.0, 3.0, 0)}, {0, 1, 2}, {0, 1, 3})), 1u);
  // Flat and unfolded, an ordinary dihedral angle, and a fold that is almost but not exactly
  // flat (the triangles then meet only along the edge's line).
  EXPECT_EQ(pairs_of(two_triangles({u, w, a, Vec3(0.5, -1, 0)}, {0, 1, 2}, {1, 0, 3})), 0u);
  EXPECT_EQ(pairs_of(two_triangles({u, w, a, Vec3(0.5, -0.5, 0.5)}, {0, 1, 2}, {1, 0, 3})), 0u);
  EXPECT_EQ(pairs_of(two_triangles({u, w, a, Vec3(0.6, 0.5, 1e-12)}, {0, 1, 2}, {1, 0, 3})), 0u);
}

TEST(SelfIntersection, SharedVertexCountsOnlyContactElsewhere) {
  const Vec3 v(0, 0, 0), a1(2, 0, 0), a2(0, 2, 0);
  // Touching only at the shared vertex: different planes, and one plane with opposite angles.
  EXPECT_EQ(pairs_of(two_triangles({v, a1, a2, Vec3(-1, 0, 1), Vec3(0, -1, 1)}, {0, 1, 2}, {0, 3, 4})), 0u);
  EXPECT_EQ(pairs_of(two_triangles({v, a1, a2, Vec3(-1, 0, 0), Vec3(0, -1, 0)}, {0, 1, 2}, {0, 3, 4})), 0u);
  EXPECT_EQ(pairs_of(two_triangles({v, a1, a2, Vec3(-1, -1e-9, 0), Vec3(-1e-9, -1, 0)}, {0, 1, 2}, {0, 3, 4})), 0u);
  // One plane, overlapping angles; and angles sharing only a side (edges overlapping).
  EXPECT_EQ(pairs_of(two_triangles({v, a1, a2, Vec3(1, 1, 0), Vec3(-1, 1, 0)}, {0, 1, 2}, {0, 3, 4})), 1u);
  EXPECT_EQ(pairs_of(two_triangles({v, a1, a2, Vec3(1, 0, 0), Vec3(0, -1, 0)}, {0, 1, 2}, {0, 3, 4})), 1u);
  // Different planes: piercing the face from the vertex, and the opposite edges touching.
  EXPECT_EQ(pairs_of(two_triangles({v, a1, a2, Vec3(0.5, 0.5, -1), Vec3(0.5, 0.5, 1)}, {0, 1, 2}, {0, 3, 4})), 1u);
  EXPECT_EQ(pairs_of(two_triangles({v, a1, a2, Vec3(1, 1, -1), Vec3(1, 1, 1)}, {0, 1, 2}, {0, 3, 4})), 1u);
  EXPECT_EQ(pairs_of(two_triangles({v, a1, a2, Vec3(1.5, 1.5, -1), Vec3(1.5, 1.5, 1)}, {0, 1, 2}, {0, 3, 4})), 1u);
  EXPECT_EQ(pairs_of(two_triangles({v, a1, a2, Vec3(1.5, 1.5, 0.1), Vec3(1.5, 1.5, 1)}, {0, 1, 2}, {0, 3, 4})), 0u);
}

TEST(SelfIntersection, CoincidentVerticesAreShared) {
  // The same point under two indices is a shared vertex: a fan split into separate indices
  // still touches only there.
  Mesh m = two_triangles({Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(0, 0, 0), Vec3(-1, 0, 1), Vec3(0, -1, 1)},
                         {0, 1, 2}, {3, 4, 5});
  EXPECT_EQ(pairs_of(m), 0u);
}

TEST(SelfIntersection, DuplicateTrianglesCount) {
  Mesh m = regular_tetrahedron();
  m.triangles.push_back(m.triangles[0]);
  const auto& t = m.triangles[1];
  m.triangles.push_back({t[0], t[2], t[1]});  // reversed
  const SelfIntersectionReport r = find_self_intersections(m);
  EXPECT_EQ(r.pairs, 2u);
  EXPECT_EQ(r.examples, (Pairs{{0, 4}, {1, 5}}));
}

TEST(SelfIntersection, DegenerateTrianglesAreSkippedAndCounted) {
  // A zero-area triangle (a needle through the face) and one with a repeated vertex.
  Mesh m = two_triangles({Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(0.5, 0.5, -1), Vec3(0.5, 0.5, 1),
                          Vec3(0.5, 0.5, 0)},
                         {0, 1, 2}, {3, 4, 5});
  m.triangles.push_back({0, 0, 4});
  const SelfIntersectionReport r = find_self_intersections(m);
  EXPECT_EQ(r.pairs, 0u);
  EXPECT_EQ(r.degenerate_triangles, 2u);
  EXPECT_TRUE(triangle_is_degenerate(m.positions[3], m.positions[4], m.positions[5]));
  EXPECT_FALSE(triangle_is_degenerate(m.positions[0], m.positions[1], m.positions[2]));
  // Collinear up to the last bit is not degenerate.
  EXPECT_FALSE(triangle_is_degenerate(Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(2, 2, std::nextafter(2.0, 3.0))));
  EXPECT_TRUE(triangle_is_degenerate(Vec3(0.1, 0.2, 0.3), Vec3(0.1, 0.2, 0.3), Vec3(1, 1, 1)));
}

TEST(SelfIntersection, EmptyAndTinyMeshes) {
  EXPECT_EQ(pairs_of(Mesh{}), 0u);
  EXPECT_EQ(pairs_of(soup({{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}})), 0u);
}

TEST(SelfIntersection, InvalidMeshesThrow) {
  Mesh m = regular_tetrahedron();
  m.triangles.push_back({0, 1, 4});
  EXPECT_THROW(find_self_intersections(m), InvalidInputError);
  m.triangles.back() = {0, -1, 2};
  EXPECT_THROW(find_self_intersections(m), InvalidInputError);
  m = regular_tetrahedron();
  m.positions[2].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(find_self_intersections(m), InvalidInputError);
  m = regular_tetrahedron();
  EXPECT_THROW(triangles_intersect(m, 0, 0), InvalidInputError);
  EXPECT_THROW(triangles_intersect(m, 0, 4), InvalidInputError);
}

// Random triangle soups: short triangles in a unit cube, some sharing vertices, some on a few
// common planes, some with coordinates on a coarse grid (touching, collinear, coplanar cases).
Mesh random_soup(std::uint64_t seed, int triangles, bool grid) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0), offset(-0.15, 0.15);
  std::uniform_int_distribution<int> cell(0, 8);
  const auto point = [&](const Vec3& near) {
    Vec3 p = near + Vec3(offset(rng), offset(rng), offset(rng));
    if (grid) p = Vec3(cell(rng), cell(rng), cell(rng)) / 8.0;
    if (unit(rng) < 0.2) p.z() = 0.5;  // a common plane
    return p;
  };
  Mesh m;
  for (int t = 0; t < triangles; ++t) {
    std::array<int, 3> tri;
    const Vec3 centre(unit(rng), unit(rng), unit(rng));
    for (int k = 0; k < 3; ++k) {
      if (!m.positions.empty() && unit(rng) < 0.3) {  // reuse a vertex
        tri[k] = std::uniform_int_distribution<int>(0, static_cast<int>(m.positions.size()) - 1)(rng);
      } else {
        m.positions.push_back(point(centre));
        tri[k] = static_cast<int>(m.positions.size()) - 1;
      }
    }
    m.triangles.push_back(tri);
  }
  return m;
}

TEST(SelfIntersection, RandomSoupsMatchBruteForce) {
  for (std::uint64_t seed = 1; seed <= 6; ++seed)
    for (bool grid : {false, true}) {
      const Mesh m = random_soup(seed, 300, grid);
      const Pairs expected = brute_force_pairs(m);
      const SelfIntersectionReport r = find_self_intersections(m, 1u << 20);
      EXPECT_EQ(r.examples, expected) << "seed " << seed << (grid ? " grid" : "");
      EXPECT_EQ(r.pairs, expected.size());
      EXPECT_GT(expected.size(), 0u);
    }
}

TEST(SelfIntersection, SameResultOnOneThread) {
  const Mesh m = merged(icosphere(3), icosphere(3, Vec3(0.5, 0.2, 0.1)));
  const SelfIntersectionReport all = find_self_intersections(m, 1000);
  SelfIntersectionReport one;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = find_self_intersections(m, 1000);
  }
  EXPECT_GT(all.pairs, 0u);
  EXPECT_EQ(one.pairs, all.pairs);
  EXPECT_EQ(one.examples, all.examples);
  EXPECT_EQ(one.candidate_pairs, all.candidate_pairs);
}

TEST(SelfIntersection, ExactTestIsSymmetricAndIgnoresVertexOrder) {
  // Integer coordinates in a small range: many touching, collinear and coplanar configurations;
  // the exact test must not depend on which triangle or which vertex comes first.
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> c(0, 3);
  std::size_t hits = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    std::array<Vec3, 3> a, b;
    for (auto* t : {&a, &b})
      for (Vec3& p : *t) p = Vec3(c(rng), c(rng), c(rng));
    const bool r = triangles_intersect(a, b);
    hits += r;
    ASSERT_EQ(triangles_intersect(b, a), r);
    ASSERT_EQ(triangles_intersect({a[1], a[2], a[0]}, {b[2], b[1], b[0]}), r);
    // Moving both by the same vector and swapping axes keeps the answer (exact for integers).
    std::array<Vec3, 3> a2, b2;
    for (int k = 0; k < 3; ++k) {
      a2[k] = Vec3(a[k].z(), a[k].x(), a[k].y()) + Vec3(-7, 3, 1);
      b2[k] = Vec3(b[k].z(), b[k].x(), b[k].y()) + Vec3(-7, 3, 1);
    }
    ASSERT_EQ(triangles_intersect(a2, b2), r);
  }
  EXPECT_GT(hits, 1000u);
}

TEST(SelfIntersection, NearlyCoplanarTrianglesGetOneAnswerInAnyOrder) {
  // Points of a tilted plane, rounded to double: nearly (rarely exactly) coplanar, where a
  // floating-point test would answer differently for different vertex orders.
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> x(-1.0, 1.0);
  const Vec3 o(0.1, 0.2, 0.3), e1(0.7, -0.3, 0.11), e2(0.2, 0.9, -0.37);
  std::size_t hits = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    std::array<Vec3, 3> a, b;
    for (auto* t : {&a, &b})
      for (Vec3& p : *t) p = o + x(rng) * e1 + x(rng) * e2;
    if (trial % 2) b[0] = a[1];  // a shared vertex
    if (trial % 3 == 0) b[1] = a[2];  // with the line above, a shared edge
    const bool r = triangles_intersect(a, b);
    hits += r;
    ASSERT_EQ(triangles_intersect(b, a), r);
    ASSERT_EQ(triangles_intersect({a[2], a[0], a[1]}, {b[1], b[0], b[2]}), r);
  }
  EXPECT_GT(hits, 1000u);
}

// An independent floating-point reference for triangles in general position (no shared
// vertices, not coplanar): they meet when an edge of one passes through the other.
bool edge_hits(const Vec3& p, const Vec3& q, const std::array<Vec3, 3>& t) {
  const Vec3 d = q - p, e1 = t[1] - t[0], e2 = t[2] - t[0];
  const Vec3 s = d.cross(e2);
  const double det = e1.dot(s);
  const Vec3 o = p - t[0];
  const double u = o.dot(s) / det;
  const Vec3 r = o.cross(e1);
  const double v = d.dot(r) / det, h = e2.dot(r) / det;
  return h >= 0 && h <= 1 && u >= 0 && v >= 0 && u + v <= 1;
}

TEST(SelfIntersection, AgreesWithAFloatingPointTestInGeneralPosition) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> x(-1.0, 1.0);
  std::size_t hits = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    std::array<Vec3, 3> a, b;
    for (auto* t : {&a, &b})
      for (Vec3& p : *t) p = Vec3(x(rng), x(rng), x(rng));
    bool reference = false;
    for (int e = 0; e < 3; ++e)
      reference = reference || edge_hits(a[e], a[(e + 1) % 3], b) || edge_hits(b[e], b[(e + 1) % 3], a);
    ASSERT_EQ(triangles_intersect(a, b), reference) << "trial " << trial;
    hits += reference;
  }
  EXPECT_GT(hits, 1000u);
}

// The same for triangles with one shared vertex v in general position: their planes meet in a
// line through v, and each triangle holds the part of that line on one side of v, or none (its
// angle at v holds the line's direction d or -d, or neither); they meet beyond v when both
// hold the same side.
TEST(SelfIntersection, SharedVertexAgreesWithAFloatingPointTestInGeneralPosition) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> x(-1.0, 1.0);
  // Which side of the line through v along d the angle (v; e1, e2) holds: +1 for d, -1 for -d,
  // 0 for neither; nothing when d is too close to a side of the angle to tell in floating point.
  const auto side = [](const Vec3& e1, const Vec3& e2, const Vec3& d) -> std::optional<int> {
    const Vec3 n = e1.cross(e2).normalized();
    const double s1 = n.dot(e1.normalized().cross(d)), s2 = n.dot(d.cross(e2.normalized()));
    if (std::abs(s1) < 1e-6 || std::abs(s2) < 1e-6) return std::nullopt;
    if (s1 > 0 && s2 > 0) return 1;
    if (s1 < 0 && s2 < 0) return -1;
    return 0;
  };
  std::size_t hits = 0, misses = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Vec3 v(x(rng), x(rng), x(rng));
    const std::array<Vec3, 3> a{v, Vec3(x(rng), x(rng), x(rng)), Vec3(x(rng), x(rng), x(rng))};
    const std::array<Vec3, 3> b{v, Vec3(x(rng), x(rng), x(rng)), Vec3(x(rng), x(rng), x(rng))};
    const Vec3 d = (a[1] - v).cross(a[2] - v).normalized().cross((b[1] - v).cross(b[2] - v).normalized());
    if (d.norm() < 1e-3) continue;  // nearly one plane
    const auto sa = side(a[1] - v, a[2] - v, d.normalized()), sb = side(b[1] - v, b[2] - v, d.normalized());
    if (!sa || !sb) continue;
    const bool reference = *sa != 0 && *sa == *sb;
    ASSERT_EQ(triangles_intersect(a, b), reference) << "trial " << trial;
    ASSERT_EQ(triangles_intersect(b, a), reference) << "trial " << trial;
    ++(reference ? hits : misses);
  }
  EXPECT_GT(hits, 2000u);
  EXPECT_GT(misses, 2000u);
}

TEST(OverlappingBoxPairs, MatchBruteForceIncludingTouchingAndEmptyBoxes) {
  std::mt19937_64 rng(3);
  std::uniform_int_distribution<int> c(0, 20), len(0, 3);
  std::vector<Box> boxes;
  for (int i = 0; i < 600; ++i) {
    Box b;
    for (int a = 0; a < 3; ++a) {
      b.min[a] = c(rng) * 1e5;  // far from float-friendly sizes on purpose
      b.max[a] = b.min[a] + len(rng) * 1e5;
    }
    if (i % 50 == 0) std::swap(b.min, b.max), b.max.x() = b.min.x() - 1;  // empty
    boxes.push_back(b);
  }
  Pairs expected;
  for (int i = 0; i < static_cast<int>(boxes.size()); ++i)
    for (int j = i + 1; j < static_cast<int>(boxes.size()); ++j) {
      const Box &p = boxes[i], &q = boxes[j];
      const bool empty = (p.min.array() > p.max.array()).any() || (q.min.array() > q.max.array()).any();
      if (!empty && (p.min.array() <= q.max.array()).all() && (q.min.array() <= p.max.array()).all())
        expected.emplace_back(i, j);
    }
  EXPECT_GT(expected.size(), 1000u);
  EXPECT_EQ(overlapping_box_pairs(boxes), expected);
  EXPECT_TRUE(overlapping_box_pairs({}).empty());
  // Boxes one float step apart near a large offset still count exactly in double.
  const double big = 1e9;
  std::vector<Box> close{{Vec3(big, 0, 0), Vec3(big + 1, 1, 1)}, {Vec3(big + 1, 0, 0), Vec3(big + 2, 1, 1)},
                         {Vec3(big + 2 + 1e-6, 0, 0), Vec3(big + 3, 1, 1)}};
  EXPECT_EQ(overlapping_box_pairs(close), (Pairs{{0, 1}}));
  std::vector<Box> bad{{Vec3::Zero(), Vec3::Ones()}, {Vec3::Zero(), Vec3::Constant(std::numeric_limits<double>::infinity())}};
  EXPECT_THROW(overlapping_box_pairs(bad), InvalidInputError);
}

}  // namespace
}  // namespace cdp
