#include "stage_repair.h"

#include "../parallel.h"
#include "../union_find.h"
#include "resolve_settings.h"
#include "stage_checks.h"

#include <cdp/core/curvature.h>

#include <algorithm>
#include <array>
#include <numbers>
#include <utility>
#include <vector>

namespace cdp::adaptive {
namespace {

// A mesh that covers more than kOverlapArea times the area the seed grid measures has a front
// that ran over finished mesh: it is checked before the repair, which cannot take doubled
// surface away and would spend its rounds on the triangles where the sheets cross (blobs31 of
// the topology sweep at tolerance 3e-2: 45 s on a mesh of 469k triangles and 112k intersecting
// pairs, area 1.83 times the estimate, that the checks then refused). Each triangle is counted
// with its own crossing weight (|nx| + |ny| + |nz|, against the estimate's mean
// kMeanCrossings), so that a cube's faces (weight 1) do not pass for doubled surface. Meshes the
// checks pass measure 0.90-1.01 times the estimate on the topology sweep's fields; the failed
// ones, 1.13-1.94. Not for the crease-aware meshes, whose intersections are checked after the
// repair (it removes some that chords on an acute crease's two faces make).
constexpr double kOverlapArea = 1.25;

// Where the distance bound needs it, the repair's last resort (quality.h) may halve edges down
// to this share of the default min_edge: an edge between one and two min_edge long on a bend a
// little tighter than min_edge follows (blobs37 of the topology sweep at 1e-3: radius of
// curvature 0.0062, edges of 0.009 where 0.0077 keeps the bound, min_edge 0.0063) cannot be
// split into halves of min_edge.
constexpr double kLastResortEdgeShare = 0.5;

void check_overlap(const RunContext& run, const Settings& resolved, const SeedGridStage& seeds,
                   const CreaseLayout& creases, const Tracking& tracking, const Mesh& mesh,
                   std::optional<double>* sheets_gap) {
  if (creases.mesh || !(seeds.estimated_area > 0) || !(tracking.tracker->area() > kOverlapArea * seeds.estimated_area))
    return;
  double seen = 0;  // the area as the grid sees it
  for (const auto& t : mesh.triangles) {
    const Vec3& a = mesh.positions[t[0]];
    const Vec3 n = (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a);  // twice the area
    seen += 0.5 * n.cwiseAbs().sum() / kMeanCrossings;
  }
  if (seen > kOverlapArea * seeds.estimated_area) {
    run.enter("checks");
    check_mesh(mesh, tracking.seeding.seeds + creases.components, run.options.check_self_intersections,
               run.options.threads, run.options.cancel, nullptr, &run.field, resolved.sizing.min_edge, sheets_gap);
  }
}

QualityReport repair_patches(const Field& field, Mesh& mesh, const CreaseMesh& patches, const QualityOptions& qo,
                             BandChanges& band);

// After a repair in parts (the blocks' and their band's, the crease groups' and theirs), whose
// searches could not aim at the whole mesh's mean edge ratio: where that mean is over the aim,
// the whole mesh repaired once more with the search, as a mesh repaired at once would be, its
// counts added to `report` and its tolerance count taken as the mesh's (it measured every
// triangle). Returns whether it ran.
bool repair_whole_over_aim(const Field& field, Mesh& mesh, const QualityOptions& qo, QualityReport& report) {
  if (!(qo.aim_mean_edge_ratio > 0 && mean_edge_ratio(mesh, qo.threads) > qo.aim_mean_edge_ratio)) return false;
  const QualityReport whole = improve_mesh(field, mesh, qo);
  add_repair_counts(report, whole);
  report.over_tolerance = whole.over_tolerance;
  report.over_tolerance_worst = whole.over_tolerance_worst;
  report.over_tolerance_near = whole.over_tolerance_near;
  return true;
}

}  // namespace

QualityOptions repair_options(const RunContext& run, const Settings& resolved, const CreaseLayout& creases) {
  const AdaptiveOptions& options = run.options;
  QualityOptions qo;
  qo.improve_below = kRepairBelowDegrees * std::numbers::pi / 180;
  qo.tolerance = resolved.sizing.mode == SizingMode::Tolerance ? requested_tolerance(options, resolved) : 0;
  qo.diagonal = resolved.diagonal;
  qo.min_edge = resolved.sizing.min_edge;
  // The default min_edge is the sizing's floor, not the caller's: where the distance bound
  // needs it, the last resort may halve edges down to kLastResortEdgeShare of it. A min_edge
  // the caller set holds for every split.
  qo.last_resort_min_edge =
      options.min_edge > 0 ? resolved.sizing.min_edge : kLastResortEdgeShare * resolved.sizing.min_edge;
  qo.threads = options.threads;
  qo.cancel = options.cancel;
  // Neither the search nor the dense measurement before a split where a field with branch
  // points (min, max, abs) is meshed without following its creases (CreaseHandling::Ignore,
  // or a crease layout that failed; see QualityOptions): the triangles across a crease stay
  // stretched, so the mean is no aim. Meshed so, the creased shapes of
  // results/creases came out as often further from it as nearer, and the two spheres at
  // 5e-4 fell from 19.7 to 13.6 degrees; meshed along their creases they all came nearer.
  // A field with branch points whose crease tracing ran and found no crease (the hollow
  // sphere: its two sheets meet nowhere) is a smooth surface; one meshed without its layout
  // may have creases the mesh crosses.
  const bool no_crease =
      options.creases == CreaseHandling::Follow && creases.fallback.empty() && creases.traced.curves.empty();
  const bool across_creases = run.field.has_pieces() && !creases.mesh && !no_crease;
  qo.aim_mean_edge_ratio = across_creases ? 0 : kBoundMeanEdgeRatio;
  qo.measure_near_bound = !across_creases;
  // Decided here, on the run's own field, for every repair of the run alike: a block's repair in
  // lockstep sees a view of it whose calls are not costly (lockstep.h).
  qo.predict_estimates = run.field.predicts_from_hessians() || run.field.costly_calls() ? QualityOptions::Predict::Always
                                                                               : QualityOptions::Predict::Never;
  return qo;
}

QualityReport repair_mesh(const RunContext& run, const Settings& resolved, const SeedGridStage& seeds,
                          const CreaseLayout& creases, const BlockMeshing& blocks, const Tracking& tracking, Mesh& mesh,
                          BandChanges& band, std::optional<double>* sheets_gap) {
  band = {};
  if (run.options.variant != Variant::Improved) return {};
  check_overlap(run, resolved, seeds, creases, tracking, mesh, sheets_gap);
  run.enter("quality", "repairing triangles");
  const QualityOptions qo = repair_options(run, resolved, creases);
  if (!blocks.mesh) {
    if (creases.mesh && creases.mesh->group_ends.size() > 1) {
      const Mesh& patches = creases.mesh->mesh;
      // The patches as they were adopted, first: the tracker only adds to them.
      if (mesh.triangles.size() >= patches.triangles.size() &&
          std::equal(patches.triangles.begin(), patches.triangles.end(), mesh.triangles.begin()))
        return repair_patches(run.field, mesh, *creases.mesh, qo, band);
    }
    return improve_mesh(run.field, mesh, qo);
  }
  QualityReport report = blocks.quality;
  QualityOptions in_band = qo;
  in_band.aim_mean_edge_ratio = 0;  // as the blocks': the whole mesh's mean decides (below)
  const std::vector<char> sealed =
      run.options.check_self_intersections ? sealed_triangles(blocks, mesh) : std::vector<char>{};
  QualityReport own = repair_band(run.field, mesh, blocks.report.seam_vertices, blocks.vertices, in_band, band,
                                  sealed.empty() ? nullptr : &sealed, &blocks.report.cuts);
  add_repair_counts(report, own);
  // The relaxation's search (QualityOptions::aim_mean_edge_ratio) aims at the whole mesh's mean
  // edge ratio, which neither a block nor the band knows: where it is over the aim, the whole
  // mesh is repaired again with the search, as a mesh tracked alone would be (rare: the blocks'
  // meshes are better shaped; a block's own mean over it made the random blobs at 1e-3 search in
  // four of their eight blocks, 1.5 times the evaluations of the whole run).
  if (repair_whole_over_aim(run.field, mesh, qo, report))
    band = {};  // every vertex measured again (add_curvature_properties)
  // Afresh: the blocks' counts include triangles beside a seam that the band's repair changed.
  report.bad_after = triangles_under(mesh, qo.improve_below, qo.threads);
  return report;
}

namespace {

// What repair_parts did: the counts summed over the parts in part order, each input vertex's
// index after it (-1 for one removed), and per vertex after it whether a part moved or added it.
struct PartsRepair {
  QualityReport report;
  std::vector<int> renumbered;
  std::vector<char> changed;
};

// Repairs the triangles t of `mesh` with part[t] >= 0, each part (0 .. parts-1) cut out as an open
// mesh of its own and repaired with its boundary kept (QualityOptions::keep_boundary), the parts
// on up to `workers` threads: they share only boundary vertices, which no part moves, so each
// part's repair is the same whoever runs it and whenever. Put back in place: the vertices in their
// order without those removed, then each part's added ones, part by part; the triangles of no part
// in their order, then each part's. `measured_again` (optional, per vertex of `mesh`): see
// improve_mesh. `flags` (optional, per triangle): carried with the triangles of no part, 0 for
// the parts'.
PartsRepair repair_parts(const Field& field, Mesh& mesh, const std::vector<int>& part, std::size_t parts,
                         QualityOptions qo, const std::vector<char>* measured_again, std::vector<char>* flags,
                         unsigned workers) {
  const std::size_t nv = mesh.positions.size();
  std::vector<std::vector<int>> triangles(parts);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    if (part[t] >= 0) triangles[static_cast<std::size_t>(part[t])].push_back(static_cast<int>(t));
  struct Piece {
    Mesh mesh;
    std::vector<int> global;      // its input vertices' numbers in `mesh`, ascending
    std::vector<int> renumbered;  // improve_mesh's
    QualityReport report;
  };
  std::vector<Piece> pieces(parts);
  qo.keep_boundary = true;
  if (parts > 1 && workers > 1) qo.threads = 1;  // the parts are the threads' work
  detail::parallel_blocks(parts, 1, workers, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t g = begin; g < end; ++g) {
      Piece& p = pieces[g];
      for (int t : triangles[g])
        for (int v : mesh.triangles[static_cast<std::size_t>(t)]) p.global.push_back(v);
      std::sort(p.global.begin(), p.global.end());
      p.global.erase(std::unique(p.global.begin(), p.global.end()), p.global.end());
      const auto local = [&](int v) {
        return static_cast<int>(std::lower_bound(p.global.begin(), p.global.end(), v) - p.global.begin());
      };
      p.mesh.positions.reserve(p.global.size());
      p.mesh.normals.reserve(p.global.size());
      for (int v : p.global) {
        p.mesh.positions.push_back(mesh.positions[static_cast<std::size_t>(v)]);
        p.mesh.normals.push_back(mesh.normals[static_cast<std::size_t>(v)]);
      }
      p.mesh.triangles.reserve(triangles[g].size());
      for (int t : triangles[g]) {
        const auto& x = mesh.triangles[static_cast<std::size_t>(t)];
        p.mesh.triangles.push_back({local(x[0]), local(x[1]), local(x[2])});
      }
      std::vector<char> again;
      if (measured_again)
        for (int v : p.global) again.push_back((*measured_again)[static_cast<std::size_t>(v)]);
      p.report = improve_mesh(field, p.mesh, qo, &p.renumbered, measured_again ? &again : nullptr);
    }
  });

