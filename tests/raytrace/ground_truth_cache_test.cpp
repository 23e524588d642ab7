// Checks <cdp/raytrace/ground_truth_cache.h>: keys, a bit-exact round trip, missing and damaged files.
#include <cdp/raytrace/ground_truth_cache.h>

#include <common/run_command.h>
#include <cdp/core/errors.h>
#include <cdp/core/models/analytic.h>

#include <gtest/gtest.h>

#include <fstream>

namespace cdp {
namespace {

const std::string kField = R"({"type": "torus", "major_radius": 1.0, "minor_radius": 0.3})";

TEST(GroundTruthCache, KeyIgnoresFormattingButNotContent) {
  CameraOptions camera;
  RaycastOptions raycast;
  const std::string key = ground_truth_key(kField, camera, raycast);
  EXPECT_EQ(key.size(), 16u);
  EXPECT_EQ(key, ground_truth_key(R"({ "minor_radius":0.3,"type":"torus",  "major_radius":1.0 })", camera, raycast));
  EXPECT_NE(key, ground_truth_key(R"({"type": "torus", "major_radius": 1.0, "minor_radius": 0.31})", camera, raycast));
  CameraOptions other = camera;
  other.resolution = 65;
  EXPECT_NE(key, ground_truth_key(kField, other, raycast));
  other = camera;
  other.projection = Projection::Orthographic;
  EXPECT_NE(key, ground_truth_key(kField, other, raycast));
  RaycastOptions finer = raycast;
  finer.min_step = 1e-5;
  EXPECT_NE(key, ground_truth_key(kField, camera, finer));
  EXPECT_THROW(ground_truth_key("{not json", camera, raycast), InvalidInputError);
}

TEST(GroundTruthCache, RoundTripIsBitExact) {
  const test::TempDir dir("gt_cache");
  const Torus torus(Vec3::Zero(), 1.0, 0.3);
  CameraOptions camera;
  camera.views = 2;
  camera.resolution = 8;
  const GroundTruth gt = compute_ground_truth(torus, make_camera_rays(torus.bounds(), camera));
  const std::string key = ground_truth_key(kField, camera, {});
  EXPECT_FALSE(load_ground_truth(dir.path, key).has_value());
  save_ground_truth(gt, dir.path / "sub", key);
  const auto back = load_ground_truth(dir.path / "sub", key);
  ASSERT_TRUE(back.has_value());
  ASSERT_EQ(back->rays.size(), gt.rays.size());
  EXPECT_EQ(back->setup.box.min, gt.setup.box.min);
  EXPECT_EQ(back->setup.box.max, gt.setup.box.max);
  EXPECT_EQ(back->setup.lipschitz, gt.setup.lipschitz);
  EXPECT_EQ(back->setup.lipschitz_from_model, gt.setup.lipschitz_from_model);
  EXPECT_EQ(back->setup.min_step, gt.setup.min_step);
  for (std::size_t i = 0; i < gt.rays.size(); ++i) {
    EXPECT_EQ(back->rays[i].origin, gt.rays[i].origin);
    EXPECT_EQ(back->rays[i].direction, gt.rays[i].direction);
    EXPECT_EQ(back->hits[i].status, gt.hits[i].status);
    EXPECT_EQ(back->hits[i].flags, gt.hits[i].flags);
    EXPECT_EQ(back->hits[i].steps, gt.hits[i].steps);
    EXPECT_EQ(back->hits[i].t, gt.hits[i].t);
    EXPECT_EQ(back->hits[i].normal, gt.hits[i].normal);
  }
  // No temporary file is left behind.
  std::size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path / "sub")) files += e.is_regular_file();
  EXPECT_EQ(files, 1u);
}

TEST(GroundTruthCache, CachedGroundTruthCastsOnceAndRecastsForOtherRays) {
  const test::TempDir dir("gt_cache_policy");
  const Torus torus(Vec3::Zero(), 1.0, 0.3);
  CameraOptions camera;
  camera.views = 2;
  camera.resolution = 8;
  const std::vector<Ray> rays = make_camera_rays(torus.bounds(), camera);
  const std::string key = ground_truth_key(kField, camera, {});
  int casts = 0;
  bool cached = true;
  const GroundTruth first = cached_ground_truth(torus, rays, {}, dir.path, key, &cached, [&] { ++casts; });
  EXPECT_FALSE(cached);
  EXPECT_EQ(casts, 1);
  EXPECT_TRUE(load_ground_truth(dir.path, key).has_value());  // saved
  const GroundTruth second = cached_ground_truth(torus, rays, {}, dir.path, key, &cached, [&] { ++casts; });
  EXPECT_TRUE(cached);
  EXPECT_EQ(casts, 1);
  ASSERT_EQ(second.hits.size(), first.hits.size());
  for (std::size_t i = 0; i < first.hits.size(); ++i) EXPECT_EQ(second.hits[i].t, first.hits[i].t);
  // A file cast along other rays under the same key (another build's cameras) is stale.
  std::vector<Ray> moved = rays;
  moved.front().origin.x() += 1e-3;
  cached_ground_truth(torus, moved, {}, dir.path, key, &cached, [&] { ++casts; });
  EXPECT_FALSE(cached);
  EXPECT_EQ(casts, 2);
  // Without a folder nothing is read or written.
  cached_ground_truth(torus, rays, {}, "", key, &cached, [&] { ++casts; });
  EXPECT_FALSE(cached);
  EXPECT_EQ(casts, 3);
}

TEST(GroundTruthCache, DamagedOrForeignFilesAreErrors) {
  const test::TempDir dir("gt_cache_bad");
  const Sphere sphere(Vec3::Zero(), 1.0);
  CameraOptions camera;
  camera.views = 1;
  camera.resolution = 4;
  const GroundTruth gt = compute_ground_truth(sphere, make_camera_rays(sphere.bounds(), camera));
  save_ground_truth(gt, dir.path, "aaaa");
  // A file under another key's name (copied by hand) is refused.
  std::filesystem::copy_file(ground_truth_path(dir.path, "aaaa"), ground_truth_path(dir.path, "bbbb"));
  EXPECT_THROW(load_ground_truth(dir.path, "bbbb"), InvalidInputError);
  // A truncated file is refused.
  const auto size = std::filesystem::file_size(ground_truth_path(dir.path, "aaaa"));
  std::filesystem::resize_file(ground_truth_path(dir.path, "aaaa"), size - 5);
  EXPECT_THROW(load_ground_truth(dir.path, "aaaa"), InvalidInputError);
  std::ofstream(ground_truth_path(dir.path, "cccc")) << "garbage";
  EXPECT_THROW(load_ground_truth(dir.path, "cccc"), InvalidInputError);
}

}  // namespace
}  // namespace cdp
