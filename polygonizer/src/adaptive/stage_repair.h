// The repair stage of a run (Variant::Improved): the mesh's triangles repaired to the quality
// bounds and, with a tolerance, refined to it (quality.h); the curvature properties measured
// where the repair moved vertices.
#pragma once

#include "blocks.h"
#include "quality.h"
#include "run_context.h"
#include "stage_creases.h"
#include "stage_tracking.h"

#include <array>
#include <cstddef>
#include <vector>

namespace cdp::adaptive {

// Variant::Improved repairs triangles whose smallest angle is under 30 degrees: the quality
// bounds (stage_checks.h) ask for every triangle at 20 degrees or more and 99% at 30 or more,
// and aiming the repair at the higher bound leaves the lower one a margin.
inline constexpr double kRepairBelowDegrees = 30;

// The repair's options for a run: its sizing, tolerance and aims (the blocks' repairs take them
// too, with their seams kept).
QualityOptions repair_options(const RunContext& run, const Settings& resolved, const CreaseLayout& creases);

// What the repair of a mesh meshed in blocks (repair_band) changed: each vertex's index after it
// (-1 for one removed) and the vertices, numbered after it, that it moved or added. Empty where
// the whole mesh was repaired.
struct BandChanges {
  std::vector<int> renumbered;
  std::vector<int> moved;
  // Per triangle after it: sealed (sealed_triangles, blocks.h) and outside the band, so that the
  // final check tests no pair of two such (check_mesh's `sealed`). Empty: test every pair.
  std::vector<char> sealed;
  // The parts the band was repaired in (repair_band's `cuts`): the cells' (1 for the band as one
  // open mesh), then those around the vertices two cells' parts share.
  std::size_t parts = 0, junctions = 0;
};

// Repairs `mesh` (tracked, the crease patches' components included in `creases`), where the
// variant repairs. A mesh whose area is well over the seed grid's estimate is checked first
// (check_mesh): it has a front that ran over finished mesh, which no repair mends. A mesh
// adopted from `blocks`, whose blocks each repaired their own, has only the band around their
// seams and what the tracker added repaired (repair_band; `band` says what changed), and the
// report sums the blocks' repairs and the band's, with the triangles under the repair's bound
// counted afresh.
// `resolved`: the run's settings as the options resolve them.
// \return what the repair did (empty for Variant::Paper).
// \throw NoSurfaceError from that check (where the mesh intersects itself between two sheets
//        closer than its edges, their distance goes to `sheets_gap`: check_mesh); CancelledError.
QualityReport repair_mesh(const RunContext& run, const Settings& resolved, const SeedGridStage& seeds,
                          const CreaseLayout& creases, const BlockMeshing& blocks, const Tracking& tracking, Mesh& mesh,
                          BandChanges& band, std::optional<double>* sheets_gap = nullptr);

// Repairs, with `qo` and the rest of the mesh kept as it is, the triangles of `mesh` that touch
// one of its first `seams` vertices (the blocks' seams) or a neighbour of one, and those with a
// vertex numbered `finished` or more (what the tracker meshed beside the blocks): cut out as one
// open mesh, repaired with its boundary kept (QualityOptions::keep_boundary), put back with its
// vertices in their places, those the repair added appended, those it removed dropped.
// `sealed` (optional, one flag per triangle of `mesh`): carried over to band.sealed for the
// triangles outside the band, 0 for the band's.
// `cuts` (optional, the blocks' cut planes): the band is repaired in parts, on the threads of
// qo.threads for a thread-safe field (the same mesh on any number): first the parts by the cells
// of a grid centred on the cut planes, then the triangles beside the vertices two of them share.
// Without, or for a field whose calls are costly, the band is repaired as one open mesh.
QualityReport repair_band(const Field& field, Mesh& mesh, std::size_t seams, std::size_t finished, QualityOptions qo,
                          BandChanges& band, const std::vector<char>* sealed = nullptr,
                          const std::array<std::vector<double>, 3>* cuts = nullptr);

// The "mac" and "shape_index" vertex scalars (AdaptiveOptions::curvature_properties): the
// tracker's own where the repair changed nothing, else measured again at every vertex (at the
// vertices `band` lists, after a band's repair).
void add_curvature_properties(const Field& field, const Tracker& tracker, const QualityReport& quality,
                              const BandChanges& band, Mesh& mesh);

}  // namespace cdp::adaptive
