// Checks <cdp/baselines/marching_cubes.h>: topology on closed surfaces of genus 0, 1 and 5 and on
// several components, for both traversals; area convergence; vertices on the surface; every
// cube case met by random fields closes up; errors.
#include "marching_checks.h"

#include <cdp/baselines/marching_cubes.h>

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

TEST(MarchingCubes, SphereIsOneClosedGenusZeroMeshFromBothTraversals) {
  const Sphere sphere({0.013, -0.021, 0.008}, 1.0);
  expect_topology_both_traversals(marching_cubes, sphere, 0.15, 1, 0);
}

TEST(MarchingCubes, TorusHasGenusOne) {
  const Torus torus({0.01, 0.02, -0.015}, 1.0, 0.4);
  expect_topology_both_traversals(marching_cubes, torus, 0.12, 1, 1);
}

TEST(MarchingCubes, TanglecubeHasGenusFive) {
  const auto tangle = test::tanglecube();
  expect_topology_both_traversals(marching_cubes, *tangle, 0.2, 1, 5);
}

TEST(MarchingCubes, SeparateBlobsGiveOneComponentEach) {
  const auto blobs = test::three_separate_blobs();
  expect_topology_both_traversals(marching_cubes, *blobs, 0.12, 3, 0);
}

TEST(MarchingCubes, NoDegenerateTrianglesWhereTheSurfacePassesThroughLatticeCorners) {
  {
    SCOPED_TRACE("three tori joined by min");
    expect_no_degenerate_triangles(marching_cubes, *test::field_from_json(test::kThreeTori), 0.05, 1, 3);
  }
  {
    SCOPED_TRACE("thin shell");  // F = 0 at lattice corners on both spheres
    expect_no_degenerate_triangles(marching_cubes, *test::field_from_json(test::kThinShell), 0.05, 2, 0);
  }
}

// Both sheets of the shell and every blob lie in one cluster of crossed seed-grid cells, whose
// single seed reaches one component only (issue 13: 1 of 2 on the shell).
TEST(MarchingCubes, ContinuationMeshesEveryComponentTheSeedsMiss) {
  {
    SCOPED_TRACE("thin shell");
    expect_continuation_finds_what_the_seeds_miss(marching_cubes, *test::field_from_json(test::kThinShell), 0.05, 2);
  }
  {
    SCOPED_TRACE("three blobs");
    expect_continuation_finds_what_the_seeds_miss(marching_cubes, *test::field_from_json(test::kCloseBlobs3), 0.1, 3);
  }
  {
    SCOPED_TRACE("two blobs");
    expect_continuation_finds_what_the_seeds_miss(marching_cubes, *test::field_from_json(test::kCloseBlobs2), 0.1, 2);
  }
}

TEST(MarchingCubes, EveryCaseOfRandomFieldsClosesUpUnderEveryAmbiguityRule) {
  std::size_t centre_vertices = 0;
  for (FaceAmbiguity rule : {FaceAmbiguity::AsymptoticDecider, FaceAmbiguity::JoinInside, FaceAmbiguity::SeparateInside})
    for (unsigned seed : {1u, 2u, 3u}) {
      SCOPED_TRACE(std::string(to_string(rule)) + " seed " + std::to_string(seed));
      const test::NoiseField noise(14, seed);
      MarchingOptions o = test::marching_options(1.0, Traversal::Grid);
      o.face_ambiguity = rule;
      const PolygonizeResult r = marching_cubes(noise, o);
      const MeshTopology t = analyze_topology(r.mesh);
      test::expect_closed_manifold(t);
      EXPECT_EQ(t.euler_characteristic, 2 * static_cast<int>(t.components) - 2 * t.genus);
      EXPECT_GT(t.components + t.genus, 5u);  // many pieces and handles: not a trivial test
      centre_vertices += r.stats.lattice->centre_vertices;
    }
  EXPECT_GT(centre_vertices, 0u);  // the polygons fanned around a centre vertex occur too
}

TEST(MarchingCubes, AreaConvergesOnSphereAndTorus) {
  const Sphere sphere({0.013, -0.021, 0.008}, 1.0);
  const auto s = test::area_errors(marching_cubes, sphere, 4 * std::numbers::pi, {0.4, 0.2, 0.1, 0.05});
  const Torus torus({0.01, 0.02, -0.015}, 1.0, 0.4);
  const auto t = test::area_errors(marching_cubes, torus, 4 * std::numbers::pi * std::numbers::pi * 0.4,
                                   {0.2, 0.1, 0.05});
  // Second order: halving the cell divides the error by about four (measured 3.4 to 4.6).
  for (const auto* e : {&s, &t})
    for (std::size_t i = 1; i < e->size(); ++i) EXPECT_GT((*e)[i - 1], 2.5 * (*e)[i]) << "cell step " << i;
  EXPECT_LT(s.back(), 1e-3);
  EXPECT_LT(t.back(), 1e-3);
}

