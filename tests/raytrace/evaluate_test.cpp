// Checks <cdp/raytrace/evaluate.h>: the documented metric names are all present and consistent.
#include <cdp/raytrace/evaluate.h>
#include "common/reference_meshes.h"

#include <cdp/core/errors.h>
#include <cdp/core/models/analytic.h>

#include <gtest/gtest.h>

namespace cdp {
namespace {

TEST(Evaluate, IcosphereOfASphereHasEveryDocumentedMetric) {
  const Sphere sphere(Vec3::Zero(), 1.0);
  EvaluateOptions o;
  o.camera.views = 3;
  o.camera.resolution = 16;
  o.sampling.samples = 500;
  const GroundTruth gt = compute_ground_truth(sphere, make_camera_rays(sphere.bounds(), o.camera), o.raycast);
  const Mesh mesh = icosphere(3);
  const nlohmann::json j = evaluate_mesh(sphere, mesh, gt, o, "file", "0123456789abcdef");
  EXPECT_EQ(j["schema"], kMetricsSchema);
  for (const char* k : {"mean", "std", "max", "relative_mean"}) EXPECT_TRUE(j["depth_error"][k].is_number()) << k;
  for (const char* k : {"mean", "std"}) EXPECT_TRUE(j["phong_error_deg"][k].is_number()) << k;
  EXPECT_TRUE(j["silhouette_disagreement"].is_number());
  for (const char* k : {"surface_only", "mesh_only", "compared"}) EXPECT_TRUE(j["silhouette_counts"][k].is_number());
  for (const char* k : {"mean", "std"}) EXPECT_TRUE(j["edge_ratio"][k].is_number());
  EXPECT_EQ(j["edge_ratio"]["histogram"]["counts"].size() + 1, j["edge_ratio"]["histogram"]["edges"].size());
  EXPECT_TRUE(j["near_equilateral_fraction"].is_number());
  EXPECT_TRUE(j["near_equilateral_definition"].is_string());
  for (const char* k : {"min", "mean"}) EXPECT_TRUE(j["min_angle_deg"][k].is_number());
  for (const char* k : {"min", "mean"}) EXPECT_TRUE(j["radius_ratio"][k].is_number());
  EXPECT_EQ(j["triangles"], mesh.num_triangles());
  EXPECT_EQ(j["vertices"], mesh.num_vertices());
  EXPECT_EQ(j["topology"]["closed"], true);
  EXPECT_EQ(j["topology"]["manifold"], true);
  EXPECT_EQ(j["topology"]["oriented"], true);
  EXPECT_EQ(j["topology"]["components"], 1);
  EXPECT_EQ(j["topology"]["genus"], 0);
  EXPECT_EQ(j["topology"]["self_intersections"]["pairs"], 0);
  EXPECT_TRUE(j["topology"]["self_intersections"]["examples"].is_array());
  EXPECT_EQ(j["topology"]["self_intersections"]["degenerate_triangles_skipped"], 0);
  EXPECT_GT(j["topology"]["self_intersections"]["candidate_pairs"].get<std::size_t>(), mesh.num_triangles());
  EXPECT_LT(j["vertex_distance"]["max"].get<double>(), 1e-15);
  EXPECT_EQ(j["mesh_to_surface"]["samples"], 500);
  EXPECT_GT(j["surface_to_mesh"]["points"].get<int>(), 100);
  EXPECT_EQ(j["rays"]["count"], gt.rays.size());
  EXPECT_EQ(j["rays"]["cache_key"], "0123456789abcdef");
  EXPECT_EQ(j["rays"]["surface_hits"].get<std::size_t>(), j["silhouette_counts"]["both_hit"].get<std::size_t>() +
                                                               j["silhouette_counts"]["surface_only"].get<std::size_t>());
  // Both one-sided distances are bounded by the deepest face centre of the inscribed mesh.
  EXPECT_LT(j["surface_to_mesh"]["max"].get<double>(), 0.01);
  EXPECT_LE(j["depth_error"]["mean"].get<double>(), j["depth_error"]["max"].get<double>());
  EXPECT_NO_THROW((void)j.dump());
}

TEST(Evaluate, SelfIntersectionsAreReportedWithExamples) {
  const Sphere sphere(Vec3::Zero(), 1.0);
  EvaluateOptions o;
  o.camera.views = 1;
  o.camera.resolution = 4;
  o.sampling.samples = 10;
  const GroundTruth gt = compute_ground_truth(sphere, make_camera_rays(sphere.bounds(), o.camera), o.raycast);
  Mesh mesh = icosphere(1);
  mesh.positions[0] = -1.5 * mesh.positions[0];  // pushed through the far side
  const SelfIntersectionReport expected = find_self_intersections(mesh);
  const nlohmann::json j = evaluate_mesh(sphere, mesh, gt, o);
  const nlohmann::json& s = j["topology"]["self_intersections"];
  EXPECT_GT(expected.pairs, 0u);
  EXPECT_EQ(s["pairs"].get<std::size_t>(), expected.pairs);
  ASSERT_EQ(s["examples"].size(), expected.examples.size());
  for (std::size_t i = 0; i < expected.examples.size(); ++i) {
    EXPECT_EQ(s["examples"][i][0].get<int>(), expected.examples[i].first);
    EXPECT_EQ(s["examples"][i][1].get<int>(), expected.examples[i].second);
  }
}

TEST(Evaluate, MeshWithoutNormalsIsRefused) {
  const Sphere sphere(Vec3::Zero(), 1.0);
  EvaluateOptions o;
  o.camera.views = 1;
  o.camera.resolution = 2;
  const GroundTruth gt = compute_ground_truth(sphere, make_camera_rays(sphere.bounds(), o.camera));
  Mesh mesh = icosphere(1);
  mesh.normals.clear();
  EXPECT_THROW(evaluate_mesh(sphere, mesh, gt, o), InvalidInputError);
}

// Every accuracy measure of these would be over zero samples, once reported as a perfect 0.
TEST(Evaluate, MeshWithoutTrianglesOrWithoutAnyRayHittingItIsRefused) {
  const Sphere sphere(Vec3::Zero(), 1.0);
  EvaluateOptions o;
  o.camera.views = 2;
  o.camera.resolution = 8;
  o.sampling.samples = 10;
  const GroundTruth gt = compute_ground_truth(sphere, make_camera_rays(sphere.bounds(), o.camera), o.raycast);
  ASSERT_GT(gt.counts().hits, 0u);
  Mesh empty = icosphere(1);
  empty.triangles.clear();
  const Mesh far = icosphere(1, Vec3(10, 10, 10));
  for (const auto& [mesh, message] : {std::pair{empty, std::string("the mesh has no triangles")},
                                      std::pair{far, "no ray hits the mesh (" + std::to_string(gt.counts().hits) +
                                                         " of 128 rays hit the surface)"}}) {
    try {
      (void)evaluate_mesh(sphere, mesh, gt, o);
      ADD_FAILURE() << message;
    } catch (const InvalidInputError& e) {
      EXPECT_EQ(std::string(e.what()), message);
    }
  }
}

}  // namespace
}  // namespace cdp
