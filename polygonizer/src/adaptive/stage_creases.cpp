#include "stage_creases.h"

#include <cdp/core/mesh_topology.h>

namespace cdp::adaptive {

namespace {

// The patches meshed with each of kPatchLookAheadGradations in turn until none stalls.
CreaseMesh mesh_patches(const Field& field, const CreaseTracingResult& traced, const Settings& settings,
                        double estimated_area) {
  for (std::size_t k = 0;; ++k) {
    try {
      return mesh_crease_patches(field, traced, settings, estimated_area, kPatchLookAheadGradations[k]);
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
  for (int attempt = 0; attempt < kCreaseTracings; ++attempt, co.resolution *= 2) {
    try {
      out.tracing_resolution = co.resolution;
      co.grid = attempt == 0 ? seed_grid : nullptr;
      out.traced = trace_creases(field, co);  // no work for a field without pieces
      if (!out.traced.curves.empty()) {
        if (attempt == 0 && options.phase) options.phase("meshing along creases");
        out.mesh = mesh_patches(field, out.traced, settings, estimated_area);
        out.components = analyze_topology(out.mesh->mesh).components;
        out.fallback.clear();
      }
      break;
    } catch (const CreaseLayoutError& e) {
      out.fallback = e.what();  // a crease the grid missed? A finer one may find it
    } catch (const NoSurfaceError& e) {
      out.fallback = e.what();
      break;
    } catch (const LimitExceededError& e) {
      out.fallback = e.what();
      break;
    }
  }
  return out;
}

}  // namespace cdp::adaptive
