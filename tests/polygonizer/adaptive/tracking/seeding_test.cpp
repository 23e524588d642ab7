// The seeding guarantee of the adaptive polygonizer (polygonizer/src/adaptive/seeding.h): every
// component meshed, none twice, and the stats that say so. Each case here lost or doubled
// surface before coverage replaced proximity and the small-component search existed.
#include <gtest/gtest.h>

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/errors.h>
#include <cdp/core/mesh_topology.h>
#include <cdp/core/models/volume.h>

#include <iomanip>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "common/test_fields.h"
#include "polygonizer/mesh_checks.h"

namespace cdp {
namespace {

AdaptiveOptions at_factor(double factor, int seed_resolution = 32) {
  AdaptiveOptions o;
  o.factor = factor;
  o.seed_resolution = seed_resolution;
  return o;
}

// A closed, oriented, manifold, outward mesh without self-intersections, with the expected
// components (each of the expected genus in total) and seeding stats that agree.
void expect_components(const Field& field, const AdaptiveOptions& o, std::size_t components, int genus,
                       const std::string& what) {
  SCOPED_TRACE(what);
  const PolygonizeResult r = polygonize_adaptive(field, o);
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_TRUE(t.watertight()) << t.boundary_edges << " boundary, " << t.nonmanifold_edges << " non-manifold edges, "
                              << t.misoriented_edges << " misoriented, volume " << t.signed_volume;
  EXPECT_EQ(t.components, components);
  EXPECT_EQ(t.genus, genus);
  EXPECT_EQ(test::count_self_intersections(r.mesh), 0u);
  EXPECT_EQ(r.stats.components, components);
  EXPECT_EQ(r.stats.adaptive->seeding.uncovered, 0u);
  EXPECT_EQ(r.stats.adaptive->seeding.seeds, components);
}

TEST(AdaptiveSeeding, HollowSphereKeepsItsInnerSphereAtEveryFactor) {
  // The inner sphere's crossings lie within reach of outer vertices at coarse factors; they are
  // meshed only if coverage, not proximity, decides.
  const auto f = test::field_from_json(R"J({"type": "expression",
      "value": "max(sqrt(x^2+y^2+z^2)-1.25, 0.75-sqrt(x^2+y^2+z^2))", "bounds": [[-2,-2,-2],[2,2,2]]})J");
  for (double k : {1.0, 2.0, 3.0, 5.0}) expect_components(*f, at_factor(k), 2, 0, "factor " + std::to_string(k));
  expect_components(*f, at_factor(2, 200), 2, 0, "seed resolution 200");
}

TEST(AdaptiveSeeding, OffCentreCavityAndAThinShell) {
  const auto cavity = test::field_from_json(R"J({"type": "expression",
      "value": "max(sqrt(x^2+y^2+z^2)-1.25, 0.5-sqrt((x-0.4)^2+y^2+z^2))", "bounds": [[-2,-2,-2],[2,2,2]]})J");
  const auto shell = test::field_from_json(R"J({"type": "expression",
      "value": "abs(sqrt(x^2+y^2+z^2)-1)-0.1", "bounds": [[-1.5,-1.5,-1.5],[1.5,1.5,1.5]]})J");
  for (double k : {1.0, 3.0}) {
    expect_components(*cavity, at_factor(k), 2, 0, "cavity, factor " + std::to_string(k));
    expect_components(*shell, at_factor(k), 2, 0, "shell, factor " + std::to_string(k));
  }
}

// `count` Wyvill blobs of radius 0.1 (surface radius about 0.063) at random in a 10-unit box.
std::unique_ptr<Blobs> tiny_blobs(int count) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-4.5, 4.5);
  std::vector<Blob> blobs;
  for (int i = 0; i < count; ++i) blobs.push_back({Vec3(u(rng), u(rng), u(rng)), 0.1, 1.0});
  auto field = std::make_unique<Blobs>(BlobKernel::Wyvill, 0.3, blobs);
  field->set_bounds({Vec3::Constant(-5), Vec3::Constant(5)});
  return field;
}

