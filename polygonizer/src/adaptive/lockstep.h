// Tasks in lockstep: independent tasks (a block's tracker, the seams of a block's face) that
// evaluate a field whose every call costs far more than the arithmetic of its points
// (Field::costly_calls: a Python function, each call a trip into the interpreter) run each on a
// stack of its own (a fiber: ../fiber.h), and every evaluation waits until each task still
// running has asked for one; then all of them are made together, one evaluation of the field for
// every kind asked for (values; values and gradients; gradients and Hessians:
// Field::evaluate_together, one call of a Python function). The tracker's calls
// come one after another (each expansion starts from the mesh the last one left), so one task
// cannot batch them; many tasks can.
//
// The k-th batch holds the k-th evaluation of every task that makes one, in carrier order,
// whatever the threads' timing: the same batches on every run and on any machine (a numpy
// function gets the same arrays), and each task the same numbers as it would get alone, so the
// same mesh as the tasks run one after another. All of it runs on the calling thread, so the field
// need not be thread-safe.
#pragma once

#include <cdp/core/field.h>

#include <cstddef>
#include <cstdint>
#include <functional>

namespace cdp::adaptive {

// At most this many tasks in flight, each on a stack of its own: the calls per vertex divide by
// about the tasks in flight (a tracker alone makes about five per vertex on the torus of
// python/README.md), and a batch of 64 trackers' Newton rounds and curvatures (with central
// differences, 7 and 25 points a point) stays near 10^3-10^4 points, where a numpy call costs its
// arithmetic rather than its entry.
constexpr std::size_t kLockstepTasks = 64;

struct LockstepReport {
  std::size_t carriers = 0;  // fibers that carried the tasks (at most kLockstepTasks)
  std::uint64_t batches = 0;  // gathered evaluations (Field::evaluate_together), one a round
};

// Runs task(view, i) for every i in [0, n): task i on carrier i % carriers (carriers =
// min(n, kLockstepTasks)), each carrier's tasks in increasing i, on the calling thread. `view`
// stands for `field` with every evaluation gathered with the other carriers' (above); it has no
// branch points and is not thread-safe, so a task evaluates it on its own carrier only. A task
// runs on a fiber's stack of Fiber::kDefaultStackBytes, with none of the calling thread's
// thread-local state (the run's pass clock, a lent helper).
// \pre `field` has no branch points (a black box: Field::costly_calls) and is evaluated by
//      nothing else meanwhile.
// \throw the exception of the lowest i whose task threw, after every carrier has ended (tasks
//        that must all run catch their own); LimitExceededError where the carriers' stacks cannot
//        be mapped (before any task runs).
LockstepReport run_in_lockstep(const Field& field, std::size_t n,
                               const std::function<void(const Field& view, std::size_t i)>& task);

}  // namespace cdp::adaptive
