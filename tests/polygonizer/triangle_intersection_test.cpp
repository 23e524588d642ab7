// Checks <cdp/core/triangle_intersection.h>: the hash-grid broad phase with the exact test gives
// the same pairs as raytrace's find_self_intersections (Embree broad phase) and as brute force on
// random soups of triangles of very different sizes, on overlapping spheres and on meshes with
// huge triangles; pairs around a vertex whose star is proved flat are skipped only when they
// cannot intersect (perturbed and folded spheres, a star wound twice, two fans pinched at a
// vertex); degenerate and duplicate triangles follow the documented rules; the first max_pairs
// pairs and the count agree; invalid meshes throw. (The exact test's own rules are checked case
// by case in tests/raytrace/self_intersection_test.cpp.)
#include <cdp/core/triangle_intersection.h>

#include <cdp/core/errors.h>
#include "common/reference_meshes.h"
#include <cdp/raytrace/self_intersection.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include "common/intersection_helpers.h"

namespace cdp {
namespace {

using test::brute_force_pairs;
using test::merged;
using test::Pairs;
constexpr std::size_t kAll = std::numeric_limits<std::size_t>::max();

Pairs embree_pairs(const Mesh& mesh) { return find_self_intersections(mesh, kAll).examples; }

void add_triangle(Mesh& m, const Vec3& a, const Vec3& b, const Vec3& c) {
  const int base = static_cast<int>(m.positions.size());
  m.positions.insert(m.positions.end(), {a, b, c});
  m.triangles.push_back({base, base + 1, base + 2});
}

// Triangles in the cube [0, 2]^3 whose sizes vary log-uniformly by a factor 100 (0.004 to 0.4);
// some continue the previous triangle (sharing one or two of its vertices, at its size), some
// have a vertex on a common plane, and with `grid` every coordinate is a multiple of 1/256
// (touching, collinear, coplanar and degenerate cases).
Mesh varied_soup(std::uint64_t seed, int triangles, bool grid) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0), sym(-1.0, 1.0);
  Mesh m;
  double size = 0.0;
  for (int t = 0; t < triangles; ++t) {
    int shared = 0;
    Vec3 centre;
    if (t > 0 && unit(rng) < 0.4) {
      shared = unit(rng) < 0.5 ? 1 : 2;
      centre = m.positions[static_cast<std::size_t>(m.triangles.back()[0])];
    } else {
      centre = 2.0 * Vec3(unit(rng), unit(rng), unit(rng));
      size = 0.004 * std::pow(100.0, unit(rng));
    }
    std::array<int, 3> tri;
    for (int k = 0; k < 3; ++k) {
      if (k < shared) {
        tri[k] = m.triangles.back()[static_cast<std::size_t>(k)];
        continue;
      }
      Vec3 p = centre + size * Vec3(sym(rng), sym(rng), sym(rng));
      if (unit(rng) < 0.1) p.z() = 1.0;
      if (grid) p = (p * 256.0).array().round() / 256.0;
      m.positions.push_back(p);
      tri[k] = static_cast<int>(m.positions.size()) - 1;
    }
    m.triangles.push_back(tri);
  }
  return m;
}

TEST(TriangleIntersection, IcosphereAndTetrahedronHaveNone) {
  EXPECT_TRUE(self_intersecting_pairs(icosphere(4)).empty());
  EXPECT_EQ(count_self_intersecting_pairs(icosphere(4)), 0u);
  EXPECT_EQ(count_self_intersecting_pairs(regular_tetrahedron()), 0u);
  EXPECT_EQ(count_self_intersecting_pairs(merged(icosphere(2), icosphere(2, Vec3(3.0, 0.0, 0.0)))), 0u);
}