TEST(AdaptiveSeeding, FiftyTinyBlobsComeOutWholeEachOnce) {
  // Far below the seed grid's cell of 0.31: found by refining the cells the blobs' value range
  // does not prove empty.
  const auto field = tiny_blobs(50);
  for (double k : {1.0, 3.0}) expect_components(*field, at_factor(k), 50, 0, "factor " + std::to_string(k));
}

TEST(AdaptiveSeeding, ThinTorusAndNeedleAreFound) {
  // No grid node lies inside either: every sample is positive.
  // (At factor 1 the tracker itself, not the seeding, still runs away on this torus; see the
  // known limits in docs/adaptive_polygonizer.md.)
  Torus thin(Vec3::Zero(), 1.0, 0.01);
  for (double k : {2.0, 3.0}) expect_components(thin, at_factor(k), 1, 1, "thin torus, factor " + std::to_string(k));
  // The needle's tips are finer than min_edge: the mesh stops short of them, and the sign
  // changes there count as detail of the meshed component, not as new components.
  Ellipsoid needle(Vec3::Zero(), Vec3(5, 0.05, 0.05));
  for (int res : {32, 200}) {
    expect_components(needle, at_factor(3, res), 1, 0, "needle, seed resolution " + std::to_string(res));
  }
}

TEST(AdaptiveSeeding, NothingIsMeshedTwice) {
  // Two spheres 1e-3 apart: two components, not one merged and not three.
  const auto spheres = test::field_from_json(R"J({"type": "expression",
      "value": "min(sqrt((x-1.0005)^2+y^2+z^2)-1, sqrt((x+1.0005)^2+y^2+z^2)-1)",
      "bounds": [[-2.5,-2.5,-2.5],[2.5,2.5,2.5]]})J");
  for (double k : {2.0, 3.0}) expect_components(*spheres, at_factor(k), 2, 0, "two spheres, factor " + std::to_string(k));
  // Chmutov's quartic at factor 1: a coarse mesh whose chords miss half the grid's sign changes;
  // they must count as meshed, not start a second, overlapping copy.
  const auto chmutov = test::field_from_json(R"J({"type": "expression",
      "value": "(8*x^4-8*x^2+1)+(8*y^4-8*y^2+1)+(8*z^4-8*z^2+1)", "bounds": [[-1.3,-1.3,-1.3],[1.3,1.3,1.3]]})J");
  expect_components(*chmutov, at_factor(1), 1, 5, "Chmutov quartic, factor 1");
  const auto r = polygonize_adaptive(*chmutov, at_factor(1));
  EXPECT_GT(r.stats.adaptive->seeding.covered_nearby, 0u);
}

TEST(AdaptiveSeeding, ReportsWhatTheSearchDid) {
  Torus thin(Vec3::Zero(), 1.0, 0.01);
  const auto r = polygonize_adaptive(thin, at_factor(2));
  EXPECT_GT(r.stats.adaptive->seeding.refined_cells, 0u);
  EXPECT_GT(r.stats.adaptive->seeding.sign_changes, 0u);
  EXPECT_EQ(r.stats.adaptive->seeding.probes, 0u);  // a bound exists: no probes
  // Expressions have no bound: the local minima of |F| are probed instead.
  const auto f = test::field_from_json(R"J({"type": "expression", "value": "x^2+y^2+z^2-1",
      "bounds": [[-2,-2,-2],[2,2,2]]})J");
  const auto e = polygonize_adaptive(*f, at_factor(2));
  EXPECT_EQ(e.stats.adaptive->seeding.refined_cells, 0u);
}

TEST(AdaptiveSeeding, SmallBlobWithoutABoundIsFoundByAProbe) {
  // An expression (no Lipschitz bound) with a ball of radius 0.05 between the nodes of a grid of
  // cell 0.125: no node is inside it, and the grid node nearest it is a local minimum of |F|.
  const auto f = test::field_from_json(R"J({"type": "expression",
      "value": "min(sqrt(x^2+y^2+z^2)-1, sqrt((x-1.55)^2+(y-1.55)^2+(z-1.55)^2)-0.05)",
      "bounds": [[-2,-2,-2],[2,2,2]]})J");
  expect_components(*f, at_factor(2), 2, 0, "sphere and a small ball");
  const auto r = polygonize_adaptive(*f, at_factor(2));
  EXPECT_GT(r.stats.adaptive->seeding.probes, 0u);
}

