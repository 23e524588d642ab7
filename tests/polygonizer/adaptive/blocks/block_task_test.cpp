// Blocks meshed elsewhere (cdp/core/block_tasks.h, src/adaptive/block_task.h): a run whose blocks
// go through a runner as bytes makes the mesh the run on its own threads makes, bit for bit; the
// bytes that are not a task or a piece of this build are refused; a tracker's failure travels in
// its piece and decides as a block's own would.
#include <gtest/gtest.h>

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/block_tasks.h>
#include <cdp/core/errors.h>

#include "common/same_mesh.h"
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
    test::expect_same_mesh(here.mesh, there.mesh);
    EXPECT_FALSE(there.mesh.vertex_scalars.empty());
    EXPECT_EQ(here.stats.adaptive->blocks.seam_vertices, b.seam_vertices);
  }
}

TEST(BlockTasks, TheReportCountsTheBlocksTrackersWork) {
  // Tanglecube at factor 5 (8 blocks) crosses every cut, so the seeding's tracker makes no step:
  // the tracker's counters in the report are the blocks' trackers', summed from their pieces
  // (before, the seeding tracker's alone: side points, deferrals and curvature time read 0).
  const auto f = test::field_from_json(R"({"type": "expression", "bounds": [[-3, -3, -3], [3, 3, 3]],
                                          "value": "x^4 - 5*x^2 + y^4 - 5*y^2 + z^4 - 5*z^2 + 11.8"})");
  AdaptiveOptions o = task_options(5);
  TrackerReport pieces_sum;
  o.block_runner = [&](const std::vector<std::string>& tasks) {
    std::vector<std::string> pieces;
    for (const std::string& t : tasks) {
      pieces.push_back(run_block_task(*f, t));
      add_tracker_counts(pieces_sum, read_part(pieces.back()).tracker);
    }
    return pieces;
  };
  const PolygonizeResult r = polygonize_adaptive(*f, o);
  ASSERT_TRUE(r.stats.adaptive->blocks.used) << r.stats.adaptive->blocks.fallback;
  ASSERT_EQ(r.stats.adaptive->seeding.seeds, 0u);
  const TrackerReport& tr = r.stats.adaptive->tracker;
  EXPECT_EQ(tr.steps, 0u);  // the seeding tracker's; the blocks' are blocks.steps
  EXPECT_EQ(r.stats.adaptive->blocks.steps, pieces_sum.steps);
  EXPECT_GT(pieces_sum.side_points + pieces_sum.deferrals, 0u);
  EXPECT_EQ(tr.side_points, pieces_sum.side_points);
  EXPECT_EQ(tr.deferrals, pieces_sum.deferrals);
  EXPECT_EQ(tr.anticipations, pieces_sum.anticipations);
  EXPECT_EQ(tr.over_mesh_rejections, pieces_sum.over_mesh_rejections);
  EXPECT_GT(pieces_sum.search_visits, 0u);
  EXPECT_GE(tr.search_visits, pieces_sum.search_visits);  // and the seeding's coverage searches
  EXPECT_GT(tr.hessian_seconds, 0.0);
  // The same counts from the blocks run on this process's threads.
  const PolygonizeResult here = polygonize_adaptive(*f, task_options(5));
  EXPECT_EQ(here.stats.adaptive->tracker.side_points, tr.side_points);
  EXPECT_EQ(here.stats.adaptive->tracker.deferrals, tr.deferrals);
  EXPECT_EQ(here.stats.adaptive->tracker.search_visits, tr.search_visits);
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
  // A black box's kink ends the run, not a fallback to tracking alone: it travels as itself, with
  // the place and length of the kink (the run's tightest bend; stats tracker.min_curvature_radius).
  failed.error = std::make_exception_ptr(BlackBoxKinkError("adaptive: a kink"));
  failed.tightest = {2.5e-5, Vec3(0.25, -0.5, 1)};
  const BlockPart kink = read_part(write_part(failed));
  EXPECT_THROW(std::rethrow_exception(kink.error), BlackBoxKinkError);
  EXPECT_EQ(kink.tightest.first, 2.5e-5);
  EXPECT_EQ(kink.tightest.second, Vec3(0.25, -0.5, 1));
  // Any other error (the field's) travels as a std::runtime_error with its message, for the run
  // to raise in block order.
  failed.error = std::make_exception_ptr(std::range_error("the field's"));
  try {
    std::rethrow_exception(read_part(write_part(failed)).error);
    ADD_FAILURE() << "no error";
  } catch (const std::logic_error&) {
    ADD_FAILURE() << "a field's error is no tracker's failure";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "the field's");
  }
}