TEST(TriangleIntersection, OverlappingIcospheresMatchEmbree) {
  for (const Vec3& offset : {Vec3(0.5, 0.0, 0.0), Vec3(0.31, 0.7, -0.2), Vec3(0.0, 0.0, 1.7)}) {
    const Mesh m = merged(icosphere(3), icosphere(3, offset, 0.8));
    const Pairs expected = embree_pairs(m);
    EXPECT_GT(expected.size(), 10u);
    EXPECT_EQ(self_intersecting_pairs(m, kAll), expected);
    EXPECT_EQ(count_self_intersecting_pairs(m), expected.size());
  }
  // Smaller spheres: also against brute force.
  const Mesh m = merged(icosphere(2), icosphere(2, Vec3(0.5, 0.0, 0.0)));
  EXPECT_EQ(self_intersecting_pairs(m, kAll), brute_force_pairs(m));
}

TEST(TriangleIntersection, RandomSoupsOfVariedSizesMatchEmbree) {
  for (std::uint64_t seed = 1; seed <= 6; ++seed)
    for (bool grid : {false, true}) {
      const Mesh m = varied_soup(seed, 3000, grid);
      const Pairs expected = embree_pairs(m);
      EXPECT_GT(expected.size(), 1000u) << "seed " << seed;
      EXPECT_EQ(self_intersecting_pairs(m, kAll), expected) << "seed " << seed << (grid ? " grid" : "");
      EXPECT_EQ(count_self_intersecting_pairs(m), expected.size());
    }
}

TEST(TriangleIntersection, RandomSoupsMatchBruteForce) {
  for (std::uint64_t seed = 11; seed <= 12; ++seed)
    for (bool grid : {false, true}) {
      const Mesh m = varied_soup(seed, 800, grid);
      const Pairs expected = brute_force_pairs(m);
      EXPECT_GT(expected.size(), 10u);
      EXPECT_EQ(self_intersecting_pairs(m, kAll), expected) << "seed " << seed << (grid ? " grid" : "");
    }
}

// A 30 x 30 array of small upright triangles, each crossing the plane z = 0 (and apart from each
// other), with one huge triangle in that plane inserted at index `huge_at`.
Mesh huge_over_small(int huge_at) {
  Mesh m;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) {
      if (static_cast<int>(m.triangles.size()) == huge_at)
        add_triangle(m, Vec3(-1, -1, 0), Vec3(3, -1, 0), Vec3(-1, 3, 0));
      const double x = (i + 0.5) / 30.0, y = (j + 0.5) / 30.0;
      add_triangle(m, Vec3(x - 0.01, y, -0.01), Vec3(x + 0.01, y, -0.01), Vec3(x, y + 0.005, 0.01));
    }
  if (static_cast<int>(m.triangles.size()) == huge_at) add_triangle(m, Vec3(-1, -1, 0), Vec3(3, -1, 0), Vec3(-1, 3, 0));
  return m;
}

TEST(TriangleIntersection, OneHugeTriangleCrossingManySmallOnes) {
  for (int huge_at : {0, 450, 900}) {
    const Mesh m = huge_over_small(huge_at);
    Pairs expected;
    for (int f = 0; f <= 900; ++f)
      if (f != huge_at) expected.emplace_back(std::min(f, huge_at), std::max(f, huge_at));
    EXPECT_EQ(self_intersecting_pairs(m, kAll), expected) << huge_at;
    EXPECT_EQ(embree_pairs(m), expected);
    EXPECT_EQ(count_self_intersecting_pairs(m), 900u);
  }
  // Lifted by a hair above the small triangles' tops: no contact.
  Mesh m = huge_over_small(450);
  for (int k = 0; k < 3; ++k) m.positions[static_cast<std::size_t>(3 * 450 + k)].z() = std::nextafter(0.01, 1.0);
  EXPECT_EQ(count_self_intersecting_pairs(m), 0u);
  // Lowered to touch their top vertices exactly: every one touches.
  for (int k = 0; k < 3; ++k) m.positions[static_cast<std::size_t>(3 * 450 + k)].z() = 0.01;
  EXPECT_EQ(count_self_intersecting_pairs(m), 900u);
}