TEST(MarchingCubes, VerticesLieOnTheSurfaceWithinTheRootTolerance) {
  // Signed distance fields: |F| is the distance to the surface, at most the distance along the
  // edge to the crossing.
  const Sphere sphere({0.013, -0.021, 0.008}, 1.0);
  const Torus torus({0.01, 0.02, -0.015}, 1.0, 0.4);
  for (const Field* f : {static_cast<const Field*>(&sphere), static_cast<const Field*>(&torus)})
    for (double tol : {1e-3, 1e-7}) {
      MarchingOptions o = test::marching_options(0.1, Traversal::Continuation);
      o.root_tolerance = tol;
      const PolygonizeResult r = marching_cubes(*f, o);
      double worst = 0;
      for (const Vec3& p : r.mesh.positions) worst = std::max(worst, std::abs(f->value(p)));
      EXPECT_LE(worst, tol * (1 + 1e-6)) << f->type_name();
      EXPECT_DOUBLE_EQ(r.stats.lattice->root_tolerance, tol);
    }
}

TEST(MarchingCubes, NormalsPointOutward) {
  const Sphere sphere(Vec3::Zero(), 1.0);
  const PolygonizeResult r = marching_cubes(sphere, test::marching_options(0.2, Traversal::Continuation));
  for (std::size_t v = 0; v < r.mesh.num_vertices(); ++v)
    EXPECT_GT(r.mesh.normals[v].dot(r.mesh.positions[v].normalized()), 0.999);
}

TEST(MarchingCubes, ContinuationEvaluatesOnlyNearTheSurfaceAndIsDeterministic) {
  const Sphere sphere({0.013, -0.021, 0.008}, 1.0);
  const PolygonizeResult cont = marching_cubes(sphere, test::marching_options(0.02, Traversal::Continuation));
  const PolygonizeResult grid = marching_cubes(sphere, test::marching_options(0.02, Traversal::Grid));
  // 111^3 lattice corners against a shell of cubes one cell thick: many times fewer.
  // Root searches cost the same in both (same crossed edges); the lattice corners do not.
  const auto corners = [](const PolygonizeResult& r) { return r.stats.lattice->corner_evaluations; };
  EXPECT_LT(corners(cont) * 10, corners(grid));
  EXPECT_LT(cont.stats.field_evaluations.value, grid.stats.field_evaluations.value);
  EXPECT_EQ(cont.stats.lattice->root_evaluations, grid.stats.lattice->root_evaluations);
  EXPECT_GT(cont.stats.field_evaluations.value_gradient, 0u);  // normals
  EXPECT_EQ(cont.stats.method, "mc");
  EXPECT_EQ(cont.stats.lattice->traversal, "continuation");
  EXPECT_EQ(grid.stats.lattice->traversal, "grid");
  const PolygonizeResult again = marching_cubes(sphere, test::marching_options(0.02, Traversal::Continuation));
  EXPECT_EQ(again.mesh.positions, cont.mesh.positions);
  EXPECT_EQ(again.mesh.triangles, cont.mesh.triangles);
}

// A sphere of radius 0.06 around a seed-grid node (cell 0.125) falls between the corners of a
// lattice of cell 0.35: the six grid edges around that node change sign, and no cube of the
// lattice is crossed near them. The mesh cannot hold it; the statistics say so.
TEST(MarchingCubes, ContinuationReportsSignChangesTheLatticeCannotReach) {
  const auto field = test::field_from_json(
      R"json({"type": "expression", "value": "min(sqrt(x^2+y^2+z^2)-1, sqrt((x-1.625)^2+(y-1.625)^2+(z-1.625)^2)-0.06)",
              "bounds": [[-2, -2, -2], [2, 2, 2]]})json");
  const PolygonizeResult r = marching_cubes(*field, test::marching_options(0.35, Traversal::Continuation));
  EXPECT_EQ(r.stats.components, 1u);
  EXPECT_EQ(r.stats.lattice->seeding->unreached_sign_changes, 6u);
  EXPECT_EQ(r.stats.lattice->seeding->completion_starts, 0u);
}