TEST(BlockTasks, EverySettingAndRepairOptionTravels) {
  // Every member set away from its default, read back member by member: one left out of
  // write_task would come back as its default.
  BlockTask t;
  t.block = 17;
  Settings& s = t.settings;
  s.sizing = {SizingMode::Chord, 3.5, 1e-3, 0.01, 0.2, 0.7};
  s.rule = TriangleCountRule::PaperFloor;
  s.collision_factor = 1.7, s.max_triangles = 123, s.max_steps = 456, s.search_visits_per_step = 789;
  s.callers_search_bound = true, s.stop_at_kink = true, s.curvature_properties = true, s.grading = false;
  s.side_points = false;
  s.diagonal = 4.25, s.rollback = true, s.anticipate = true;
  s.finer_zones = {{Vec3(1, 2, 3), 0.5, 0.01}, {Vec3(-1, 0, 2), 0.25, 0.02}};
  s.look_ahead = true, s.look_ahead_gradation = 0.3, s.hash_cell = 0.05;
  t.estimated_area = 9.5, t.lo = Vec3(-1, -2, -3), t.hi = Vec3(1, 2, 3);
  Tracker::Placed p;
  p.point = Vec3(0.1, 0.2, 0.3);
  p.curvature.normal = Vec3(0, 0, 1), p.curvature.C = Mat3::Identity() * 2, p.curvature.k1 = 3, p.curvature.k2 = -1;
  p.curvature.dir1 = Vec3(1, 0, 0), p.curvature.dir2 = Vec3(0, 1, 0), p.curvature.gaussian = -3;
  p.curvature.mean = 1, p.curvature.mac = 3, p.curvature.min_radius = 1.0 / 3, p.curvature.shape_index = 0.2;
  p.to_critical = Vec3(0.5, 0.5, 0.5), p.seam_target = 0.04;
  Tracker::Placed q = p;
  q.to_critical.reset();
  t.loops = {{p, q, p}, {q}};
  QualityOptions& r = t.repair.emplace();
  r.improve_below = 0.5, r.tolerance = 1e-3, r.diagonal = 4.25, r.min_edge = 0.002, r.last_resort_min_edge = 0.001;
  r.measure_near_bound = false, r.aim_mean_edge_ratio = 1.2, r.threads = 3, r.keep_boundary = true;
  r.count_near_boundary = false, r.predict_estimates = QualityOptions::Predict::Always;
  t.check_self_intersections = true;
  const BlockTask b = read_task(write_task(t));
  EXPECT_EQ(b.block, 17u);
  const Settings& x = b.settings;
  EXPECT_EQ(x.sizing.mode, s.sizing.mode);
  EXPECT_EQ(x.sizing.factor, s.sizing.factor);
  EXPECT_EQ(x.sizing.tolerance, s.sizing.tolerance);
  EXPECT_EQ(x.sizing.min_edge, s.sizing.min_edge);
  EXPECT_EQ(x.sizing.max_edge, s.sizing.max_edge);
  EXPECT_EQ(x.sizing.max_turn, s.sizing.max_turn);
  EXPECT_EQ(x.rule, s.rule);
  EXPECT_EQ(x.collision_factor, s.collision_factor);
  EXPECT_EQ(x.max_triangles, s.max_triangles);
  EXPECT_EQ(x.max_steps, s.max_steps);
  EXPECT_EQ(x.search_visits_per_step, s.search_visits_per_step);
  EXPECT_EQ(x.callers_search_bound, s.callers_search_bound);
  EXPECT_EQ(x.stop_at_kink, s.stop_at_kink);
  EXPECT_EQ(x.curvature_properties, s.curvature_properties);
  EXPECT_EQ(x.grading, s.grading);
  EXPECT_EQ(x.side_points, s.side_points);
  EXPECT_EQ(x.diagonal, s.diagonal);
  EXPECT_EQ(x.rollback, s.rollback);
  EXPECT_EQ(x.anticipate, s.anticipate);
  ASSERT_EQ(x.finer_zones.size(), 2u);
  EXPECT_EQ(x.finer_zones[1].center, s.finer_zones[1].center);
  EXPECT_EQ(x.finer_zones[1].radius, s.finer_zones[1].radius);
  EXPECT_EQ(x.finer_zones[1].edge, s.finer_zones[1].edge);
  EXPECT_EQ(x.look_ahead, s.look_ahead);
  EXPECT_EQ(x.look_ahead_gradation, s.look_ahead_gradation);
  EXPECT_EQ(x.hash_cell, s.hash_cell);
  EXPECT_EQ(b.estimated_area, t.estimated_area);
  EXPECT_EQ(b.lo, t.lo);
  EXPECT_EQ(b.hi, t.hi);
  ASSERT_EQ(b.loops.size(), 2u);
  ASSERT_EQ(b.loops[0].size(), 3u);
  const Tracker::Placed& y = b.loops[0][0];
  EXPECT_EQ(y.point, p.point);
  EXPECT_EQ(y.curvature.normal, p.curvature.normal);
  EXPECT_EQ(y.curvature.C, p.curvature.C);
  EXPECT_EQ(y.curvature.k1, p.curvature.k1);
  EXPECT_EQ(y.curvature.k2, p.curvature.k2);
  EXPECT_EQ(y.curvature.dir1, p.curvature.dir1);
  EXPECT_EQ(y.curvature.dir2, p.curvature.dir2);
  EXPECT_EQ(y.curvature.gaussian, p.curvature.gaussian);
  EXPECT_EQ(y.curvature.mean, p.curvature.mean);
  EXPECT_EQ(y.curvature.mac, p.curvature.mac);
  EXPECT_EQ(y.curvature.min_radius, p.curvature.min_radius);
  EXPECT_EQ(y.curvature.shape_index, p.curvature.shape_index);
  EXPECT_EQ(y.to_critical, p.to_critical);
  EXPECT_EQ(y.seam_target, p.seam_target);
  EXPECT_FALSE(b.loops[0][1].to_critical.has_value());
  ASSERT_TRUE(b.repair.has_value());
  EXPECT_EQ(b.repair->improve_below, r.improve_below);
  EXPECT_EQ(b.repair->tolerance, r.tolerance);
  EXPECT_EQ(b.repair->diagonal, r.diagonal);
  EXPECT_EQ(b.repair->min_edge, r.min_edge);
  EXPECT_EQ(b.repair->last_resort_min_edge, r.last_resort_min_edge);
  EXPECT_EQ(b.repair->measure_near_bound, r.measure_near_bound);
  EXPECT_EQ(b.repair->aim_mean_edge_ratio, r.aim_mean_edge_ratio);
  EXPECT_EQ(b.repair->threads, r.threads);
  EXPECT_EQ(b.repair->keep_boundary, r.keep_boundary);
  EXPECT_EQ(b.repair->count_near_boundary, r.count_near_boundary);
  EXPECT_EQ(b.repair->predict_estimates, r.predict_estimates);
  EXPECT_EQ(b.check_self_intersections, t.check_self_intersections);
}