TEST(TriangleIntersection, ManyLargeTrianglesMatchBruteForce) {
  // More large triangles than the broad phase keeps out of the grid: the cell grows.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0), wide(-2.0, 3.0);
  Mesh m = varied_soup(21, 400, false);
  for (int k = 0; k < 80; ++k)
    add_triangle(m, Vec3(wide(rng), wide(rng), unit(rng)), Vec3(wide(rng), wide(rng), unit(rng)),
                 Vec3(wide(rng), wide(rng), unit(rng)));
  const Pairs expected = brute_force_pairs(m);
  EXPECT_GT(expected.size(), 1000u);
  EXPECT_EQ(self_intersecting_pairs(m, kAll), expected);
  EXPECT_EQ(embree_pairs(m), expected);
}

TEST(TriangleIntersection, TinyTrianglesFarApart) {
  // Cells sized from 1e-6 triangles over a 1e9 extent: the cell grows to keep coordinates small.
  Mesh m;
  for (double x : {0.0, 1e9})
    for (int k = 0; k < 2; ++k)
      add_triangle(m, Vec3(x, 0, 0), Vec3(x + 1e-6, k * 1e-7, 0), Vec3(x + 0.5e-6, 0.5e-6, 1e-7 - k * 2e-7));
  EXPECT_EQ(self_intersecting_pairs(m, kAll), embree_pairs(m));
  EXPECT_EQ(self_intersecting_pairs(m, kAll), brute_force_pairs(m));
}

TEST(TriangleIntersection, FirstPairsInOrderAndCount) {
  const Mesh m = merged(icosphere(3), icosphere(3, Vec3(0.5, 0.2, 0.1)));
  const Pairs all = self_intersecting_pairs(m, kAll);
  ASSERT_GT(all.size(), 20u);
  EXPECT_TRUE(std::is_sorted(all.begin(), all.end()));
  for (const auto& [f, g] : all) EXPECT_LT(f, g);
  EXPECT_EQ(self_intersecting_pairs(m), Pairs(all.begin(), all.begin() + 16));  // the default
  EXPECT_EQ(self_intersecting_pairs(m, 5), Pairs(all.begin(), all.begin() + 5));
  EXPECT_TRUE(self_intersecting_pairs(m, 0).empty());
  EXPECT_EQ(self_intersecting_pairs(m, all.size() + 10), all);
  EXPECT_EQ(count_self_intersecting_pairs(m), all.size());
  EXPECT_EQ(self_intersecting_pairs(m, kAll), all);  // deterministic
}

TEST(TriangleIntersection, DuplicateTrianglesCount) {
  Mesh m = regular_tetrahedron();
  m.triangles.push_back(m.triangles[0]);
  const auto t = m.triangles[1];
  m.triangles.push_back({t[0], t[2], t[1]});  // reversed
  EXPECT_EQ(self_intersecting_pairs(m), (Pairs{{0, 4}, {1, 5}}));
  // The same triangle under other indices at bit-identical positions.
  Mesh copy;
  add_triangle(copy, Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0));
  add_triangle(copy, Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 0));
  EXPECT_EQ(self_intersecting_pairs(copy), (Pairs{{0, 1}}));
}

TEST(TriangleIntersection, DegenerateTrianglesTakePartInNoPair) {
  // A zero-area needle through a face, a triangle with a repeated vertex, and a duplicated
  // degenerate triangle: none is reported (find_self_intersections counts them as skipped).
  Mesh m;
  m.positions = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(0.5, 0.5, -1), Vec3(0.5, 0.5, 1), Vec3(0.5, 0.5, 0)};
  m.triangles = {{0, 1, 2}, {3, 4, 5}, {0, 0, 4}, {3, 4, 5}};
  EXPECT_TRUE(self_intersecting_pairs(m, kAll).empty());
  EXPECT_EQ(find_self_intersections(m).degenerate_triangles, 3u);
  std::size_t degenerate = 0;
  const std::vector<Box> boxes = triangle_boxes_for_intersection(m, &degenerate);
  EXPECT_EQ(degenerate, 3u);
  EXPECT_TRUE((boxes[0].min.array() <= boxes[0].max.array()).all());
  EXPECT_TRUE((boxes[1].min.array() > boxes[1].max.array()).any());
  // The same needle one ulp off the line has area and crosses the face.
  m.positions[5].x() = std::nextafter(0.5, 1.0);
  EXPECT_EQ(self_intersecting_pairs(m, kAll), (Pairs{{0, 1}, {0, 3}, {1, 3}}));
}