  PartsRepair out;
  for (const Piece& p : pieces) add_repair_counts(out.report, p.report);
  // In place, without a second copy of the mesh (at 1.85M triangles the copy was most of the
  // repair's memory, then the run's peak): a kept vertex or triangle moves down, never up, so
  // each is read before anything is written over it.
  std::vector<char> removed(nv, 0);
  for (const Piece& p : pieces)
    for (std::size_t l = 0; l < p.global.size(); ++l)
      if (p.renumbered[l] < 0) removed[static_cast<std::size_t>(p.global[l])] = 1;
  out.renumbered.assign(nv, -1);
  std::size_t kept = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    if (removed[v]) continue;
    out.renumbered[v] = static_cast<int>(kept);
    mesh.positions[kept] = mesh.positions[v];
    mesh.normals[kept] = mesh.normals[v];
    ++kept;
  }
  std::size_t added = 0, in_parts = 0;  // the vertices the parts added, their triangles
  for (const Piece& p : pieces) {
    added += p.mesh.positions.size() -
             static_cast<std::size_t>(std::count_if(p.renumbered.begin(), p.renumbered.end(), [](int r) { return r >= 0; }));
    in_parts += p.mesh.triangles.size();
  }
  mesh.positions.resize(kept);
  mesh.normals.resize(kept);
  // Room for what the parts add made once (a doubling would hold the old array beside the new),
  // and only that: the arrays' spare room (the blocks' assembly leaves some) often holds it, where
  // a new array is fresh pages (0.055 s for the torus at 1.85M triangles).
  mesh.positions.reserve(kept + added);
  mesh.normals.reserve(kept + added);
  out.changed.assign(kept, 0);
  std::vector<std::vector<int>> placed(parts);  // each part's vertex -> the output's
  for (std::size_t g = 0; g < parts; ++g) {
    const Piece& p = pieces[g];
    std::vector<int>& at = placed[g];
    at.assign(p.mesh.positions.size(), -1);
    for (std::size_t l = 0; l < p.global.size(); ++l)
      if (p.renumbered[l] >= 0)
        at[static_cast<std::size_t>(p.renumbered[l])] = out.renumbered[static_cast<std::size_t>(p.global[l])];
    for (std::size_t q = 0; q < at.size(); ++q) {
      if (at[q] < 0) {
        at[q] = static_cast<int>(mesh.positions.size());
        mesh.positions.push_back(p.mesh.positions[q]);
        mesh.normals.push_back(p.mesh.normals[q]);
        out.changed.push_back(1);
        continue;
      }
      const auto v = static_cast<std::size_t>(at[q]);
      if (mesh.positions[v] == p.mesh.positions[q]) continue;
      mesh.positions[v] = p.mesh.positions[q];
      mesh.normals[v] = p.mesh.normals[q];
      out.changed[v] = 1;
    }
  }
  std::size_t outside = 0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    if (part[t] < 0) {
      const auto x = mesh.triangles[t];
      if (flags) (*flags)[outside] = (*flags)[t];
      mesh.triangles[outside++] = {out.renumbered[x[0]], out.renumbered[x[1]], out.renumbered[x[2]]};
    }
  mesh.triangles.resize(outside);
  mesh.triangles.reserve(outside + in_parts);
  for (std::size_t g = 0; g < parts; ++g)
    for (const auto& x : pieces[g].mesh.triangles)
      mesh.triangles.push_back({placed[g][x[0]], placed[g][x[1]], placed[g][x[2]]});
  if (flags) {
    flags->resize(outside);
    flags->resize(mesh.triangles.size(), 0);
  }
  return out;
}

