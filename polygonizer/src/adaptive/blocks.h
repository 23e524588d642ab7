// Block-parallel tracking (AdaptiveOptions::blocks): the box is cut into blocks by planes that
// depend only on the field and the options (never on the thread count), the curves where the
// surface crosses the cuts are traced once and sampled with the sizing the surface asks for
// there (seams), and each block's piece of surface is meshed from its seams by fronts of its own,
// as a crease patch is meshed from its creases (crease_patches.h). Blocks run on
// AdaptiveOptions::threads threads (a field whose calls cost more than their points: in
// lockstep, lockstep.h); their meshes are assembled in block order, so the mesh is the
// same on any number of threads and in any order the blocks are run. Components that cross no
// cut are left to the seeding.
//
// The steps, each in one place (blocks.cpp):
//   choose_cuts     the cut planes: near equal shares of the box, through the middle of seed-grid
//                   cells, moved by up to kCutShift cells where the surface grazes the plane
//                   (a candidate the seed grid predicts to graze sampled last, predicted_lean)
//   sample_plane    a candidate plane's samples, evaluated only near the surface the seed grid sees
//   find_corners    where the surface crosses a block edge (F = 0 on a line), once per edge,
//                   every edge's roots bisected together
//   trace_face      every seam of one face of a block: from corner to corner, and loops found
//                   from the plane's samples (the faces one after another, or in lockstep)
//   block_cycles    each block's boundary cycles, its seams oriented with its patch on their left
//   mesh_blocks     one tracker per block from its cycles, on all threads, then one mesh
#pragma once

#include "crease_patches.h"
#include "missed_necks.h"
#include "quality.h"
#include "stage_seed_grid.h"

#include <cdp/core/adaptive_report.h>

#include <cstdint>
#include <exception>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

