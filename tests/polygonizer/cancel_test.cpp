// CancelToken (cdp/core/cancel.h): a run holding a cancelled token ends with CancelledError,
// whichever method and whenever the token is cancelled, and the field meshes again afterwards.
// How soon a run stops is measured by bench/adaptive.cpp's BM_CancelLatency, not here.
#include <gtest/gtest.h>

#include <cdp/baselines/marching_cubes.h>
#include <cdp/baselines/marching_tetrahedra.h>
#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/cancel.h>
#include <cdp/core/models/analytic.h>
#include <cdp/core/triangle_intersection.h>

#include <atomic>
#include <chrono>
#include <thread>

namespace cdp {
namespace {

TEST(CancelToken, CopiesShareOneFlagAndResetClearsIt) {
  const CancelToken a;
  const CancelToken b = a;
  EXPECT_FALSE(b.cancelled());
  EXPECT_NO_THROW(b.check("x"));
  a.cancel();
  EXPECT_TRUE(b.cancelled());
  EXPECT_THROW(b.check("x"), CancelledError);
  EXPECT_FALSE(CancelToken().cancelled());  // a new token is a new flag
  b.reset();
  EXPECT_FALSE(a.cancelled());
}

TEST(CancelToken, ALinkedTokenFollowsItsParentAndNotTheOtherWay) {
  const CancelToken run;
  const CancelToken part = run.linked(), other = run.linked(), deeper = part.linked();
  part.cancel();
  EXPECT_TRUE(part.cancelled());
  EXPECT_TRUE(deeper.cancelled());
  EXPECT_FALSE(run.cancelled());
  EXPECT_FALSE(other.cancelled());
  part.reset();
  EXPECT_FALSE(deeper.cancelled());
  run.cancel();
  EXPECT_TRUE(part.cancelled() && other.cancelled() && deeper.cancelled());
  EXPECT_THROW(deeper.check("x"), CancelledError);
  run.reset();
  EXPECT_FALSE(deeper.cancelled());
}

TEST(CancelToken, EveryMethodEndsWithCancelledErrorWhenCancelledBeforeItStarts) {
  const Sphere sphere(Vec3::Zero(), 1);
  AdaptiveOptions a;
  a.cancel.cancel();
  EXPECT_THROW(polygonize_adaptive(sphere, a), CancelledError);
  MarchingOptions m;
  m.cell_size = 0.1;
  m.cancel.cancel();
  EXPECT_THROW(marching_cubes(sphere, m), CancelledError);
  EXPECT_THROW(marching_tetrahedra(sphere, m), CancelledError);
  m.traversal = Traversal::Grid;
  EXPECT_THROW(marching_cubes(sphere, m), CancelledError);
}

TEST(CancelToken, TheSelfIntersectionSearchPollsIt) {
  const Sphere sphere(Vec3::Zero(), 1);
  const Mesh mesh = polygonize_adaptive(sphere, AdaptiveOptions{}).mesh;
  const CancelToken token;
  EXPECT_TRUE(self_intersecting_pairs(mesh, 16, 1, &token).empty());
  token.cancel();
  EXPECT_THROW(self_intersecting_pairs(mesh, 16, 1, &token), CancelledError);
}

// Cancelled from another thread at several moments of a run (the seed grid, tracking, the
// repair, the checks: the torus at factor 12 takes about 0.1 s here), the run ends with
// CancelledError; the same options with the token reset then give the mesh a run never
// cancelled gives, bit for bit.
TEST(CancelToken, ARunCancelledFromAnotherThreadEndsAndTheFieldMeshesAgainTheSame) {
  const Torus torus(Vec3::Zero(), 1, 0.4);
  AdaptiveOptions o;
  o.factor = 12;
  o.threads = 2;
  const PolygonizeResult reference = polygonize_adaptive(torus, o);
  const double seconds = reference.stats.seconds;
  int cancelled = 0;
  for (const double share : {0.05, 0.3, 0.6, 0.9}) {
    o.cancel.reset();
    std::thread canceller([&, share] {
      std::this_thread::sleep_for(std::chrono::duration<double>(share * seconds));
      o.cancel.cancel();
    });
    try {
      polygonize_adaptive(torus, o);
    } catch (const CancelledError& e) {
      ++cancelled;
      EXPECT_NE(std::string(e.what()).find("cancelled"), std::string::npos);
    }
    canceller.join();
  }
  // A loaded machine may let a run finish before its token is cancelled; most do not.
  EXPECT_GE(cancelled, 2);
  o.cancel.reset();
  const PolygonizeResult again = polygonize_adaptive(torus, o);
  EXPECT_EQ(again.mesh.positions, reference.mesh.positions);
  EXPECT_EQ(again.mesh.triangles, reference.mesh.triangles);
}

}  // namespace
}  // namespace cdp
