// One block's work (blocks.h), all it needs besides the field, and what it returns: run on the
// run's threads, or as bytes in another process (cdp/core/block_tasks.h).
//   run_block               a block's tracker from its seams, its repair, its own check
//   write_task, read_task   a task as bytes and back (every double as it is: the same mesh)
//   write_part, read_part   a piece as bytes and back, a tracker's failure as its kind and message
#pragma once

#include "quality.h"
#include "tracker.h"

#include <cstddef>
#include <exception>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cdp::adaptive {

struct BlockTask {
  std::size_t block = 0;  // its index in block order, returned in its piece
  Settings settings;  // the run's, its cancel token left behind when sent
  double estimated_area = 0;  // the seed grid's (Tracker::set_estimated_area), 0 for none
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();  // the block's box
  std::vector<std::vector<Tracker::Placed>> loops;  // its boundary cycles, seam vertices measured
  std::optional<QualityOptions> repair;  // mesh_blocks' `repair`, the seams kept
  bool check_self_intersections = false;
};

struct BlockPart {
  std::size_t block = 0;  // its task's
  Mesh mesh;
  std::vector<std::vector<int>> ids;  // the part's vertex ids of the cycles' vertices
  std::vector<double> target, mac, shape_index;
  std::size_t steps = 0, splits = 0, merges = 0, forced_closures = 0, patch_refusals = 0;
  std::vector<CriticalStart> critical_starts;
  // Its tracker's counters (Tracker::report) and tightest bend (Tracker::tightest_bend), for the
  // run's report and its failure handling (a black box's kink met in a block).
  TrackerReport tracker;
  std::pair<double, Vec3> tightest{std::numeric_limits<double>::infinity(), Vec3::Zero()};
  QualityReport quality;
  double seconds = 0;
  std::exception_ptr error;  // what its tracker threw, kept for the block order to decide
};

// Meshes one block (what mesh_blocks' tasks do); every error is kept in the part's `error`.
BlockPart run_block(const Field& field, const BlockTask& task);

std::string write_task(const BlockTask& task);
// The cancel token is `cancel` (the worker's own).
// \throw InvalidInputError when the bytes are not a task of this build.
BlockTask read_task(std::string_view bytes, const CancelToken& cancel = {});

// The tracker's failures (CreaseLayoutError, StalledFrontError, LimitExceededError,
// NoSurfaceError, std::logic_error, CancelledError) travel as their kind and message and are
// made again by read_part; any other error (the field's) as a std::runtime_error with its message.
std::string write_part(const BlockPart& part);
// \throw InvalidInputError when the bytes are not a piece of this build, or its numbers disagree
// (an index past its vertices, a per-vertex array of another length).
BlockPart read_part(std::string_view bytes);

}  // namespace cdp::adaptive