TEST(TriangleIntersection, SharedVerticesAndEdgesFollowTheRules) {
  // A flat fold over a shared edge counts; an ordinary dihedral angle does not; the same point
  // under two indices is a shared vertex.
  Mesh fold;
  fold.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.3, 1, 0), Vec3(0.6, 0.5, 0), Vec3(0.5, -0.5, 0.5)};
  fold.triangles = {{0, 1, 2}, {1, 0, 3}, {1, 0, 4}};
  EXPECT_EQ(self_intersecting_pairs(fold), (Pairs{{0, 1}}));
  Mesh fan;
  fan.positions = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(0, 0, 0), Vec3(-1, 0, 1), Vec3(0, -1, 1)};
  fan.triangles = {{0, 1, 2}, {3, 4, 5}};
  EXPECT_TRUE(self_intersecting_pairs(fan).empty());
}

// apart_at_shared_vertex never calls apart two triangles that the exact test finds meeting
// beyond their shared vertex: pairs around a vertex at random (every shape, on the coordinate
// grid of 1/8 too, for touching and coplanar cases), and a corner a few units in the last place
// from the other triangle. It settles the pairs it is for: in fans of 5 to 9
// triangles around a vertex, flat or bent like a surface of curvature up to 2 per edge, every
// pair with a triangle between them.
TEST(TriangleIntersection, ApartAtSharedVertexIsNeverWrongAndSettlesFans) {
  std::mt19937_64 rng(20261127);
  std::uniform_real_distribution<double> sym(-1.0, 1.0), unit(0.0, 1.0);
  const auto meet = [](const Vec3& s, const Vec3& a1, const Vec3& a2, const Vec3& b1, const Vec3& b2) {
    return triangles_intersect({s, a1, a2}, {s, b1, b2});
  };
  const auto random_point = [&](bool grid) {
    Vec3 p(sym(rng), sym(rng), sym(rng));
    return grid ? Vec3((p * 8.0).array().round() / 8.0) : p;
  };
  int apart = 0, meeting = 0;
  for (int trial = 0; trial < 200000; ++trial) {
    const bool grid = trial % 2 == 1;
    const Vec3 s = random_point(grid), a1 = random_point(grid), a2 = random_point(grid), b1 = random_point(grid),
               b2 = random_point(grid);
    if (triangle_is_degenerate(s, a1, a2) || triangle_is_degenerate(s, b1, b2) || a1 == b1 || a1 == b2 ||
        a2 == b1 || a2 == b2)
      continue;
    const bool filtered = apart_at_shared_vertex(s, a1, a2, b1, b2);
    const bool met = meet(s, a1, a2, b1, b2);
    apart += filtered;
    meeting += met;
    if (filtered) {
      ASSERT_FALSE(met) << "trial " << trial;
    }
  }
  EXPECT_GT(apart, 10000);   // the random pairs it could settle
  EXPECT_GT(meeting, 10000);  // and the random pairs that meet, none of them settled
  // A corner of b within a few units in the last place of a's inside (b touches a at k = 0).
  for (int k = -4; k <= 4; ++k) {
    const Vec3 s(0.5, 0.25, 0.125), a1 = s + Vec3(1, 1, 0), a2 = s + Vec3(1, -1, 0);
    const Vec3 b1 = (s + a1 + a2) / 3 + Vec3(0, 0, k * std::numeric_limits<double>::epsilon()),
               b2 = s + Vec3(0.1, 0.2, -1);
    const bool met = meet(s, a1, a2, b1, b2);
    if (k == 0) {
      EXPECT_TRUE(met);
    }
    if (apart_at_shared_vertex(s, a1, a2, b1, b2)) {
      EXPECT_FALSE(met) << k;
    }
  }
  // Corners that are not finite decide nothing (and do not throw).
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(apart_at_shared_vertex(Vec3::Zero(), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(-1, 0, 0), Vec3(nan, 0, 0)));
  EXPECT_FALSE(apart_at_shared_vertex(Vec3::Zero(), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(-1, 0, 0), Vec3(-inf, 1, 0)));
  // Fans: triangles i and j with at least one triangle between them on both sides.
  for (int n = 5; n <= 9; ++n)
    for (const double bend : {0.0, 0.5, 2.0})
      for (int trial = 0; trial < 20; ++trial) {
        const Vec3 s(sym(rng), sym(rng), sym(rng));
        std::vector<Vec3> ring;
        double angle = 0;
        for (int k = 0; k < n; ++k) {
          angle = 2 * std::numbers::pi * (k + 0.3 * sym(rng)) / n;
          const double r = 0.7 + 0.6 * unit(rng);
          ring.push_back(s + Vec3(r * std::cos(angle), r * std::sin(angle), -0.5 * bend * r * r + 0.05 * sym(rng)));
        }
        for (int i = 0; i < n; ++i)
          for (int j = i + 2; j < n; ++j) {
            if ((j + 1) % n == i) continue;  // neighbours across the end of the ring
            const Vec3 &a1 = ring[i], &a2 = ring[(i + 1) % n], &b1 = ring[j], &b2 = ring[(j + 1) % n];
            EXPECT_FALSE(meet(s, a1, a2, b1, b2));
            EXPECT_TRUE(apart_at_shared_vertex(s, a1, a2, b1, b2)) << "n " << n << " bend " << bend << " i " << i << " j " << j;
          }
      }
}