// Which part of the band triangle t is in: the cell of its centroid in a grid whose cells are
// centred on the cut planes (bounded by the planes halfway between two cuts), so that each
// part holds where the seams of one block corner's planes meet, and the parts' own boundaries
// cross the seams' strips halfway along them.
class BandCells {
 public:
  explicit BandCells(const std::array<std::vector<double>, 3>& cuts) {
    for (int a = 0; a < 3; ++a) {
      for (std::size_t i = 1; i < cuts[a].size(); ++i) mids_[a].push_back(0.5 * (cuts[a][i - 1] + cuts[a][i]));
      size_[a] = mids_[a].size() + 1;
    }
  }
  std::size_t cells() const { return size_[0] * size_[1] * size_[2]; }
  std::size_t cell(const Vec3& p) const {
    std::size_t c = 0;
    for (int a = 0; a < 3; ++a)
      c = c * size_[a] +
          static_cast<std::size_t>(std::upper_bound(mids_[a].begin(), mids_[a].end(), p[a]) - mids_[a].begin());
    return c;
  }

 private:
  std::array<std::vector<double>, 3> mids_;
  std::array<std::size_t, 3> size_{};
};

// The band's triangles (part[t] >= 0 on entry) numbered by the cell of their centroids
// (BandCells), the cells in order; `shared` flags each vertex two cells' triangles share.
// \return the number of parts.
std::size_t cell_parts(const Mesh& mesh, const std::array<std::vector<double>, 3>& cuts, std::vector<int>& part,
                       std::vector<char>& shared) {
  const BandCells cells(cuts);
  std::vector<int> id(cells.cells(), -1);
  for (std::size_t i = 0; i < part.size(); ++i)
    if (part[i] >= 0) {
      const auto& t = mesh.triangles[i];
      part[i] = static_cast<int>(cells.cell((mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3));
      id[static_cast<std::size_t>(part[i])] = 0;
    }
  std::size_t parts = 0;
  for (int& c : id)
    if (c == 0) c = static_cast<int>(parts++);
  std::vector<int> owner(mesh.positions.size(), -1);
  shared.assign(mesh.positions.size(), 0);
  for (std::size_t i = 0; i < part.size(); ++i)
    if (part[i] >= 0) {
      part[i] = id[static_cast<std::size_t>(part[i])];
      for (int v : mesh.triangles[i]) {
        int& o = owner[static_cast<std::size_t>(v)];
        if (o < 0) o = part[i];
        else if (o != part[i]) shared[static_cast<std::size_t>(v)] = 1;
      }
    }
  return parts;
}

// The triangles from `from` on (the band's, after its first pass) with a corner on or next to a
// vertex flagged in `again`, numbered by their components through shared vertices, in order of
// their first triangles; every other triangle -1.
std::vector<int> junction_parts(const Mesh& mesh, std::size_t from, const std::vector<char>& again, std::size_t& parts) {
  const std::size_t nt = mesh.triangles.size();
  std::vector<char> next(mesh.positions.size(), 0);
  for (std::size_t i = from; i < nt; ++i) {
    const auto& t = mesh.triangles[i];
    if (again[t[0]] || again[t[1]] || again[t[2]])
      for (int v : t) next[static_cast<std::size_t>(v)] = 1;
  }
  std::vector<int> part(nt, -1);
  UnionFind components(mesh.positions.size());
  for (std::size_t i = from; i < nt; ++i) {
    const auto& t = mesh.triangles[i];
    if (next[t[0]] || next[t[1]] || next[t[2]]) {
      part[i] = 0;
      components.unite(t[0], t[1]);
      components.unite(t[0], t[2]);
    }
  }
  std::vector<int> label(mesh.positions.size(), -1);
  parts = 0;
  for (std::size_t i = from; i < nt; ++i)
    if (part[i] >= 0) {
      int& l = label[static_cast<std::size_t>(components.find(mesh.triangles[i][0]))];
      if (l < 0) l = static_cast<int>(parts++);
      part[i] = l;
    }
  return part;
}

// Two repairs one after the other as one: the second's counts added to the first's (but
// bad_before, the first's: the second's were left by the first), each input vertex's index after
// both, and the vertices either moved or added, numbered after both.
PartsRepair one_after_the_other(PartsRepair first, const PartsRepair& second) {
  const std::size_t bad_before = first.report.bad_before;
  add_repair_counts(first.report, second.report);
  first.report.bad_before = bad_before;
  for (int& r : first.renumbered)
    if (r >= 0) r = second.renumbered[static_cast<std::size_t>(r)];
  std::vector<char> changed = second.changed;
  for (std::size_t u = 0; u < first.changed.size(); ++u)
    if (first.changed[u] && second.renumbered[u] >= 0) changed[static_cast<std::size_t>(second.renumbered[u])] = 1;
  first.changed = std::move(changed);
  return first;
}

}  // namespace

