// Blocks meshed in other processes (AdaptiveOptions::block_runner): the adaptive method's blocks
// (AdaptiveOptions::blocks) depend only on the field and the options, so each block's tracker can
// run anywhere the same field can be built. The run lays the blocks out and hands each block's
// task, as bytes, to a runner; the runner has each task run by run_block_task (on a cluster's
// workers: python/cdp/distributed.py) and returns the pieces; the run assembles them in block
// order and goes on (the seeding of what no block holds, the repair of the band around the seams,
// the checks) as with blocks run on its own threads. The mesh is the same, bit for bit.
#pragma once

#include <cdp/core/field.h>

#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace cdp {

// Takes every block task of one layout (block order) and returns, in the same order, what
// run_block_task(field, task) returns for each, run with the run's own field (the same model,
// built by the same build of the library: the bytes are this build's memory layout, checked by a
// tag). Called on the run's thread, once per layout (a run that meshes again lays out again).
// Errors it throws end the run unchanged (a Python exception from a cluster stays one); pieces
// that do not answer their tasks (another block's, numbers that disagree) end it with
// InvalidInputError.
using BlockRunner = std::function<std::vector<std::string>(const std::vector<std::string>& tasks)>;

// Meshes one block from its task: its tracker from its seams, its repair with the seams kept, and
// the check for intersecting triangles, as the run does on its own threads. What the block's run
// throws travels in the piece, for the run to decide in block order as for its own blocks: a
// tracker's failure (a stalled front, a bound, a block's loops it cannot mesh) falls back to
// tracking alone, any other error (the field's: a Python function's) is raised by the run as a
// std::runtime_error with its message.
// \throw InvalidInputError when `task` is not a block task of this build.
std::string run_block_task(const Field& field, std::string_view task);

}  // namespace cdp