// The check skips pairs that share a vertex whose star it has proved flat (a fan that projects
// one-to-one); every other pair is tested. On spheres whose vertices are moved by up to a fraction
// of an edge (small moves keep the stars flat, large ones fold some, and vertices pushed past
// their neighbours fold their stars over), the pairs are those of brute force.
TEST(TriangleIntersection, PerturbedSpheresMatchBruteForce) {
  std::size_t folded = 0;
  for (const double move : {0.02, 0.3, 1.0})
    for (const bool push : {false, true}) {
      Mesh m = icosphere(2);  // edges about 0.3 long
      std::mt19937_64 rng(static_cast<std::uint64_t>(move * 1000) + push);
      std::uniform_real_distribution<double> sym(-1.0, 1.0);
      for (Vec3& p : m.positions) p += 0.3 * move * Vec3(sym(rng), sym(rng), sym(rng));
      if (push)  // past its neighbours, along the sphere: the star folds over itself
        for (std::size_t v = 0; v < m.positions.size(); v += 17)
          m.positions[v] = (m.positions[v] + 0.45 * m.positions[v].cross(Vec3(0.6, 0.8, 0.0)).normalized()).normalized();
      const Pairs expected = brute_force_pairs(m);
      if (move == 0.02 && !push) {
        EXPECT_TRUE(expected.empty());
      }
      folded += expected.empty() ? 0 : 1;
      EXPECT_EQ(self_intersecting_pairs(m, kAll), expected) << "move " << move << (push ? " pushed" : "");
    }
  EXPECT_GE(folded, 4u);
}