QualityReport repair_band(const Field& field, Mesh& mesh, std::size_t seams, std::size_t finished, QualityOptions qo,
                          BandChanges& band, const std::vector<char>* sealed,
                          const std::array<std::vector<double>, 3>* cuts) {
  const std::size_t nv = mesh.positions.size(), nt = mesh.triangles.size();
  // The seams and their neighbours.
  std::vector<char> near(nv, 0);
  for (std::size_t v = 0; v < std::min(seams, nv); ++v) near[v] = 1;
  for (const auto& t : mesh.triangles)
    if (static_cast<std::size_t>(std::min({t[0], t[1], t[2]})) < seams)
      for (int v : t) near[static_cast<std::size_t>(v)] = 1;
  // The band: the triangles with a corner among them or added beside the blocks.
  std::vector<int> part(nt, -1);
  for (std::size_t i = 0; i < nt; ++i)
    for (int v : mesh.triangles[i])
      if (near[static_cast<std::size_t>(v)] || static_cast<std::size_t>(v) >= finished) part[i] = 0;
  near = {};
  qo.count_near_boundary = true;
  std::vector<char> flags;
  if (sealed) flags = *sealed;
  std::vector<char>* carried = sealed ? &flags : nullptr;
  PartsRepair done;
  // One part, as on one thread, for a field whose calls are costly: its repair gathers the
  // band's evaluations into batches (a Python function), which parts would split.
  if (!cuts || field.costly_calls()) {
    done = repair_parts(field, mesh, part, 1, qo, nullptr, carried, 1);
    band.parts = 1;
  } else {
    const unsigned workers = field.thread_safe() ? detail::worker_count(qo.threads) : 1;
    // First the cells' parts side by side, each leaving out of its count the triangles beside a
    // vertex it shares with another part; ...
    std::vector<char> shared;
    band.parts = cell_parts(mesh, *cuts, part, shared);
    const std::size_t from = nt - static_cast<std::size_t>(std::count_if(part.begin(), part.end(), [](int p) { return p >= 0; }));
    done = repair_parts(field, mesh, part, band.parts, qo, &shared, carried, workers);
    // ... then the triangles beside those shared vertices (kept, so each is still there), in
    // parts that touch at most at a vertex, each counting all it measures.
    std::vector<char> again(mesh.positions.size(), 0);
    for (std::size_t v = 0; v < nv; ++v)
      if (shared[v]) again[static_cast<std::size_t>(done.renumbered[v])] = 1;
    shared = {};
    part = junction_parts(mesh, from, again, band.junctions);
    again = {};
    done = one_after_the_other(std::move(done),
                               repair_parts(field, mesh, part, band.junctions, qo, nullptr, carried, workers));
  }
  band.renumbered = std::move(done.renumbered);
  for (std::size_t v = 0; v < done.changed.size(); ++v)
    if (done.changed[v]) band.moved.push_back(static_cast<int>(v));
  if (sealed) band.sealed = std::move(flags);
  return done.report;
}

