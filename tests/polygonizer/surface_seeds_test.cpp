// Seeds land on every component; fields without a usable surface are reported as such.
#include <gtest/gtest.h>

#include <cdp/core/errors.h>
#include <cdp/core/surface_seeds.h>

#include <cdp/core/models/analytic.h>
#include <cdp/core/models/expression.h>

#include <mutex>
#include <set>
#include <thread>

#include "common/test_fields.h"

namespace cdp {
namespace {

std::string no_surface_message(const std::string& json) {
  try {
    find_surface_seeds(*test::field_from_json(json));
  } catch (const NoSurfaceError& e) {
    return e.what();
  }
  return "";
}

TEST(SurfaceSeeds, OneSeedOnEachOfThreeSeparateBlobs) {
  const auto f = test::three_separate_blobs();
  const auto seeds = find_surface_seeds(*f);
  ASSERT_EQ(seeds.size(), 3u);
  std::set<int> clusters;
  for (const auto& s : seeds) {
    EXPECT_LT(std::abs(f->value(s.point)) / f->gradient(s.point).norm(), 1e-9);
    clusters.insert(s.cluster);
  }
  EXPECT_EQ(clusters, (std::set<int>{0, 1, 2}));
}

TEST(SurfaceSeeds, CrossingsCoverEveryComponentAndAreDeterministic) {
  const auto f = test::tanglecube();
  const auto a = find_surface_crossings(*f);
  const auto b = find_surface_crossings(*f);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].point, b[i].point);
    EXPECT_EQ(a[i].cluster, b[i].cluster);
  }
  int max_cluster = 0;
  for (const auto& c : a) max_cluster = std::max(max_cluster, c.cluster);
  EXPECT_EQ(max_cluster, 0) << "the tanglecube is one connected surface";
  EXPECT_GT(a.size(), 100u);
}

// A torus that records the threads evaluating it and its batched calls, and says whether it
// may be evaluated concurrently as told.
class RecordingTorus : public Field {
 public:
  explicit RecordingTorus(bool thread_safe) : thread_safe_(thread_safe) { set_bounds(torus_.bounds()); }
  std::string type_name() const override { return "recording_torus"; }
  bool thread_safe() const override { return thread_safe_; }
  std::set<std::thread::id> threads() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return threads_;
  }
  std::size_t batches() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return batches_;
  }

 protected:
  double eval_value(const Vec3& p) const override { return torus_.value(p); }
  double eval_value_gradient(const Vec3& p, Vec3& g) const override { return torus_.value_gradient(p, g); }
  double eval_gradient_hessian(const Vec3& p, Vec3& g, Mat3& h) const override {
    return torus_.gradient_hessian(p, g, h);
  }
  void eval_values(const Vec3* points, double* out, std::size_t n) const override {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      threads_.insert(std::this_thread::get_id());
      ++batches_;
    }
    for (std::size_t i = 0; i < n; ++i) out[i] = torus_.value(points[i]);
  }

 private:
  Torus torus_{Vec3(0.01, 0.02, -0.015), 1.0, 0.4};
  bool thread_safe_;
  mutable std::mutex mutex_;
  mutable std::set<std::thread::id> threads_;
  mutable std::size_t batches_ = 0;
};

TEST(SurfaceSeeds, GridIsTheSameOnOneThreadOrMany) {
  // Resolution 48: 38,416 nodes on this flat box, sampled in blocks of 4096 on every core when
  // the field allows.
  SeedOptions o;
  o.resolution = 48;
  const RecordingTorus serial(false), parallel(true);
  const SeedGrid a = sample_seed_grid(serial, o), b = sample_seed_grid(parallel, o);
  ASSERT_EQ(a.values.size(), static_cast<std::size_t>(a.n[0] + 1) * (a.n[1] + 1) * (a.n[2] + 1));
  ASSERT_GT(a.values.size(), 4u * 4096u);
  ASSERT_EQ(a.values.size(), b.values.size());
  for (std::size_t i = 0; i < a.values.size(); ++i) ASSERT_EQ(a.values[i], b.values[i]) << "node " << i;
  // Every node evaluated once, counted once, whatever the threads.
  EXPECT_EQ(serial.counts().value, a.values.size());
  EXPECT_EQ(parallel.counts().value, b.values.size());
  // A field that is not thread-safe gets one batched call on the caller's thread.
  EXPECT_EQ(serial.batches(), 1u);
  EXPECT_EQ(serial.threads(), (std::set<std::thread::id>{std::this_thread::get_id()}));
  // A thread-safe one gets blocks (on one thread or more, as the machine has).
  EXPECT_GT(parallel.batches(), 1u);
  EXPECT_LE(parallel.threads().size(), std::max(1u, std::thread::hardware_concurrency()));
}