TEST(AdaptiveSeeding, ABeadBesideTheSurfaceIsFoundByABandProbe) {
  // Balls of radius 0.02-0.025 (2-3 min_edge) 0.02-0.03 from a sphere, under it (a void) and
  // beside a box's face, between the nodes of a grid of cell 0.0875 in cells the big surface
  // crosses or borders: no grid edge crosses them and no node around them is a local minimum of
  // |F| (the big surface's sign change is next to them). The level sets curl around them, and
  // Newton from those nodes lands on them. Without those probes each meshed one component, exit 0.
  const auto expression_in_box = [](const std::string& value) {
    return test::field_from_json(R"J({"type": "expression", "value": ")J" + value +
                                 R"J(", "bounds": [[-1.4,-1.4,-1.4],[1.4,1.4,1.4]]})J");
  };
  const auto bead = expression_in_box("min(sqrt(x^2+y^2+z^2)-1, sqrt((x-1.04)^2+(y-0.013)^2+(z-0.007)^2)-0.02)");
  expect_components(*bead, at_factor(1), 2, 0, "a bead by a sphere");
  const auto void_under =
      expression_in_box("max(sqrt(x^2+y^2+z^2)-1, 0.02-sqrt((x-0.95)^2+(y-0.013)^2+(z-0.007)^2))");
  for (const double k : {3.0, 6.0}) expect_components(*void_under, at_factor(k), 2, 0, "a void under a sphere");
  // The crease patches mesh the box, not a seed: one seed, the bead's.
  const auto by_box =
      expression_in_box("min(max(max(abs(x),abs(y)),abs(z))-0.8, sqrt((x-0.85)^2+(y-0.31)^2+(z+0.17)^2)-0.025)");
  for (const double k : {1.0, 3.0, 6.0}) {
    SCOPED_TRACE(k);
    const PolygonizeResult r = polygonize_adaptive(*by_box, at_factor(k));
    const MeshTopology t = analyze_topology(r.mesh);
    EXPECT_TRUE(t.watertight());
    EXPECT_EQ(t.components, 2u);
    EXPECT_EQ(t.genus, 0);
    EXPECT_EQ(test::count_self_intersections(r.mesh), 0u);
    EXPECT_TRUE(r.stats.adaptive->creases.followed);
    EXPECT_EQ(r.stats.adaptive->seeding.seeds, 1u);
    EXPECT_GT(r.stats.adaptive->seeding.probes, 0u);
  }
}

TEST(AdaptiveSeeding, ABeadBesideABoxFaceIsNotTakenForTheFace) {
  // A ball of radius 0.032 centred 0.09 beside a box's face, level with its edge (bounds 1.6, a
  // grid cell of 0.1, min_edge 0.011), crossing no grid edge: a band probe lands on it, and it was
  // taken for meshed: the segment from it to the nearest triangle of the face runs through air
  // all the way, so F kept the sign it has at that triangle, which lies on the flat face (F = 0
  // there, counted as outside). A triangle on the surface has no side of its own now. Of 120
  // beads placed at random beside a sphere, a box and a torus and voids under a sphere, 15 of the
  // 16 the probes missed or a spike hid (AFrontIsNotProjectedOntoABeadBesideIt) were lost so.
  const auto f = test::field_from_json(R"J({"type": "expression",
      "value": "min(max(max(abs(x),abs(y)),abs(z))-0.8, sqrt((x+0.8905453)^2+(y+0.3639723)^2+(z+0.8)^2)-0.0321124)",
      "bounds": [[-1.6,-1.6,-1.6],[1.6,1.6,1.6]]})J");
  const PolygonizeResult r = polygonize_adaptive(*f, at_factor(3));
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.components, 2u);
  EXPECT_EQ(t.genus, 0);
  EXPECT_EQ(test::count_self_intersections(r.mesh), 0u);
  EXPECT_GT(r.stats.adaptive->seeding.probes, 0u);
}