TEST(BlockTasks, PiecesThatDoNotAnswerTheirTasksAreRefused) {
  const auto f = test::field_from_json(kTaskTorus);
  AdaptiveOptions o = task_options();
  // Two pieces swapped: each is another block's.
  o.block_runner = [&](const std::vector<std::string>& tasks) {
    std::vector<std::string> pieces;
    for (const auto& t : tasks) pieces.push_back(run_block_task(*f, t));
    std::swap(pieces[0], pieces[1]);
    return pieces;
  };
  EXPECT_THROW(polygonize_adaptive(*f, o), InvalidInputError);
  // A piece whose triangle names a vertex it lacks.
  BlockPart part;
  part.mesh.positions = {Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY()};
  part.mesh.normals = {Vec3::UnitZ(), Vec3::UnitZ(), Vec3::UnitZ()};
  part.target = part.mac = part.shape_index = {1, 1, 1};
  part.mesh.triangles = {{0, 1, 2}};
  EXPECT_NO_THROW(read_part(write_part(part)));
  part.mesh.triangles = {{0, 1, 3}};
  EXPECT_THROW(read_part(write_part(part)), InvalidInputError);
  part.mesh.triangles = {{0, 1, 2}};
  part.target = {1, 1};
  EXPECT_THROW(read_part(write_part(part)), InvalidInputError);
}

}  // namespace
}  // namespace cdp::adaptive
