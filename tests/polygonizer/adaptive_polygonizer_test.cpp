// The adaptive polygonizer's meshes: closed, outward, manifold, of the right topology, on the
// surface, well shaped and free of self-intersections, on analytic shapes, expressions and
// blob fields (including two dozen random ones); plus determinism, limits and errors.
#include <gtest/gtest.h>

#include <polygonizer/adaptive_polygonizer.h>
#include <polygonizer/errors.h>
#include <polygonizer/mesh_topology.h>

#include <random>

#include "common/test_fields.h"
#include "polygonizer/mesh_checks.h"

namespace cdp {
namespace {

struct Expected {
  std::size_t components = 1;
  int genus = 0;
  double max_mean_ratio = 1.5;
  double min_angle = 10;
};

// Every property a user relies on; returns the topology for further checks.
MeshTopology expect_good_mesh(const Field& field, const PolygonizeResult& r, const Expected& e,
                              const std::string& what) {
  SCOPED_TRACE(what);
  const Mesh& m = r.mesh;
  const MeshTopology t = analyze_topology(m);
  EXPECT_TRUE(t.closed()) << t.boundary_edges << " boundary edges";
  EXPECT_TRUE(t.edge_manifold()) << t.nonmanifold_edges << " non-manifold edges";
  EXPECT_TRUE(t.vertex_manifold()) << t.nonmanifold_vertices << " non-manifold vertices";
  EXPECT_TRUE(t.oriented()) << t.misoriented_edges << " misoriented edges";
  EXPECT_EQ(t.degenerate_triangles, 0u);
  EXPECT_EQ(t.duplicate_triangles, 0u);
  EXPECT_EQ(t.unreferenced_vertices, 0u);
  EXPECT_GT(t.signed_volume, 0);
  EXPECT_EQ(t.components, e.components);
  EXPECT_EQ(t.genus, e.genus);
  EXPECT_EQ(r.stats.components, t.components);
  EXPECT_EQ(r.stats.triangles, m.num_triangles());
  EXPECT_EQ(r.stats.vertices, m.num_vertices());
  EXPECT_LT(test::max_surface_distance(field, m), 1e-6 * field.bounds().diagonal());
  EXPECT_EQ(test::count_self_intersections(m), 0u);
  const test::ShapeStats s = test::shape_stats(m);
  EXPECT_LT(s.mean_ratio, e.max_mean_ratio);
  EXPECT_GT(s.min_angle_degrees, e.min_angle);
  EXPECT_NEAR(r.stats.extra.at("min_angle_degrees").get<double>(), s.min_angle_degrees, 1e-9);
  // Normals: unit, from the field gradient, hence outward.
  EXPECT_EQ(m.normals.size(), m.positions.size());
  double worst = 1;
  for (std::size_t v = 0; v < m.normals.size(); ++v)
    worst = std::min(worst, m.normals[v].dot(field.gradient(m.positions[v]).normalized()));
  EXPECT_NEAR(worst, 1.0, 1e-9);
  return t;
}

AdaptiveOptions coarse(double factor = 2) {
  AdaptiveOptions o;
  o.factor = factor;
  return o;
}

TEST(AdaptivePolygonizer, SphereIsAClosedOutwardGenusZeroMesh) {
  Sphere sphere(Vec3(0.1, -0.2, 0.3), 1.0);
  const auto r = polygonize_adaptive(sphere, coarse(3));
  expect_good_mesh(sphere, r, {}, "sphere");
  EXPECT_EQ(r.stats.method, "adaptive");
  EXPECT_EQ(r.stats.extra.at("seeds").get<int>(), 1);
  EXPECT_GT(r.stats.field_evaluations.gradient_hessian, 0u);
}

TEST(AdaptivePolygonizer, EllipsoidFollowsCurvature) {
  Ellipsoid e(Vec3::Zero(), Vec3(1.5, 0.8, 0.5));
  const auto r = polygonize_adaptive(e, coarse(3));
  expect_good_mesh(e, r, {}, "ellipsoid");
}

TEST(AdaptivePolygonizer, TorusHasGenusOne) {
  Torus torus(Vec3::Zero(), 1.0, 0.4);
  for (double k : {1.0, 2.0, 4.0}) {
    const auto r = polygonize_adaptive(torus, coarse(k));
    expect_good_mesh(torus, r, {1, 1}, "torus factor " + std::to_string(k));
  }
}

TEST(AdaptivePolygonizer, TanglecubeHasGenusFive) {
  const auto field = test::tanglecube();
  const auto r = polygonize_adaptive(*field, coarse(2));
  expect_good_mesh(*field, r, {1, 5}, "tanglecube");
}

TEST(AdaptivePolygonizer, SeparateBlobsGiveOneComponentEach) {
  const auto field = test::three_separate_blobs();
  const auto r = polygonize_adaptive(*field, coarse(2));
  expect_good_mesh(*field, r, {3, 0}, "three blobs");
  EXPECT_EQ(r.stats.extra.at("seeds").get<int>(), 3);
}

TEST(AdaptivePolygonizer, BlobsTouchingInARingFormAHandle) {
  std::vector<Blob> ring;
  for (int k = 0; k < 6; ++k) {
    const double t = k * M_PI / 3;
    ring.push_back({Vec3(1.3 * std::cos(t), 1.3 * std::sin(t), 0), 1.0, 1.0});
  }
  Blobs blobs(BlobKernel::Wyvill, 0.35, ring);
  const auto reference = analyze_topology(test::marching_tetrahedra_reference(blobs, 48));
  ASSERT_EQ(reference.genus, 1);
  const auto r = polygonize_adaptive(blobs, coarse(2));
  expect_good_mesh(blobs, r, {1, 1}, "ring of blobs");
}

}  // namespace
}  // namespace cdp
