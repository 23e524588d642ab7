#include "stage_creases.h"

#include "stage_seed_grid.h"

#include <cdp/core/mesh_topology.h>

namespace cdp::adaptive {

namespace {

// The patches meshed with each of kPatchLookAheadGradations in turn until none stalls.
CreaseMesh mesh_patches(const Field& field, const CreaseTracingResult& traced, const Settings& settings,
                        double estimated_area, int threads) {
  for (std::size_t k = 0;; ++k) {
    try {
      return mesh_crease_patches(field, traced, settings, estimated_area, kPatchLookAheadGradations[k], threads);
    } catch (const StalledFrontError&) {
      if (k + 1 == kPatchLookAheadGradations.size()) throw;
    }
  }
}

}  // namespace

CreaseLayout lay_out_creases(const Field& field, const AdaptiveOptions& options, const Settings& settings,
                             double estimated_area, const SeedGrid* seed_grid) {
  CreaseLayout out;
  if (!follows_creases(options)) return out;
  CreaseTracingOptions co;
  co.resolution = options.seed_resolution;
  co.cancel = &options.cancel;
  co.progress = options.progress;
  for (int attempt = 0; attempt < kCreaseTracings; ++attempt, co.resolution *= 2) {
    try {
      out.tracing_resolution = co.resolution;
      out.estimated_area = estimated_area;
      // A grid of its own past the seed grid, sampled here so that its measure of the surface
      // bounds the patches (a field without pieces has no creases: no grid).
      SeedGrid finer;
      co.grid = attempt == 0 ? seed_grid : nullptr;
      if (!co.grid && field.has_pieces()) {
        SeedOptions so;
        so.resolution = co.resolution;
        so.require_closed_in_box = false;
        so.threads = options.threads;
        finer = sample_seed_grid(field, so);
        co.grid = &finer;
        out.estimated_area = std::max(estimated_area, measured_area(finer));
      }
      // No work for a field without pieces. A CSG model's creases may take seconds (fogleman/sdf's
      // knurling example: 14 s), so the phase is named and its progress reported.
      if (field.has_pieces() && options.phase) options.phase(attempt == 0 ? "tracing creases" : "tracing creases again");
      out.traced = trace_creases(field, co);
      if (!out.traced.curves.empty()) {
        if (attempt == 0 && options.phase) options.phase("meshing along creases");
        out.mesh = mesh_patches(field, out.traced, settings, out.estimated_area, options.threads);
        out.components = analyze_topology(out.mesh->mesh).components;
        out.fallback.clear();
      }
      break;
    } catch (const CreaseVertexError& e) {
      // A crease turning faster than the tracer's max_turn allows at its shortest step is
      // followed by chords of that step (a rim of radius 0.0025 by three or four, up to 0.0012
      // inside it), and laying it out on the edges of a lowered min_edge (0.00083) projects
      // vertices from points on those chords that land more than half an edge away. Traced
      // again in steps down to min_edge. (Down to min_edge from the start, the Barth ball's
      // lowered run laid out a network whose patches ran out of the box.)
      out.fallback = e.what();
      co.min_step = settings.sizing.min_edge;
    } catch (const CreaseLayoutError& e) {
      out.fallback = e.what();  // a crease the grid missed? A finer one may find it
    } catch (const NoSurfaceError& e) {
      out.fallback = e.what();
      if (out.traced.curves.empty()) break;
    } catch (const LimitExceededError& e) {
      // The patches' fronts stalled or ran on: a patch the grid missed a crease of (a table top
      // thinner than a seed cell, flush on a leg: only the leg's creases were found, and the
      // underside's patch round the leg had no outer edge) is bounded on a finer grid.
      out.fallback = e.what();
      if (out.traced.curves.empty()) break;
    }
  }
  return out;
}

}  // namespace cdp::adaptive