namespace cdp::adaptive {

struct BlockMeshing {
  // The blocks' meshes as one, seam vertices first (every component that crosses a cut, closed),
  // in the form crease patches come in, to be adopted as finished surface; none when the
  // surface was not cut (too small for blocks) or the layout or a block failed
  // (`report.fallback`).
  std::optional<CreaseMesh> mesh;
  std::size_t components = 0;  // of `mesh`
  // Of `mesh`, kept when the run moves its arrays into the tracker's mesh (`adopted`: from then
  // on `mesh` holds its counters only).
  std::size_t vertices = 0;
  bool adopted = false;
  // The blocks' trackers' vertices near critical points of F (Tracker::critical_starts), in
  // block order: where the neck search (check_necks) looks for necks their fronts stepped over.
  std::vector<CriticalStart> critical_starts;
  // Each meshed block's own vertices in `mesh` ([begin, end), seam vertices excluded) and its box:
  // a triangle of three of them whose box lies strictly inside it was in its block's check for
  // self-intersections and can meet no other block's (sealed_triangles).
  struct Own {
    std::size_t begin, end;
    Vec3 lo, hi;
  };
  std::vector<Own> own;
  // With a repair (mesh_blocks' `repair`): what the blocks' repairs did, summed over them (their
  // seams kept; the triangles beyond the tolerance near a seam are left to the band's repair,
  // repair_band, and not counted here).
  QualityReport quality;
  // The kept blocks' trackers' counters, summed (Tracker::report), and the tightest bend any
  // block's tracker met, kept or not (the first in block order among equals): the run's report
  // and failure handling add them.
  TrackerReport tracker;
  std::pair<double, Vec3> tightest{std::numeric_limits<double>::infinity(), Vec3::Zero()};
  // A block's tracker stopped at a kink of a black box (BlackBoxKinkError, creases: follow): no
  // mesh, and the run ends with this error (tracking alone would stop at the same kind of place).
  std::exception_ptr kink;
  // The blocks after `kink`'s in block order that its stop ended before they were done (their
  // parts, which could not change the outcome, dropped).
  std::size_t stopped = 0;
  // The stage's part of the run's stats (adaptive_report.h): the blocks, cuts, seams, times
  // (block_seconds: what the projected speedups at more threads are computed from) and the
  // fallback; the run adds what it alone knows (requested, used, components, steps, wall_*).
  BlocksReport report;
};

// Cuts the surface into blocks and meshes every block with seams (see above), on
// options.threads threads for a thread-safe field. Returns no mesh (and `report.fallback` saying why)
// where the seams cannot be laid out or a block's fronts fail (a NoSurfaceError,
// LimitExceededError or std::logic_error of its tracker; every block runs, and the first failing
// in block order decides): the caller then meshes the whole surface by tracking alone. Only for
// a surface without followed creases. The blocks run largest first; with `shuffle` nonzero, in
// an order drawn from it instead (the tests' check that the order changes nothing).
// `repair` (optional): each block's mesh is repaired in its task (improve_mesh with its seams
// kept, QualityOptions::keep_boundary), and its vertices' curvature measured again where the
// repair moved them; the band around the seams is the caller's to repair (repair_band). With
// options.check_self_intersections, each block's mesh is checked for intersecting triangles in
// its task too (a block whose mesh intersects itself fails as a stalled one does); the pairs
// across blocks and around the seams are the caller's (sealed_triangles).
// \throw CancelledError, and what the field's evaluations throw (the first block's in block order).
BlockMeshing mesh_blocks(const Field& field, const AdaptiveOptions& options, const Settings& settings,
                         const SeedGridStage& seeds, const QualityOptions* repair = nullptr,
                         std::uint64_t shuffle = 0);

// A cut plane p[a] = c sampled over the box at kPlaneSamples per seed-grid cell each way (its
// grazing, plane_lean, and the loops of the seams inside a face, trace_face, are found from them).
struct PlaneSamples {
  int a = 0, b = 1, d = 2;  // the plane's normal axis and the two axes in it (a+1, a+2 mod 3)
  double c = 0;             // p[a] = c
  int nb = 0, nd = 0;       // intervals along b and d
  Vec3 origin;
  double sb = 0, sd = 0;    // spacings
  // F at every sample; its gradient where F was evaluated, NaN at the samples the seed grid puts
  // far from the surface, whose value is the mean of their grid cell's nodes (kFarFromSurface).
  std::vector<double> values;
  std::vector<Vec3> gradients;
  Vec3 point(int i, int j) const {
    Vec3 p = origin;
    p[b] += sb * i;
    p[d] += sd * j;
    return p;
  }
  std::size_t index(int i, int j) const { return static_cast<std::size_t>(j) * (nb + 1) + i; }
};

// Samples the cut plane p[a] = c through the middle of `grid`'s cells of `layer` along a. Only
// the samples near the surface as the grid sees it are evaluated (kFarFromSurface in blocks.cpp:
// every sample within a sample spacing of the surface to first order), and those beside an
// evaluated one of the other sign; on `threads` threads for a thread-safe field.
// \throw what the field's evaluations throw.
PlaneSamples sample_plane(const Field& field, const SeedGrid& grid, int a, int layer, double c, int threads);

// The lean of the cut plane through the middle of the seed grid's cells of `layer` along `axis`
// (the smallest share of F's gradient in the plane near the surface, 1 where it is not near) as
// the layout's samples of the plane would measure it, predicted from the grid's values with no
// evaluation (F and its gradient from the grid's nodes either side of the plane; the columns
// within 0.4 of a cell of the surface count): choose_cuts samples a candidate predicted under
// kSkipLean only if no other is good.
double predicted_lean(const SeedGrid& grid, const Box& box, int axis, int layer);

// Whether a run meshes by blocks: AdaptiveOptions::blocks, or where unset, whether no bound on
// one tracker's work is given (max_steps, max_search_visits).
bool uses_blocks(const AdaptiveOptions& options);

// Whether the seed grid's estimate of the surface is large enough to cut into blocks (else
// mesh_blocks returns no mesh, and tracking alone meshes it).
bool worth_cutting(const Field& field, const SeedGridStage& seeds);

// Per triangle of `mesh` (the blocks' mesh as adopted, before the band's repair): whether it is
// sealed, one of a block's own triangles (three of its own vertices, BlockMeshing::own) whose box
// lies strictly inside the block's. Two sealed triangles of one block were in its own check; of
// two blocks, their boxes are apart. So only the pairs with a triangle not sealed are left to
// check (self_intersecting_pairs_involving).
std::vector<char> sealed_triangles(const BlockMeshing& blocks, const Mesh& mesh);

}  // namespace cdp::adaptive
