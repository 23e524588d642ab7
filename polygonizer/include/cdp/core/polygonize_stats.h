// What every polygonization method reports (written as STATS.json by build/bin/polygonize):
// plain structs, typed. The core carries no JSON; `to_json` (cdp/io/polygonize_stats_json.h)
// writes them under the keys docs/stats.md lists.
#pragma once

#include <cdp/core/adaptive_report.h>
#include <cdp/core/field.h>
#include <cdp/core/lattice_report.h>
#include <cdp/core/mesh_angles.h>
#include <cdp/core/mesh_topology.h>

#include <cstddef>
#include <optional>
#include <string>

namespace cdp {

struct PolygonizeStats {
  std::string method;              // "adaptive", "mc", "mt"
  std::size_t triangles = 0;
  std::size_t vertices = 0;
  std::size_t components = 0;      // connected components of the output mesh
  double seconds = 0;              // wall-clock time of the polygonization itself
  EvaluationCounts field_evaluations;
  std::size_t splits = 0;          // adaptive only: front splits
  std::size_t merges = 0;          // adaptive only: front merges
  // The method's own report: the adaptive method's, or the lattice methods' (MC, MT).
  std::optional<AdaptiveReport> adaptive;
  std::optional<LatticeReport> lattice;
  // The mesh's angles, where a caller asked for them (add_angle_statistics, add_mesh_summary).
  std::optional<AngleStatistics> angles;
  // The mesh's topology, where a caller asked for it (add_mesh_summary): with the angles, the
  // short summary a user reads first (STATS.json's "summary").
  std::optional<MeshTopology> topology;
};

// Sets stats.angles and stats.topology from the mesh, as the polygonize program and the Python
// module report them for every method.
// \pre every triangle index is in [0, mesh.num_vertices()).
void add_mesh_summary(const Mesh& mesh, PolygonizeStats& stats);

}  // namespace cdp
