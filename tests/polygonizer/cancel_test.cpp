// CancelToken (cdp/core/cancel.h): a run holding a cancelled token ends with CancelledError,
// whichever method and whenever the token is cancelled, and the field meshes again afterwards.
// How soon a run stops is measured by bench/adaptive.cpp's BM_CancelLatency, not here.
#include <gtest/gtest.h>

#include <cdp/baselines/marching_cubes.h>
#include <cdp/baselines/marching_tetrahedra.h>
#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/cancel.h>
#include <cdp/core/crease_curves.h>
#include <cdp/core/models/expression.h>
#include <cdp/core/models/analytic.h>
#include <cdp/core/triangle_intersection.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

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

// A model's creases may take seconds to trace (fogleman/sdf's knurling example: 13 s): the
// tracing reports its progress, never going back, and a token cancelled from its progress
// callback ends it with CancelledError; polygonize_adaptive passes both on and names the phase.
TEST(CancelToken, CreaseTracingReportsProgressAndPollsIt) {
  // A box with three square holes through it: 24 creases and 40 corners.
  const Expression sponge("max(max(abs(x),abs(y),abs(z))-1, -min(max(abs(x),abs(y))-0.4, max(abs(y),abs(z))-0.4, "
                          "max(abs(x),abs(z))-0.4))",
                          {}, Box{Vec3::Constant(-1.2), Vec3::Constant(1.2)});
  CreaseTracingOptions o;
  std::vector<double> shares;
  o.progress = [&](double share) { shares.push_back(share); };
  const CreaseTracingResult traced = trace_creases(sponge, o);
  EXPECT_GE(traced.curves.size(), 24u);
  ASSERT_GE(shares.size(), 3u);
  EXPECT_TRUE(std::is_sorted(shares.begin(), shares.end()));
  EXPECT_GT(shares.front(), 0.0);
  EXPECT_LT(shares.front(), 0.5);  // the grid's crossings, then the corners
  EXPECT_GT(shares.back(), 0.5);
  EXPECT_LE(shares.back(), 1.0);
  const CancelToken token;
  o.cancel = &token;
  o.progress = [&](double share) {
    if (share > 0.5) token.cancel();  // among the corners
  };
  EXPECT_THROW(trace_creases(sponge, o), CancelledError);
  token.reset();
  o.progress = [&](double) { token.cancel(); };  // among the crossings
  EXPECT_THROW(trace_creases(sponge, o), CancelledError);
  AdaptiveOptions a;
  std::vector<std::string> phases;
  a.phase = [&](const std::string& phase) { phases.push_back(phase); };
  a.progress = [&](double) {
    if (!phases.empty() && phases.back() == "tracing creases") a.cancel.cancel();
  };
  EXPECT_THROW(polygonize_adaptive(sponge, a), CancelledError);
  EXPECT_EQ(phases.back(), "tracing creases");
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