TEST(AdaptiveSeeding, AComponentWhollyOutsideTheBoxIsNotSeeded) {
  // Balls of radius 0.25 repeated every 0.75 (x - 0.75 round(x / 0.75), as numpy code repeats a
  // shape), in a box of +-1.2: 27 balls inside, and the next ones centred at +-1.5, 0.05 beyond the
  // faces. Probes from the local minima of F on the faces followed F out of the box onto those and
  // seeded them: 81 components, where Marching Cubes on the same box finds 27.
  const auto f = test::field_from_json(R"J({"type": "expression",
      "value": "sqrt(u*u + v*v + w*w) - 0.25",
      "define": {"u": "x - 0.75*round(x/0.75)", "v": "y - 0.75*round(y/0.75)", "w": "z - 0.75*round(z/0.75)"},
      "bounds": [[-1.2,-1.2,-1.2],[1.2,1.2,1.2]]})J");
  const PolygonizeResult r = polygonize_adaptive(*f, at_factor(3));
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.components, 27u);
  EXPECT_GT(r.stats.adaptive->seeding.probes_outside, 0u);
  const Box box = f->bounds();
  for (const Vec3& p : r.mesh.positions) EXPECT_TRUE(box.contains(p)) << p.transpose();
}

TEST(AdaptiveSeeding, AFrontIsNotProjectedOntoABeadBesideIt) {
  // A ball of radius 0.025 0.028 outside a unit sphere, meshed at factor 3 (edges 0.33): a new
  // point placed in the sphere's tangent plane lies nearer the bead than the sphere, and Newton
  // took it there, its normal 69 degrees from the sphere's, inside the 75 the turn bound allows.
  // The sphere's mesh then had a vertex on the bead, which hid the bead from the seeding: one
  // component, exit 0 (now the band's split finds the bead beside the spike, the checks fail and
  // the careful recovery meshes it again, in twice the time). Such a landing, curved eight times
  // more tightly than the step, turned more than twice what the origin's curvature explains and
  // not reached by two half steps, is placed again at half the length, in the first run.
  const Vec3 c(-0.6875192721464114, 0.7960579411949409, -0.050528023662846415);
  const double radius = 0.02539741726939058;
  std::ostringstream value;
  value << std::setprecision(17) << "min(sqrt(x^2+y^2+z^2)-1, sqrt((x-(" << c.x() << "))^2+(y-(" << c.y() << "))^2+(z-(" << c.z()
        << "))^2)-" << radius << ")";
  const auto f = test::field_from_json(R"J({"type": "expression", "value": ")J" + value.str() +
                                       R"J(", "bounds": [[-1.4,-1.4,-1.4],[1.4,1.4,1.4]]})J");
  const PolygonizeResult r = polygonize_adaptive(*f, at_factor(3));
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.components, 2u);
  // Every triangle lies on one of the two spheres.
  const auto on_bead = [&](int v) { return std::abs((r.mesh.positions[v] - c).norm() - radius) < 1e-6; };
  std::size_t mixed = 0;
  for (const auto& tri : r.mesh.triangles)
    if (on_bead(tri[0]) != on_bead(tri[1]) || on_bead(tri[0]) != on_bead(tri[2])) ++mixed;
  EXPECT_EQ(mixed, 0u);
  EXPECT_GT(r.stats.adaptive->tracker.sheet_jumps, 0u);
  EXPECT_FALSE(r.stats.adaptive->recoveries.remeshed_carefully);
}

TEST(AdaptiveSeeding, SameMeshBitForBitWithTheSearch) {
  const auto field = tiny_blobs(20);
  const auto a = polygonize_adaptive(*field, at_factor(2));
  const auto b = polygonize_adaptive(*field, at_factor(2));
  ASSERT_EQ(a.mesh.triangles, b.mesh.triangles);
  ASSERT_EQ(a.mesh.positions, b.mesh.positions);
}

