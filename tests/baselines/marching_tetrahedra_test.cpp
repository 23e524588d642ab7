// Checks <cdp/baselines/marching_tetrahedra.h>: the same closedness, topology, convergence and
// accuracy requirements as Marching Cubes.
#include "marching_checks.h"

#include <cdp/baselines/marching_tetrahedra.h>

#include <cdp/core/errors.h>
#include <cdp/core/models/analytic.h>

#include <common/test_fields.h>

#include <gtest/gtest.h>

#include <numbers>

namespace cdp {
namespace {

using test::expect_continuation_finds_what_the_seeds_miss;
using test::expect_no_degenerate_triangles;
using test::expect_topology_both_traversals;

TEST(MarchingTetrahedra, SphereIsOneClosedGenusZeroMeshFromBothTraversals) {
  const Sphere sphere({0.013, -0.021, 0.008}, 1.0);
  expect_topology_both_traversals(marching_tetrahedra, sphere, 0.15, 1, 0);
}

TEST(MarchingTetrahedra, TorusHasGenusOne) {
  const Torus torus({0.01, 0.02, -0.015}, 1.0, 0.4);
  expect_topology_both_traversals(marching_tetrahedra, torus, 0.12, 1, 1);
}

TEST(MarchingTetrahedra, TanglecubeHasGenusFive) {
  const auto tangle = test::tanglecube();
  expect_topology_both_traversals(marching_tetrahedra, *tangle, 0.2, 1, 5);
}

TEST(MarchingTetrahedra, SeparateBlobsGiveOneComponentEach) {
  const auto blobs = test::three_separate_blobs();
  expect_topology_both_traversals(marching_tetrahedra, *blobs, 0.12, 3, 0);
}

TEST(MarchingTetrahedra, NoDegenerateTrianglesWhereTheSurfacePassesThroughLatticeCorners) {
  {
    SCOPED_TRACE("three tori joined by min");
    expect_no_degenerate_triangles(marching_tetrahedra, *test::field_from_json(test::kThreeTori), 0.05, 1, 3);
  }
  {
    SCOPED_TRACE("thin shell");  // F = 0 at lattice corners on both spheres
    expect_no_degenerate_triangles(marching_tetrahedra, *test::field_from_json(test::kThinShell), 0.05, 2, 0);
  }
}

// Both sheets of the shell and every blob lie in one cluster of crossed seed-grid cells, whose
// single seed reaches one component only (issue 13: 1 of 2 on the shell).
TEST(MarchingTetrahedra, ContinuationMeshesEveryComponentTheSeedsMiss) {
  {
    SCOPED_TRACE("thin shell");
    expect_continuation_finds_what_the_seeds_miss(marching_tetrahedra, *test::field_from_json(test::kThinShell), 0.05, 2);
  }
  {
    SCOPED_TRACE("three blobs");
    expect_continuation_finds_what_the_seeds_miss(marching_tetrahedra, *test::field_from_json(test::kCloseBlobs3), 0.1, 3);
  }
  {
    SCOPED_TRACE("two blobs");
    expect_continuation_finds_what_the_seeds_miss(marching_tetrahedra, *test::field_from_json(test::kCloseBlobs2), 0.1, 2);
  }
}

TEST(MarchingTetrahedra, RandomFieldsGiveClosedManifoldMeshes) {
  for (unsigned seed : {1u, 2u, 3u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const test::NoiseField noise(14, seed);
    const PolygonizeResult r = marching_tetrahedra(noise, test::marching_options(1.0, Traversal::Grid));
    const MeshTopology t = analyze_topology(r.mesh);
    test::expect_closed_manifold(t);
    EXPECT_EQ(t.euler_characteristic, 2 * static_cast<int>(t.components) - 2 * t.genus);
    EXPECT_GT(t.components + t.genus, 5u);
  }
}

TEST(MarchingTetrahedra, AreaConvergesOnSphereAndTorus) {
  const Sphere sphere({0.013, -0.021, 0.008}, 1.0);
  const auto s = test::area_errors(marching_tetrahedra, sphere, 4 * std::numbers::pi, {0.4, 0.2, 0.1, 0.05});
  const Torus torus({0.01, 0.02, -0.015}, 1.0, 0.4);
  const auto t = test::area_errors(marching_tetrahedra, torus, 4 * std::numbers::pi * std::numbers::pi * 0.4,
                                   {0.2, 0.1, 0.05});
  // Second order: halving the cell divides the error by about four (measured 3.4 to 4.6).
  for (const auto* e : {&s, &t})
    for (std::size_t i = 1; i < e->size(); ++i) EXPECT_GT((*e)[i - 1], 2.5 * (*e)[i]) << "cell step " << i;
  EXPECT_LT(s.back(), 5e-4);
  EXPECT_LT(t.back(), 5e-4);
}

TEST(MarchingTetrahedra, VerticesLieOnTheSurfaceWithinTheRootTolerance) {
  const Torus torus({0.01, 0.02, -0.015}, 1.0, 0.4);
  for (double tol : {1e-3, 1e-7}) {
    MarchingOptions o = test::marching_options(0.1, Traversal::Grid);
    o.root_tolerance = tol;
    const PolygonizeResult r = marching_tetrahedra(torus, o);
    double worst = 0;
    for (const Vec3& p : r.mesh.positions) worst = std::max(worst, std::abs(torus.value(p)));
    EXPECT_LE(worst, tol * (1 + 1e-6));
  }
}

TEST(MarchingTetrahedra, ContinuationEvaluatesOnlyNearTheSurface) {
  const Sphere sphere({0.013, -0.021, 0.008}, 1.0);
  const PolygonizeResult cont = marching_tetrahedra(sphere, test::marching_options(0.02, Traversal::Continuation));
  const PolygonizeResult grid = marching_tetrahedra(sphere, test::marching_options(0.02, Traversal::Grid));
  // Root searches cost the same in both (same crossed edges); the lattice corners do not.
  const auto corners = [](const PolygonizeResult& r) { return r.stats.lattice->corner_evaluations; };
  EXPECT_LT(corners(cont) * 10, corners(grid));
  EXPECT_LT(cont.stats.field_evaluations.value, grid.stats.field_evaluations.value);
  EXPECT_EQ(cont.stats.lattice->root_evaluations, grid.stats.lattice->root_evaluations);
  EXPECT_EQ(cont.stats.method, "mt");
  // More triangles than Marching Cubes on the same lattice: each cube is cut six times.
  EXPECT_GT(cont.stats.triangles, 0u);
}

TEST(MarchingTetrahedra, PrecisionNeedsAVariationalModel) {
  const Sphere sphere(Vec3::Zero(), 1.0);
  MarchingOptions o;
  o.precision = 0;
  try {
    marching_tetrahedra(sphere, o);
    FAIL() << "expected InvalidInputError";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("--precision needs a variational (data-driven) model"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace cdp