namespace {

// A crease-aware mesh repaired as blocks' meshes are: each group of patches (CreaseMesh::group_ends;
// the tracker's own components after them as one part more) cut out with its crease vertices
// as its kept boundary and repaired on its own, the groups on all threads (repair_parts: the same
// mesh on any number); then the band around the creases, where the groups' repairs could not
// flip, split or merge, as one open mesh (repair_band); then, where the whole mesh's mean edge
// ratio is over the aim that neither a group nor the band sees, the whole mesh again, as a mesh
// repaired at once would be. (Repaired at once, fogleman/sdf's README model at 1e-4, ten groups,
// spent as long in the repair as in meshing its patches, on one thread whatever the threads.)
// Unlike blocks, groups are not kept apart by planes: a group's repair tests its operations for
// crossings against its own triangles only, so where two groups' sheets lie within an edge of
// each other away from the creases (a thin wall), a crossing it makes is left to the final
// check (check_mesh: every pair), which then ends the crease-aware meshing with its message
// (Run::fall_back). None of the SDF sweep's 1,140 runs met one.
QualityReport repair_patches(const Field& field, Mesh& mesh, const CreaseMesh& patches, const QualityOptions& qo,
                             BandChanges& band) {
  const std::size_t nt = mesh.triangles.size(), groups = patches.group_ends.size();
  std::vector<int> part(nt, -1);
  std::size_t begin = 0;
  for (std::size_t g = 0; g < groups; ++g) {
    for (std::size_t t = begin; t < patches.group_ends[g]; ++t) part[t] = static_cast<int>(g);
    begin = patches.group_ends[g];
  }
  std::size_t parts = groups;
  if (begin < nt) {
    for (std::size_t t = begin; t < nt; ++t) part[t] = static_cast<int>(groups);
    ++parts;
  }
  QualityOptions in_parts = qo;
  in_parts.count_near_boundary = false;  // the band's repair measures them
  const unsigned workers = field.thread_safe() && !field.costly_calls() ? detail::worker_count(qo.threads) : 1u;
  const PartsRepair done = repair_parts(field, mesh, part, parts, in_parts, nullptr, nullptr, workers);
  QualityReport report = done.report;
  // The crease vertices are every group's boundary, kept: still the first, in their order.
  QualityOptions in_band = qo;
  in_band.aim_mean_edge_ratio = 0;
  BandChanges around;
  add_repair_counts(report, repair_band(field, mesh, patches.crease_vertices, mesh.positions.size(), in_band, around));
  repair_whole_over_aim(field, mesh, qo, report);
  band = {};  // every vertex measured again where curvature is asked for (add_curvature_properties)
  report.bad_before = done.report.bad_before;  // the parts hold every triangle; the band's were among them
  report.bad_after = triangles_under(mesh, qo.improve_below, qo.threads);
  return report;
}

}  // namespace