// A star that winds twice around its vertex, rising as it goes: each triangle turns the same way
// and its triangles cover each direction twice, so it is not flat. Its last triangle comes back
// down through the first turn and meets (v, a_5, a_6) along a segment from v; the pair shares v
// and must still be tested.
TEST(TriangleIntersection, AStarWoundTwiceIsTested) {
  Mesh m;
  m.positions.push_back(Vec3::Zero());
  constexpr int kSides = 12;
  for (int i = 0; i < kSides; ++i) {
    const double angle = i * std::numbers::pi / 3.0;
    m.positions.push_back(Vec3(std::cos(angle), std::sin(angle), 0.1 * i));
  }
  for (int i = 0; i < kSides; ++i) m.triangles.push_back({0, 1 + i, 1 + (i + 1) % kSides});
  const Pairs expected = brute_force_pairs(m);
  EXPECT_NE(std::find(expected.begin(), expected.end(), std::pair<int, int>{5, 11}), expected.end());
  EXPECT_EQ(self_intersecting_pairs(m, kAll), expected);
  // Wound once, the same kind of star is flat and has no intersecting pair.
  Mesh once;
  once.positions.push_back(Vec3::Zero());
  for (int i = 0; i < 6; ++i) {
    const double angle = i * std::numbers::pi / 3.0;
    once.positions.push_back(Vec3(std::cos(angle), std::sin(angle), 0.1 * i));
  }
  for (int i = 0; i < 6; ++i) once.triangles.push_back({0, 1 + i, 1 + (i + 1) % 6});
  EXPECT_TRUE(self_intersecting_pairs(once, kAll).empty());
  EXPECT_TRUE(brute_force_pairs(once).empty());
  // Two flat fans pinched at one vertex, the second turned by 30 degrees in the same plane: each
  // closes on its own, the vertex's star is not one fan, and the fans overlap.
  Mesh pinched;
  pinched.positions.push_back(Vec3::Zero());
  for (const double turn : {0.0, 0.5})
    for (int i = 0; i < 6; ++i) {
      const double angle = (i + turn) * std::numbers::pi / 3.0;
      pinched.positions.push_back(Vec3(std::cos(angle), std::sin(angle), 0.0));
    }
  for (const int fan : {1, 7})
    for (int i = 0; i < 6; ++i) pinched.triangles.push_back({0, fan + i, fan + (i + 1) % 6});
  const Pairs overlaps = brute_force_pairs(pinched);
  EXPECT_GE(overlaps.size(), 12u);
  EXPECT_EQ(self_intersecting_pairs(pinched, kAll), overlaps);
}

TEST(TriangleIntersection, EmptyAndTinyMeshes) {
  EXPECT_TRUE(self_intersecting_pairs(Mesh{}).empty());
  EXPECT_EQ(count_self_intersecting_pairs(Mesh{}), 0u);
  Mesh one;
  add_triangle(one, Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0));
  EXPECT_TRUE(self_intersecting_pairs(one).empty());
}