// A sphere of radius h/250 around a lattice corner: Marching Cubes cuts an octahedron with
// edges of h/180 around the corner, too small for any triangle of the collapse length; it is
// removed, and counted.
TEST(MarchingCubes, PiecesBelowTheCollapseLengthAreDroppedAndCounted) {
  const auto field = test::field_from_json(
      R"json({"type": "expression", "value": "min(sqrt(x^2+y^2+z^2)-1, sqrt((x-1.5)^2+(y-1.5)^2+(z-1.5)^2)-0.0005)",
              "bounds": [[-2, -2, -2], [2, 2, 2]]})json");
  for (Traversal tr : {Traversal::Continuation, Traversal::Grid}) {
    SCOPED_TRACE(to_string(tr));
    const PolygonizeResult r = marching_cubes(*field, test::marching_options(0.125, tr));
    const MeshTopology t = analyze_topology(r.mesh);
    test::expect_closed_manifold(t);
    EXPECT_EQ(t.components, 1u);
    EXPECT_EQ(r.stats.components, 1u);
    EXPECT_EQ(r.stats.lattice->dropped_components, 1u);
  }
}

TEST(MarchingCubes, PrecisionNeedsAVariationalModel) {
  const Sphere sphere(Vec3::Zero(), 1.0);
  MarchingOptions o;
  o.precision = 2;
  try {
    marching_cubes(sphere, o);
    FAIL() << "expected InvalidInputError";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("--precision needs a variational (data-driven) model"), std::string::npos)
        << e.what();
  }
}

TEST(MarchingCubes, SurfaceLeavingTheBoxIsAnErrorUnlessClippingIsAsked) {
  Sphere sphere(Vec3::Zero(), 1.0);
  sphere.set_bounds({Vec3(-1.2, -1.2, -1.2), Vec3(1.2, 1.2, 0.5)});
  for (Traversal tr : {Traversal::Continuation, Traversal::Grid})
    EXPECT_THROW(marching_cubes(sphere, test::marching_options(0.2, tr)), NoSurfaceError);
  MarchingOptions o = test::marching_options(0.2, Traversal::Grid);
  o.require_closed_in_box = false;
  const PolygonizeResult r = marching_cubes(sphere, o);
  EXPECT_GT(analyze_topology(r.mesh).boundary_edges, 0u);
  EXPECT_GT(r.stats.lattice->open_boundary_faces.value(), 0u);
}

TEST(MarchingCubes, ProgressRisesToOne) {
  const Sphere sphere({0.013, -0.021, 0.008}, 1.0);
  for (Traversal tr : {Traversal::Continuation, Traversal::Grid}) {
    std::vector<double> seen;
    MarchingOptions o = test::marching_options(0.03, tr);
    o.progress = [&](double f) { seen.push_back(f); };
    marching_cubes(sphere, o);
    ASSERT_GE(seen.size(), 2u) << to_string(tr);
    for (std::size_t i = 1; i < seen.size(); ++i) EXPECT_GE(seen[i], seen[i - 1]);
    EXPECT_GE(seen.front(), 0.0);
    EXPECT_EQ(seen.back(), 1.0);
  }
}

TEST(MarchingCubes, NonFiniteFieldIsAnError) {
  const auto nan_field = test::field_from_json(
      R"({"type": "expression", "value": "sqrt(x^2 + y^2 + z^2 - 0.25) - 0.5", "bounds": [[-1, -1, -1], [1, 1, 1]]})");
  EXPECT_THROW(marching_cubes(*nan_field, test::marching_options(0.1, Traversal::Grid)), NoSurfaceError);
}

TEST(MarchingCubes, BoundsAreEnforced) {
  const Sphere sphere(Vec3::Zero(), 1.0);
  MarchingOptions o = test::marching_options(0.05, Traversal::Grid);
  o.max_cubes = 1000;
  EXPECT_THROW(marching_cubes(sphere, o), LimitExceededError);
  o.traversal = Traversal::Continuation;
  EXPECT_THROW(marching_cubes(sphere, o), LimitExceededError);
  o = test::marching_options(0.05, Traversal::Continuation);
  o.max_triangles = 100;
  EXPECT_THROW(marching_cubes(sphere, o), LimitExceededError);
  EXPECT_THROW(marching_cubes(sphere, test::marching_options(-1, Traversal::Grid)), InvalidInputError);
}

}  // namespace
}  // namespace cdp
