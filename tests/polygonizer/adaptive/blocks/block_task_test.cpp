// Blocks meshed elsewhere (cdp/core/block_tasks.h, src/adaptive/block_task.h): a run whose blocks
// go through a runner as bytes makes the mesh the run on its own threads makes, bit for bit; the
// bytes that are not a task or a piece of this build are refused; a tracker's failure travels in
// its piece and decides as a block's own would.
#include <gtest/gtest.h>

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/block_tasks.h>
#include <cdp/core/errors.h>

#include "common/test_fields.h"
#include "src/adaptive/block_task.h"
#include "src/adaptive/crease_patches.h"

#include <algorithm>
#include <random>

namespace cdp::adaptive {
namespace {

// The torus of blocks_test.cpp: 3 x 3 x 1 blocks at factor 12.
const char* const kTaskTorus = R"({"type": "expression", "value": "(sqrt(x^2+y^2)-1)^2 + z^2 - 0.16",
                                    "bounds": [[-1.6, -1.6, -0.6], [1.6, 1.6, 0.6]]})";

AdaptiveOptions task_options(double factor = 12) {
  AdaptiveOptions o;
  o.factor = factor;
  o.blocks = true;
  o.threads = 2;
  return o;
}

void expect_same_piece_mesh(const Mesh& a, const Mesh& b) {
  ASSERT_EQ(a.positions.size(), b.positions.size());
  ASSERT_EQ(a.triangles.size(), b.triangles.size());
  for (std::size_t i = 0; i < a.positions.size(); ++i) ASSERT_EQ(a.positions[i], b.positions[i]) << "vertex " << i;
  for (std::size_t i = 0; i < a.triangles.size(); ++i) ASSERT_EQ(a.triangles[i], b.triangles[i]) << "triangle " << i;
  ASSERT_EQ(a.normals, b.normals);
}

// A runner that runs the tasks in an order drawn from `seed`, each from its bytes alone, on a
// field of its own built from the same description (as a worker builds it).
BlockRunner shuffled_runner(const char* json, std::uint64_t seed, std::size_t* calls) {
  return [json, seed, calls](const std::vector<std::string>& tasks) {
    ++*calls;
    const auto field = test::field_from_json(json);
    std::vector<std::size_t> order(tasks.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::shuffle(order.begin(), order.end(), std::mt19937_64(seed));
    std::vector<std::string> pieces(tasks.size());
    for (const std::size_t i : order) pieces[i] = run_block_task(*field, tasks[i]);
    return pieces;
  };
}

TEST(BlockTasks, BlocksRunFromTheirBytesMakeTheSameMeshAsOnTheRunsThreads) {
  const auto f = test::field_from_json(kTaskTorus);
  for (const double tolerance : {0.0, 2e-3}) {  // with a tolerance the repairs split too
    SCOPED_TRACE(tolerance);
    AdaptiveOptions o = task_options();
    if (tolerance > 0) o.sizing = SizingMode::Tolerance, o.tolerance = tolerance;
    o.curvature_properties = true;
    const PolygonizeResult here = polygonize_adaptive(*f, o);
    ASSERT_TRUE(here.stats.adaptive->blocks.used) << here.stats.adaptive->blocks.fallback;
    std::size_t calls = 0;
    o.block_runner = shuffled_runner(kTaskTorus, 7, &calls);
    const PolygonizeResult there = polygonize_adaptive(*f, o);
    const BlocksReport& b = there.stats.adaptive->blocks;
    ASSERT_TRUE(b.used) << b.fallback;
    EXPECT_EQ(calls, 1u);
    EXPECT_GT(b.task_bytes, 0u);
    EXPECT_GT(b.piece_bytes, b.task_bytes);  // a piece holds its block's mesh
    expect_same_piece_mesh(here.mesh, there.mesh);
    EXPECT_EQ(here.mesh.vertex_scalars, there.mesh.vertex_scalars);
    EXPECT_EQ(here.stats.adaptive->blocks.seam_vertices, b.seam_vertices);
  }
}

TEST(BlockTasks, BytesThatAreNotATaskOrAPieceOfThisBuildAreRefused) {
  const auto f = test::field_from_json(kTaskTorus);
  std::string task;
  AdaptiveOptions o = task_options();
  o.block_runner = [&](const std::vector<std::string>& tasks) {
    task = tasks.front();
    std::vector<std::string> pieces;
    for (const auto& t : tasks) pieces.push_back(run_block_task(*f, t));
    return pieces;
  };
  polygonize_adaptive(*f, o);
  ASSERT_FALSE(task.empty());
  EXPECT_NO_THROW(read_task(task));
  EXPECT_THROW(run_block_task(*f, task.substr(0, task.size() - 1)), InvalidInputError);
  EXPECT_THROW(run_block_task(*f, task + "x"), InvalidInputError);
  EXPECT_THROW(run_block_task(*f, ""), InvalidInputError);
  const std::string piece = run_block_task(*f, task);
  EXPECT_THROW(run_block_task(*f, piece), InvalidInputError);  // a piece is no task
  EXPECT_THROW(read_part(task), InvalidInputError);
  EXPECT_THROW(read_part(piece.substr(0, piece.size() / 2)), InvalidInputError);
  // A runner that loses a piece is an error of the run, not a mesh with a hole.
  o.block_runner = [](const std::vector<std::string>& tasks) { return std::vector<std::string>(tasks.size() - 1); };
  EXPECT_THROW(polygonize_adaptive(*f, o), std::runtime_error);
}

TEST(BlockTasks, ATrackersFailureTravelsInItsPieceWithItsKind) {
  BlockPart failed;
  failed.error = std::make_exception_ptr(CreaseLayoutError("adaptive: a block's loops"));
  const BlockPart back = read_part(write_part(failed));
  ASSERT_TRUE(back.error);
  EXPECT_THROW(std::rethrow_exception(back.error), CreaseLayoutError);
  failed.error = std::make_exception_ptr(StalledFrontError("adaptive: stalled"));
  EXPECT_THROW(std::rethrow_exception(read_part(write_part(failed)).error), StalledFrontError);
  try {
    std::rethrow_exception(read_part(write_part(failed)).error);
  } catch (const StalledFrontError& e) {
    EXPECT_STREQ(e.what(), "adaptive: stalled");
  }
  // Any other error (the field's) is not a tracker's failure: it leaves write_part as it is.
  failed.error = std::make_exception_ptr(std::runtime_error("the field's"));
  EXPECT_THROW(write_part(failed), std::runtime_error);
}

}  // namespace
}  // namespace cdp::adaptive