TEST(SurfaceSeeds, BuiltInModelsDeclareThemselvesThreadSafe) {
  EXPECT_TRUE(Torus(Vec3::Zero(), 1.0, 0.3).thread_safe());
  EXPECT_TRUE(test::tanglecube()->thread_safe());
  EXPECT_TRUE(test::three_separate_blobs()->thread_safe());
}

TEST(SurfaceSeeds, FieldWithoutZeroCrossingIsReported) {
  const std::string msg =
      no_surface_message(R"({"type": "expression", "value": "x^2 + y^2 + z^2 + 1", "bounds": [[-1,-1,-1],[1,1,1]]})");
  EXPECT_NE(msg.find("no zero crossing"), std::string::npos) << msg;
  EXPECT_NE(msg.find("positive everywhere"), std::string::npos) << msg;
}

TEST(SurfaceSeeds, SurfaceLeavingTheBoxIsReported) {
  const std::string msg = no_surface_message(R"({"type": "sphere", "radius": 1, "bounds": [[-0.5,-2,-2],[2,2,2]]})");
  EXPECT_NE(msg.find("the surface leaves the box"), std::string::npos) << msg;
}

TEST(SurfaceSeeds, NaNFieldIsReported) {
  const std::string msg =
      no_surface_message(R"({"type": "expression", "value": "sqrt(x) + y", "bounds": [[-1,-1,-1],[1,1,1]]})");
  EXPECT_NE(msg.find("not finite"), std::string::npos) << msg;
}

TEST(SurfaceSeeds, TripleRootWithVanishingGradientStillGivesSeedsOnTheSurface) {
  // The gradient of (|x|^2 - 1)^3 vanishes on the surface; bisection along the grid edge brings
  // the point close enough that the projection accepts it without dividing by a zero gradient.
  const auto f = test::field_from_json(
      R"({"type": "expression", "value": "(x^2 + y^2 + z^2 - 1)^3", "bounds": [[-2,-2,-2],[2,2,2]]})");
  const auto seeds = find_surface_seeds(*f);
  ASSERT_EQ(seeds.size(), 1u);
  EXPECT_NEAR(seeds[0].point.norm(), 1.0, 1e-6);
}

// Two unit boxes sharing the face x = 0.5, where the grid (h = 0.075 from x = -0.7) has a layer
// of nodes: their union's field is exactly 0 there and negative on either side. Counted as
// outside, each node of that face made sign changes with its neighbours, and a seed there meshed
// the face inside the solid. They count as inside: the grid's sign changes are those of the
// 2 x 1 x 1 box.
TEST(SurfaceSeeds, NodesWhereTwoSolidsTouchCountAsInside) {
  const Expression boxes("min(max(abs(x)-0.5, abs(y)-0.5, abs(z)-0.5), max(abs(x-1)-0.5, abs(y)-0.5, abs(z)-0.5))",
                         Box{Vec3(-0.7, -0.7, -0.7), Vec3(1.7, 0.7, 0.7)});
  SeedOptions o;
  o.resolution = 32;
  const SeedGrid g = sample_seed_grid(boxes, o);
  ASSERT_DOUBLE_EQ(g.point(16, 0, 0).x(), 0.5);
  // The face's nodes strictly inside its rim: |y|, |z| < 0.5, 13 x 13 of them.
  EXPECT_EQ(g.touching, 169u);
  std::size_t on_face = 0;
  g.for_each_sign_change([&](const std::array<int, 3>& a, const std::array<int, 3>& b) {
    const Vec3 pa = g.point(a[0], a[1], a[2]), pb = g.point(b[0], b[1], b[2]);
    const Vec3 mid = 0.5 * (pa + pb);
    if (std::abs(mid.x() - 0.5) < 0.04 && std::abs(mid.y()) < 0.45 && std::abs(mid.z()) < 0.45) ++on_face;
  });
  EXPECT_EQ(on_face, 0u);
}

}  // namespace
}  // namespace cdp