TEST(TriangleIntersection, InvalidMeshesThrow) {
  Mesh m = regular_tetrahedron();
  m.triangles.push_back({0, 1, 4});
  EXPECT_THROW(self_intersecting_pairs(m), InvalidInputError);
  EXPECT_THROW(count_self_intersecting_pairs(m), InvalidInputError);
  m.triangles.back() = {0, -1, 2};
  EXPECT_THROW(self_intersecting_pairs(m), InvalidInputError);
  m = regular_tetrahedron();
  m.positions[2].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(self_intersecting_pairs(m), InvalidInputError);
  m.positions[2].y() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(count_self_intersecting_pairs(m), InvalidInputError);
  // An unused non-finite position is not an error.
  m = regular_tetrahedron();
  m.positions.push_back(Vec3::Constant(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_TRUE(self_intersecting_pairs(m).empty());
  EXPECT_THROW(triangles_intersect(m, 0, 0), InvalidInputError);
  EXPECT_THROW(triangles_intersect(m, 0, 4), InvalidInputError);
}

// The check restricted to pairs with an involved triangle finds exactly the full check's pairs
// that have one, on soups of varied sizes (the coarse grid that leaves the others out, the large
// triangles' loop) and on overlapping spheres (their flat stars certified in the part checked),
// with a share of the triangles involved from none to all, all of them or the smallest three.
TEST(TriangleIntersection, PairsInvolvingFlaggedTrianglesAreTheFullChecksWithOne) {
  // The last: two small overlapping spheres and a third far away, a grid of cells of two of their
  // edges too large to make (the cells grown until it is not).
  std::vector<Mesh> meshes{varied_soup(21, 3000, false), varied_soup(22, 3000, true),
                           merged(icosphere(3), icosphere(3, Vec3(0.31, 0.7, -0.2), 0.8)), huge_over_small(450),
                           merged(merged(icosphere(3, Vec3::Zero(), 1e-3), icosphere(3, Vec3(0.31, 0.7, -0.2) * 1e-3, 0.8e-3)),
                                  icosphere(1, Vec3(3, -2, 1), 1e-3))};
  std::mt19937_64 rng(5);
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    const Mesh& m = meshes[i];
    const Pairs all = self_intersecting_pairs(m, kAll);
    ASSERT_GT(all.size(), 10u) << i;
    for (const double share : {0.0, 0.02, 0.3, 1.0}) {
      std::vector<char> involved(m.triangles.size());
      std::bernoulli_distribution pick(share);
      for (auto& f : involved) f = pick(rng);
      Pairs expected;
      for (const auto& [f, g] : all)
        if (involved[static_cast<std::size_t>(f)] || involved[static_cast<std::size_t>(g)]) expected.push_back({f, g});
      EXPECT_EQ(self_intersecting_pairs_involving(m, involved, kAll, 2), expected) << "mesh " << i << " share " << share;
      // The smallest few, as the adaptive checks ask (the part checked is renumbered).
      if (expected.size() > 3) expected.resize(3);
      EXPECT_EQ(self_intersecting_pairs_involving(m, involved, 3, 1), expected) << "mesh " << i << " share " << share;
    }
  }
  EXPECT_THROW(self_intersecting_pairs_involving(meshes[0], std::vector<char>(3, 1)), InvalidInputError);
}

// Over 2 * 4096 triangles the checks' passes are cut in slices shared among the threads: the
// same pairs, counts and restricted pairs on any number of them.
TEST(TriangleIntersection, AMeshOfManySlicesHasTheSamePairsOnAnyNumberOfThreads) {
  const Mesh m = merged(icosphere(5), icosphere(5, Vec3(0.31, 0.7, -0.2), 0.8));  // 40,960 triangles
  const Pairs all = self_intersecting_pairs(m, kAll, 1);
  ASSERT_GT(all.size(), 100u);
  std::vector<char> involved(m.triangles.size());
  std::mt19937_64 rng(7);
  std::bernoulli_distribution pick(0.02);
  for (auto& f : involved) f = pick(rng);
  Pairs expected;
  for (const auto& [f, g] : all)
    if (involved[static_cast<std::size_t>(f)] || involved[static_cast<std::size_t>(g)]) expected.push_back({f, g});
  ASSERT_GT(expected.size(), 2u);
  ASSERT_LT(expected.size(), all.size());
  for (const int threads : {1, 2, 3, 8}) {
    EXPECT_EQ(self_intersecting_pairs(m, kAll, threads), all) << threads;
    EXPECT_EQ(count_self_intersecting_pairs(m, threads), all.size()) << threads;
    EXPECT_EQ(self_intersecting_pairs_involving(m, involved, kAll, threads), expected) << threads;
  }
}

// The error of a mesh with several faults is the one a single thread meets first, on any number:
// an index out of range before a position that is not finite, the lowest triangle's first.
TEST(TriangleIntersection, AMeshOfManySlicesNamesTheSameFaultOnAnyNumberOfThreads) {
  Mesh m = icosphere(6);  // 81,920 triangles
  m.positions[static_cast<std::size_t>(m.triangles[100][0])].x() = std::numeric_limits<double>::quiet_NaN();
  m.triangles[70000][1] = static_cast<int>(m.positions.size());
  const auto message = [&](int threads, bool involving) {
    try {
      if (involving)
        self_intersecting_pairs_involving(m, std::vector<char>(m.triangles.size(), 0), kAll, threads);
      else
        self_intersecting_pairs(m, kAll, threads);
    } catch (const InvalidInputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  for (const bool involving : {false, true})
    for (const int threads : {1, 2, 8}) {
      EXPECT_NE(message(threads, involving).find("a triangle index is out of range"), std::string::npos) << threads;
    }
  m.triangles[70000][1] = m.triangles[70000][0] == 0 ? 1 : 0;
  for (const int threads : {1, 2, 8})
    EXPECT_NE(message(threads, false).find("a vertex position is not finite"), std::string::npos) << threads;
}

}  // namespace
}  // namespace cdp
