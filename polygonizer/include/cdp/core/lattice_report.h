// What the lattice methods, Marching Cubes and Marching Tetrahedra (baselines/), report beside
// their mesh (PolygonizeStats::lattice). STATS.json writes it (cdp/io/polygonize_stats_json.h)
// under the keys docs/stats.md lists. The core declares it so that PolygonizeStats can hold it
// without depending on the baselines; their enums appear here by their option spellings.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>

namespace cdp {

// The continuation traversal's seeding and completion (Traversal::Continuation).
struct LatticeSeedingReport {
  int seed_resolution = 0;
  std::size_t seeds = 0;             // surface seeds found on the seed grid
  std::size_t unresolved_seeds = 0;  // seeds with no crossed cube near them
  std::size_t starts = 0;            // walks started (one per cluster of crossed cells)
  std::size_t seed_search_cubes = 0;
  std::size_t sign_changes = 0;      // of the seed grid
  std::size_t completion_starts = 0;       // walks started from sign changes no walk reached
  std::size_t unreached_sign_changes = 0;  // sign changes in detail the lattice does not resolve
  std::size_t completion_evaluations = 0;
};

struct LatticeReport {
  std::string traversal;       // "continuation" or "grid"
  std::string face_ambiguity;  // Marching Cubes' rule ("asymptotic_decider", ...); empty for MT
  double cell_size = 0;
  std::optional<int> precision;  // the paper's precision, when it set the cell
  std::array<long long, 3> cells{};  // lattice cells per axis
  double root_tolerance = 0;
  std::size_t cubes_visited = 0, cubes_crossed = 0;
  std::size_t corner_evaluations = 0, root_evaluations = 0;
  std::size_t centre_vertices = 0;  // vertices at the centre of a cube's polygon
  // The short-edge collapse after meshing (edges under a fraction of the cell).
  std::size_t collapsed_edges = 0, dropped_components = 0, short_edges_left = 0;
  std::optional<LatticeSeedingReport> seeding;  // Traversal::Continuation only
  // Faces of crossed cubes on the box's boundary, when a mesh open at the box is allowed.
  std::optional<std::size_t> open_boundary_faces;
};

}  // namespace cdp