void add_curvature_properties(const Field& field, const Tracker& tracker, const QualityReport& quality,
                              const BandChanges& band, Mesh& mesh) {
  if (!band.renumbered.empty()) {
    // The tracker's (the blocks' measured again where their repairs moved vertices), renumbered,
    // and measured where the band's repair moved or added a vertex.
    const std::vector<double>& tmac = tracker.vertex_mac();
    const std::vector<double>& tshape = tracker.vertex_shape_index();
    std::vector<double> mac(mesh.positions.size()), shape(mesh.positions.size());
    for (std::size_t v = 0; v < band.renumbered.size(); ++v)
      if (band.renumbered[v] >= 0) {
        mac[static_cast<std::size_t>(band.renumbered[v])] = tmac[v];
        shape[static_cast<std::size_t>(band.renumbered[v])] = tshape[v];
      }
    std::vector<Vec3> at;
    for (int v : band.moved) at.push_back(mesh.positions[static_cast<std::size_t>(v)]);
    const std::vector<Curvature> c = curvatures_at(field, at);
    for (std::size_t i = 0; i < band.moved.size(); ++i) {
      mac[static_cast<std::size_t>(band.moved[i])] = c[i].mac;
      shape[static_cast<std::size_t>(band.moved[i])] = c[i].shape_index;
    }
    mesh.vertex_scalars["mac"] = std::move(mac);
    mesh.vertex_scalars["shape_index"] = std::move(shape);
    return;
  }
  if (quality.moves + quality.relaxed + quality.collapses + quality.splits + quality.inserts == 0) {
    mesh.vertex_scalars["mac"] = tracker.vertex_mac();
    mesh.vertex_scalars["shape_index"] = tracker.vertex_shape_index();
    return;
  }
  // The repair moved, removed or added vertices: measure them all where they are now.
  std::vector<double> mac(mesh.positions.size()), shape(mesh.positions.size());
  const std::vector<Curvature> c = curvatures_at(field, mesh.positions);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    mac[v] = c[v].mac;
    shape[v] = c[v].shape_index;
  }
  mesh.vertex_scalars["mac"] = std::move(mac);
  mesh.vertex_scalars["shape_index"] = std::move(shape);
}

}  // namespace cdp::adaptive