TEST(AdaptiveSeeding, NaNAwayFromTheSurfaceCountsAsOutside) {
  // sqrt(1.6 - x) is NaN beyond x = 1.6, far from the unit sphere: those nodes are outside (and
  // counted); the sphere is meshed as if they were positive. Two spheres, one of them within
  // reach of the undefined part, are both meshed.
  const auto f = test::field_from_json(R"J({"type": "expression",
      "value": "sqrt(x^2+y^2+z^2) - 1 + 0*sqrt(1.6 - x)", "bounds": [[-2,-2,-2],[2,2,2]]})J");
  expect_components(*f, at_factor(3), 1, 0, "one sphere");
  const PolygonizeResult r = polygonize_adaptive(*f, at_factor(3));
  EXPECT_GT(r.stats.adaptive->seeding.non_finite_samples, 0u);
  const auto g = test::field_from_json(R"J({"type": "expression",
      "value": "min(sqrt(x^2+y^2+z^2) - 1, sqrt((x-1.6)^2+y^2+z^2) - 0.2) + 0*sqrt(1.95 - x)",
      "bounds": [[-2,-2,-2],[2,2,2]]})J");
  expect_components(*g, at_factor(3), 2, 0, "two spheres");
}

TEST(AdaptiveSeeding, NaNNextToTheInsideIsAnError) {
  // The solid reaches where F is undefined: the surface may pass there.
  const auto f = test::field_from_json(R"J({"type": "expression",
      "value": "sqrt(x^2+y^2+z^2) - 1 + 0*sqrt(0.5 - x)", "bounds": [[-2,-2,-2],[2,2,2]]})J");
  try {
    polygonize_adaptive(*f, at_factor(3));
    FAIL() << "no error";
  } catch (const NoSurfaceError& e) {
    EXPECT_NE(std::string(e.what()).find("not finite (nan) at"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("next to the inside"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cdp

namespace cdp {
namespace {

// A sphere's distance sampled on n^3 nodes over [-1, 1]^3 plus uniform noise of +-amplitude
// (from mt19937's raw output, the same on every platform), the two outer layers outside.
VolumeSamples noisy_sphere(std::size_t n, double amplitude) {
  VolumeSamples s;
  s.dims = {n, n, n};
  s.origin = Vec3::Constant(-1);
  s.spacing = Vec3::Constant(2.0 / static_cast<double>(n - 1));
  std::mt19937 rng(4);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t k = 0; k < n; ++k) {
        const Vec3 p = s.origin + s.spacing.cwiseProduct(Vec3(double(i), double(j), double(k)));
        const double noise = amplitude * (2.0 * static_cast<double>(rng()) / 4294967296.0 - 1.0);
        const auto edge = [&](std::size_t m) { return m < 2 || m + 2 >= n; };
        s.values.push_back(edge(i) || edge(j) || edge(k) ? 1.0 : p.norm() - 0.6 + noise);
      }
  return s;
}

// The noise's interpolant has bubbles far smaller than the seed grid's cells, and its value and
// slope bounds (from prefiltered coefficients that ring) prove few cells empty: the search for
// small components would split cells without end. Its budget ends it, and the run says that a
// component may be missing, at once, instead of a mesh that misses it (before the budget: 2^20
// cells split in 10-40 s, and meshes of 3 and 6 components where marching cubes on the full grid
// finds 4 and 9).
TEST(AdaptiveSeeding, ASearchThatCannotFinishSaysAComponentMayBeMissing) {
  const Volume noisy(noisy_sphere(20, 0.1), 0.0);
  AdaptiveOptions o;
  o.min_edge = 0.007;  // the default's, kept: no run with a lowered one
  int attempts = 0;  // each attempt's tracking announces "meshing"
  o.phase = [&](const std::string& name) { attempts += name == "meshing"; };
  try {
    polygonize_adaptive(noisy, o);
    FAIL() << "the run meshed";
  } catch (const LimitExceededError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("stopped at its bound"), std::string::npos) << what;
    EXPECT_NE(what.find("may be missing"), std::string::npos) << what;
  }
  // One attempt: no recovery and no run made again meets the same cells after it.
  EXPECT_EQ(attempts, 1);
}

}  // namespace
}  // namespace cdp
