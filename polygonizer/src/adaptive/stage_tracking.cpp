#include "stage_tracking.h"

#include "../helper_thread.h"
#include "stage_checks.h"

#include <exception>
#include <sstream>
#include <string>

namespace cdp::adaptive {
namespace {

// One meshing: the crease patches' or blocks' mesh adopted as finished surface, then every component the
// seeding finds uncovered.
void mesh_surface(const RunContext& run, const SeedGridStage& seeds, CreaseMesh* finished, bool consume,
                  Settings& settings, bool rollback, Mesh& mesh, Tracking& tracking) {
  mesh = Mesh{};
  settings.rollback = rollback;
  tracking.note_tightest();  // of the meshing this one replaces
  Tracker& tracker = tracking.tracker.emplace(run.field, settings, mesh);
  if (seeds.estimated_area > 0) tracker.set_estimated_area(seeds.estimated_area);
  if (run.options.progress) tracker.set_progress(run.options.progress);
  if (finished && consume) {
    mesh.positions = std::move(finished->mesh.positions);
    mesh.normals = std::move(finished->mesh.normals);
    mesh.triangles = std::move(finished->mesh.triangles);
    tracker.adopt_finished(std::move(finished->target), std::move(finished->mac), std::move(finished->shape_index));
  } else if (finished) {
    mesh.positions = finished->mesh.positions;
    mesh.normals = finished->mesh.normals;
    mesh.triangles = finished->mesh.triangles;
    tracker.adopt_finished(finished->target, finished->mac, finished->shape_index);
  }
  {
    // The tracker's field calls come one or two points at a time: a costly field may run half
    // of each on a second core, with the same bits (helper_thread.h). Lent for the tracking
    // only, which runs no parallel pass beside it.
    const detail::LendHelper helper(run.options.threads);
    struct Count {  // the splits of a run that throws count too, as its phases do
      PhaseLedger& phases;
      const detail::LendHelper& helper;
      ~Count() { phases.add_split_evaluations(helper.tasks_run()); }
    } count{run.phases, helper};
    tracking.seeding =
        seed_every_component(run.field, seeds.grid, settings.sizing.min_edge, settings.hash_cell, tracker, mesh,
                             consume ? nullptr : &tracking.bridges);
  }
  tracker.compact();
}

}  // namespace

void track_surface(const RunContext& run, const SeedGridStage& seeds, CreaseMesh* finished, bool consume,
                   std::size_t finished_components, Settings& settings, Mesh& mesh, Tracking& tracking) {
  run.enter("tracking", "meshing");
  tracking.remeshed = false;
  tracking.bridges.found.clear();
  try {
    mesh_surface(run, seeds, finished, consume, settings, settings.anticipate, mesh, tracking);  // careful runs roll back from the start
  } catch (const StalledFrontError& stalled) {
    if (settings.anticipate || consume) throw;  // consumed: nothing left to adopt again
    // The rollbacks undo such places where they begin. Surfaces that mesh without them are
    // never meshed with them, so they come out exactly as before. When the second run fails
    // too, or its mesh fails the checks (a rollback has been seen to leave a non-manifold edge:
    // the printed triangle count on the bunny VIS-800 at factor 1), the first run's error stands.
    try {
      tracking.remeshed = true;
      mesh_surface(run, seeds, finished, false, settings, true, mesh, tracking);
      if (tracking.seeding.uncovered > 0) throw NoSurfaceError("uncovered sign changes");
      run.enter("checks");
      check_mesh(mesh, tracking.seeding.seeds + finished_components, run.options.check_self_intersections,
                 run.options.threads, run.options.cancel);
    } catch (const CancelledError&) {
      throw;
    } catch (const std::exception&) {
      throw stalled;
    }
  }
  const SeedingReport& seeding = tracking.seeding;
  if (mesh.triangles.empty() && seeding.sign_changes == 0) {
    tracking.no_crossing = true;
    std::ostringstream msg;
    msg << "adaptive: no zero crossing of the field in its box " << describe_point(run.field.bounds().min) << " - "
        << describe_point(run.field.bounds().max) << " at seed resolution " << run.options.seed_resolution
        << " (F is " << (seeds.grid.values[0] < 0 ? "negative" : "positive") << " everywhere sampled)";
    throw NoSurfaceError(msg.str());
  }
  if (mesh.triangles.empty())
    throw NoSurfaceError("adaptive: the field changes sign but no seed could be meshed (vanishing gradient)");
  if (seeding.unsearched_cells > 0) {
    std::ostringstream msg;
    msg << "adaptive: the search for components that no seed-grid edge crosses stopped at its bound ("
        << seeding.refined_cells << " cells split, as many as its budget allows) with " << seeding.unsearched_cells
        << " cells left that may hold surface, the first near " << describe_point(seeding.first_unsearched)
        << ": the field's bounds on its values and slope prove little there (a noisy scan's interpolant, a "
           "loose Lipschitz bound), and a small component may be missing; smoothing the field (a scan's samples), "
           "or a seed grid fine enough to cross such components (seed_resolution), meshes it";
    throw UnsearchedCellsError(msg.str());
  }
  if (seeding.uncovered > 0)
    throw NoSurfaceError("adaptive: " + std::to_string(seeding.uncovered) +
                         " sign changes of the field are not covered by the mesh, the first near " +
                         describe_point(seeding.first_uncovered) +
                         " (a singular point or a feature thinner than min_edge?)");
}

}  // namespace cdp::adaptive
