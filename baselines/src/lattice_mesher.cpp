#include "lattice_mesher.h"

#include "edge_root.h"
#include "flat_map.h"
#include "short_edge_collapse.h"

#include <cdp/core/errors.h>
#include <cdp/core/mesh_topology.h>
#include <cdp/core/newton_projection.h>
#include <cdp/core/surface_seeds.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <optional>
#include <sstream>
#include <string>

namespace cdp::marching {

namespace {

// Bits of a visited cube's value that hold its triangle count (at most 6 tetrahedra x 2, or
// a Marching Cubes case with a fanned 12-gon: well below 256).
constexpr int kTriangleRangeBits = 8;

// A seed-grid crossing the mesh does not cover is located to this fraction of a cell, enough to
// name the cube the surface passes through there (give or take a neighbour, which the search
// for a crossed cube around it looks at anyway).
constexpr double kSignChangeRootTolerance = 0.125;

// Mesh edges shorter than this fraction of a cell are collapsed. A root next to a lattice
// corner (the surface passing within a hair of it, or through it: F = 0 there on creased and
// signed-distance fields) puts vertices on all the corner's crossed edges within that hair of
// each other, and the triangles between them have edge ratios up to 10^6. A hundredth of a cell
// bounds the ratio by about (sqrt(3) + 0.01) / 0.01 < 175 while touching about 1 % of the
// vertices (0.5 % in Marching Cubes, 1.5 % in Marching Tetrahedra on random blobs).
constexpr double kShortEdge = 0.01;

// Edge roots (and centre vertices) wait until this many are pending, then are searched together,
// one batched evaluation per round of regula falsi: thousands of points per call for a field
// whose calls cost more than their arithmetic (a Python function), while the searches' state
// (about 150 bytes each) stays within a core's cache for the compiled fields.
constexpr std::size_t kRootBatch = 4096;

using Key = std::uint64_t;
using Cell = std::array<long, 3>;

std::string format_point(const Vec3& p) {
  std::ostringstream s;
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return s.str();
}

// Faces (numbered as in cube_cases.h) whose corners are not all on one side.
int crossed_faces(const std::array<double, 8>& f) {
  static constexpr int faces[6][4] = {{0, 2, 4, 6}, {1, 3, 5, 7}, {0, 1, 4, 5}, {2, 3, 6, 7}, {0, 1, 2, 3}, {4, 5, 6, 7}};
  int mask = 0;
  for (int face = 0; face < 6; ++face) {
    int in = 0;
    for (int c : faces[face]) in += f[c] < 0;
    if (in != 0 && in != 4) mask |= 1 << face;
  }
  return mask;
}

class LatticeMesher {
 public:
  LatticeMesher(const Field& field, const MarchingOptions& options, const char* method, const CubeMesher& mesher)
      : field_(field), options_(options), method_(method), mesher_(mesher) {
    h_ = resolve_cell_size(field, options);
    lattice_ = make_marching_lattice(field, h_);
    n_ = lattice_.cells;
    tolerance_ = options.root_tolerance > 0 ? options.root_tolerance : 1e-6 * h_;
    if (!std::isfinite(tolerance_)) throw InvalidInputError(std::string(method_) + ": root_tolerance must be finite");
    if (options.seed_resolution < 2) throw InvalidInputError(std::string(method_) + ": seed_resolution must be at least 2");
    if (options.threads < 0) throw InvalidInputError(std::string(method_) + ": threads must be 0 (all cores) or positive");
  }

  void run_grid();
  void run_continuation();
  // Gives every vertex created so far its position: the pending edge roots, then the pending
  // centre vertices (whose starting points are means of edge roots).
  void resolve_pending();

  Mesh mesh;
  // Per vertex, a name independent of the traversal: the lattice edge it lies on, or for a
  // centre vertex its cube and polygon (top bit set).
  std::vector<Key> vertex_keys;
  double h_ = 0, tolerance_ = 0;
  MarchingLattice lattice_;
  std::size_t cubes_visited = 0, cubes_crossed = 0, seed_search_cubes = 0, open_boundary_faces = 0;
  std::size_t root_evaluations = 0, corner_evaluations = 0, centre_vertices = 0, starts = 0, seeds = 0, unresolved_seeds = 0;
  std::size_t sign_changes = 0, completion_starts = 0, unreached_sign_changes = 0, completion_evaluations = 0;

 private:
  Key point_key(long i, long j, long k) const {
    return static_cast<Key>(i) +
           static_cast<Key>(n_[0] + 1) * (static_cast<Key>(j) + static_cast<Key>(n_[1] + 1) * static_cast<Key>(k));
  }
  Key cell_key(const Cell& c) const {
    return static_cast<Key>(c[0]) + static_cast<Key>(n_[0]) * (static_cast<Key>(c[1]) + static_cast<Key>(n_[1]) * c[2]);
  }
  Vec3 point(long i, long j, long k) const {
    const Vec3& o = lattice_.origin;
    return Vec3(o.x() + h_ * static_cast<double>(i), o.y() + h_ * static_cast<double>(j),
                o.z() + h_ * static_cast<double>(k));
  }
  bool in_lattice(const Cell& c) const {
    for (int a = 0; a < 3; ++a)
      if (c[a] < 0 || c[a] >= n_[a]) return false;
    return true;
  }
  void check_finite(const Vec3& p, double v) const {
    if (!std::isfinite(v))
      throw NoSurfaceError(std::string(method_) + ": the field is not finite (" + std::to_string(v) + ") at " +
                           format_point(p));
  }

  std::array<double, 8> cached_corners(const Cell& c);
  void prefetch_corners(const std::deque<Cell>& cubes);
  void check_boundary(const Cell& c, int mask);
  void mesh_cube(const Cell& c, const std::array<double, 8>& f);
  int vertex(const Cell& c, LocalEdge e, const std::array<double, 8>& f);
  int centre_vertex(const Cell& c, int polygon, const std::array<double, 8>& f);
  std::optional<Cell> crossed_cube_near(const Vec3& p);
  bool follow(const Cell& start, std::size_t cluster, std::size_t clusters);
  int mesh_crossings(const Vec3& a, const Vec3& b, int axis);
  void complete_from_sign_changes(const SeedGrid& grid, std::size_t clusters);
  void count_cube() {
    if (++cubes_visited > options_.max_cubes)
      throw LimitExceededError(std::string(method_) + ": more than max_cubes = " + std::to_string(options_.max_cubes) +
                               " cubes visited");
  }

  const Field& field_;
  const MarchingOptions& options_;
  const char* method_;
  const CubeMesher& mesher_;
  std::array<long, 3> n_{};
  FlatMap<double> corner_cache_;
  FlatMap<int> edge_vertex_;
  // Visited cubes; once meshed, the value is the cube's triangles (kTriangleRangeBits of
  // count below the index of the first), which are contiguous in mesh.triangles.
  FlatMap<std::uint64_t> visited_;
  CubeMesh cube_mesh_;
  std::vector<int> centre_ids_;
  double progress_reported_ = 0;
  // Vertices whose positions wait for resolve_pending(): nothing reads a vertex position while
  // the cubes are walked (the mesh's topology follows from the corner signs alone) until the
  // completion step tests the mesh against the seed grid, so the roots are searched in batches.
  std::vector<EdgeRootQuery> pending_roots_;
  std::vector<int> pending_root_ids_;
  struct PendingCentre {
    int id;
    std::size_t first, count;  // its polygon's vertex ids in pending_centre_vertices_
  };
  std::vector<PendingCentre> pending_centres_;
  std::vector<int> pending_centre_vertices_;
  std::vector<EdgeRoot> roots_;
  std::vector<int> centre_polygon_;
  std::vector<Key> prefetch_keys_;
  std::vector<Vec3> prefetch_points_;
  std::vector<double> prefetch_values_;
};

std::array<double, 8> LatticeMesher::cached_corners(const Cell& c) {
  std::array<double, 8> f;
  std::array<Key, 8> keys;
  std::array<int, 8> missing;
  std::array<Vec3, 8> points;
  int m = 0;
  for (int q = 0; q < 8; ++q) {
    const long i = c[0] + (q & 1), j = c[1] + ((q >> 1) & 1), k = c[2] + ((q >> 2) & 1);
    keys[q] = point_key(i, j, k);
    if (const double* cached = corner_cache_.find(keys[q])) {
      // Prefetched values are checked here, where the cube that first needs them would have
      // evaluated them, so that a field that is not finite fails at the same place.
      if (!std::isfinite(*cached)) check_finite(point(i, j, k), *cached);
      f[q] = *cached;
    } else {
      missing[m] = q;
      points[m++] = point(i, j, k);
    }
  }
  if (m > 0) {
    std::array<double, 8> values;
    field_.values(points.data(), values.data(), m);
    corner_evaluations += m;
    for (int r = 0; r < m; ++r) {
      check_finite(points[r], values[r]);
      f[missing[r]] = values[r];
      corner_cache_.emplace(keys[missing[r]], values[r]);
    }
  }
  return f;
}

// Evaluates the corners of the queued cubes that are not in the cache, in one batched call:
// every queued cube is meshed before the walk ends, so these are the very evaluations that
// cached_corners would make one cube at a time, in another grouping.
void LatticeMesher::prefetch_corners(const std::deque<Cell>& cubes) {
  prefetch_keys_.clear();
  prefetch_points_.clear();
  for (const Cell& c : cubes)
    for (int q = 0; q < 8; ++q) {
      const long i = c[0] + (q & 1), j = c[1] + ((q >> 1) & 1), k = c[2] + ((q >> 2) & 1);
      const Key key = point_key(i, j, k);
      // A placeholder, so that a corner shared by queued cubes is asked for once.
      if (!corner_cache_.emplace(key, 0.0).second) continue;
      prefetch_keys_.push_back(key);
      prefetch_points_.push_back(point(i, j, k));
    }
  if (prefetch_keys_.empty()) return;
  prefetch_values_.resize(prefetch_keys_.size());
  field_.values(prefetch_points_.data(), prefetch_values_.data(), prefetch_points_.size());
  corner_evaluations += prefetch_points_.size();
  for (std::size_t r = 0; r < prefetch_keys_.size(); ++r) *corner_cache_.find(prefetch_keys_[r]) = prefetch_values_[r];
}

void LatticeMesher::check_boundary(const Cell& c, int mask) {
  for (int face = 0; face < 6; ++face) {
    if (!((mask >> face) & 1)) continue;
    const int axis = face / 2;
    const bool on_boundary = face % 2 == 0 ? c[axis] == 0 : c[axis] == n_[axis] - 1;
    if (!on_boundary) continue;
    if (options_.require_closed_in_box)
      throw NoSurfaceError(std::string(method_) + ": the surface leaves the lattice near " +
                           format_point(point(c[0], c[1], c[2])) +
                           " (F < 0 on the boundary of the box); give larger \"bounds\"");
    ++open_boundary_faces;
  }
}

int LatticeMesher::vertex(const Cell& c, LocalEdge e, const std::array<double, 8>& f) {
  const long ia = c[0] + (e.a & 1), ja = c[1] + ((e.a >> 1) & 1), ka = c[2] + ((e.a >> 2) & 1);
  const Key key = point_key(ia, ja, ka) * 8 + static_cast<Key>(e.a ^ e.b);
  const auto [id, inserted] = edge_vertex_.emplace(key, static_cast<int>(mesh.positions.size()));
  if (!inserted) return *id;
  const Vec3 pb = point(c[0] + (e.b & 1), c[1] + ((e.b >> 1) & 1), c[2] + ((e.b >> 2) & 1));
  pending_roots_.push_back({point(ia, ja, ka), pb, f[e.a], f[e.b]});
  pending_root_ids_.push_back(*id);
  mesh.positions.push_back(Vec3::Zero());  // until resolve_pending()
  vertex_keys.push_back(key);
  if (pending_roots_.size() >= kRootBatch) resolve_pending();
  return *id;
}

// The mean of the polygon's crossings, moved onto the surface by the Newton projection when it
// converges within half a cell (it is left at the mean otherwise).
int LatticeMesher::centre_vertex(const Cell& c, int polygon, const std::array<double, 8>& f) {
  int& id = centre_ids_[polygon];
  if (id >= 0) return id;
  // Gathered apart: vertex() may resolve what is pending on the way, which empties the lists.
  centre_polygon_.clear();
  for (LocalEdge e : cube_mesh_.centres[polygon]) centre_polygon_.push_back(vertex(c, e, f));
  id = static_cast<int>(mesh.positions.size());
  pending_centres_.push_back({id, pending_centre_vertices_.size(), centre_polygon_.size()});
  pending_centre_vertices_.insert(pending_centre_vertices_.end(), centre_polygon_.begin(), centre_polygon_.end());
  mesh.positions.push_back(Vec3::Zero());  // until resolve_pending()
  vertex_keys.push_back(Key{1} << 63 | cell_key(c) << 4 | static_cast<Key>(polygon));
  ++centre_vertices;
  return id;
}

void LatticeMesher::resolve_pending() {
  // Taken off the lists first, so that a search that throws leaves nothing pending to retry.
  std::vector<EdgeRootQuery> queries;
  std::vector<int> ids, centre_vertices;
  std::vector<PendingCentre> centres;
  queries.swap(pending_roots_);
  ids.swap(pending_root_ids_);
  centres.swap(pending_centres_);
  centre_vertices.swap(pending_centre_vertices_);
  if (!queries.empty()) {
    find_edge_roots(field_, queries, tolerance_, roots_);
    for (std::size_t r = 0; r < roots_.size(); ++r) {
      root_evaluations += roots_[r].evaluations;
      mesh.positions[ids[r]] = roots_[r].point;
    }
  }
  if (centres.empty()) return;
  // A centre's polygon vertices are edge roots created before it, resolved above or earlier.
  std::vector<Vec3> means;
  means.reserve(centres.size());
  for (const PendingCentre& pc : centres) {
    Vec3 mean = Vec3::Zero();
    for (std::size_t v = pc.first; v < pc.first + pc.count; ++v) mean += mesh.positions[centre_vertices[v]];
    mean /= static_cast<double>(pc.count);
    means.push_back(mean);
  }
  ProjectionOptions po;
  po.tolerance = tolerance_;
  po.max_iterations = 20;
  po.max_step = 0.5 * h_;
  po.max_travel = 0.5 * h_;
  const std::vector<ProjectionOptions> options(means.size(), po);
  const std::vector<ProjectionResult> projected = project_to_surface(field_, means, options);
  for (std::size_t q = 0; q < means.size(); ++q)
    mesh.positions[centres[q].id] = projected[q].ok() ? projected[q].point : means[q];
}

void LatticeMesher::mesh_cube(const Cell& c, const std::array<double, 8>& f) {
  cube_mesh_.clear();
  mesher_(f, cube_mesh_);
  if (cube_mesh_.triangles.empty()) return;
  ++cubes_crossed;
  centre_ids_.assign(cube_mesh_.centres.size(), -1);
  const auto id = [&](LocalEdge e) { return e.a == kCentre ? centre_vertex(c, e.b, f) : vertex(c, e, f); };
  for (const CubeTriangle& t : cube_mesh_.triangles) mesh.triangles.push_back({id(t[0]), id(t[1]), id(t[2])});
  if (mesh.triangles.size() > options_.max_triangles)
    throw LimitExceededError(std::string(method_) + ": more than max_triangles = " +
                             std::to_string(options_.max_triangles) + " triangles");
}

void LatticeMesher::run_grid() {
  const double total = static_cast<double>(n_[0]) * static_cast<double>(n_[1]) * static_cast<double>(n_[2]);
  if (total > static_cast<double>(options_.max_cubes))
    throw LimitExceededError(std::string(method_) + ": the grid has " + std::to_string(static_cast<long long>(total)) +
                             " cubes, more than max_cubes = " + std::to_string(options_.max_cubes));
  const long sx = n_[0] + 1, sy = n_[1] + 1;
  std::vector<Vec3> points(static_cast<std::size_t>(sx * sy));
  std::vector<double> lower(points.size()), upper(points.size());
  const auto sample_slab = [&](long k, std::vector<double>& out) {
    for (long j = 0; j < sy; ++j)
      for (long i = 0; i < sx; ++i) points[j * sx + i] = point(i, j, k);
    field_.values(points.data(), out.data(), points.size());
    corner_evaluations += points.size();
    for (std::size_t q = 0; q < points.size(); ++q) check_finite(points[q], out[q]);
  };
  sample_slab(0, lower);
  for (long k = 0; k < n_[2]; ++k) {
    sample_slab(k + 1, upper);
    for (long j = 0; j < n_[1]; ++j)
      for (long i = 0; i < n_[0]; ++i) {
        std::array<double, 8> f;
        for (int q = 0; q < 8; ++q)
          f[q] = (q & 4 ? upper : lower)[(j + ((q >> 1) & 1)) * sx + i + (q & 1)];
        const int mask = crossed_faces(f);
        if (mask == 0) continue;
        const Cell c{i, j, k};
        check_boundary(c, mask);
        mesh_cube(c, f);
      }
    std::swap(lower, upper);
    options_.cancel.check("marching");
    if (options_.progress) options_.progress(static_cast<double>(k + 1) / static_cast<double>(n_[2]));
  }
  cubes_visited = static_cast<std::size_t>(total);
}

// The cube holding p, or failing that the nearest cube within two cells (Chebyshev distance,
// in a fixed order) whose corners straddle the surface: a seed can lie in a cube the surface
// crosses without changing the sign of any corner.
std::optional<Cell> LatticeMesher::crossed_cube_near(const Vec3& p) {
  Cell base;
  for (int a = 0; a < 3; ++a) {
    const double x = std::floor((p[a] - lattice_.origin[a]) / h_);
    base[a] = static_cast<long>(std::clamp(x, 0.0, static_cast<double>(n_[a] - 1)));
  }
  for (long r = 0; r <= 2; ++r)
    for (long dk = -r; dk <= r; ++dk)
      for (long dj = -r; dj <= r; ++dj)
        for (long di = -r; di <= r; ++di) {
          if (std::max({std::abs(di), std::abs(dj), std::abs(dk)}) != r) continue;
          const Cell c{base[0] + di, base[1] + dj, base[2] + dk};
          if (!in_lattice(c)) continue;
          ++seed_search_cubes;
          if (crossed_faces(cached_corners(c)) != 0) return c;
        }
  return std::nullopt;
}

// Bloomenthal's continuation from one crossed cube: a cube's neighbour across a face with a
// sign change is crossed too, so a breadth-first walk over such faces visits every cube of the
// polygonized component and no other.
bool LatticeMesher::follow(const Cell& start, std::size_t cluster, std::size_t clusters) {
  if (!visited_.emplace(cell_key(start), 0).second) return false;
  ++starts;
  std::deque<Cell> queue{start};
  std::size_t done = 0;
  // Each pass takes the cubes queued at its start, in the order of a plain breadth-first walk,
  // their corners evaluated together first; every cube is queued once, so the passes are
  // bounded by the cubes of the lattice.
  while (!queue.empty()) {
    prefetch_corners(queue);
    for (std::size_t level = queue.size(); level > 0; --level) {
      const Cell c = queue.front();
      queue.pop_front();
      count_cube();
      const std::array<double, 8> f = cached_corners(c);
      const int mask = crossed_faces(f);
      check_boundary(c, mask);
      const std::size_t first = mesh.triangles.size();
      mesh_cube(c, f);
      *visited_.find(cell_key(c)) = static_cast<std::uint64_t>(first) << kTriangleRangeBits | (mesh.triangles.size() - first);
      for (int face = 0; face < 6; ++face) {
        if (!((mask >> face) & 1)) continue;
        Cell nb = c;
        nb[face / 2] += face % 2 == 0 ? -1 : 1;
        if (in_lattice(nb) && visited_.emplace(cell_key(nb), 0).second) queue.push_back(nb);
      }
      if (++done % 1024 == 0) options_.cancel.check("marching");
      if (options_.progress && done % 4096 == 0) {
        const double local = static_cast<double>(done) / static_cast<double>(done + queue.size());
        progress_reported_ = std::max(progress_reported_, (static_cast<double>(cluster) + local) / clusters);
        options_.progress(progress_reported_);
      }
    }
  }
  return true;
}

// Whether a triangle crosses the open segment a -> b, parallel to `axis` with a below b: 1 it
// does, 0 it does not, -1 undecided (the segment ends on the triangle, or runs along one of its
// edges parallel to the axis). The seed grid and the lattice share their origin, so the segment
// often lies in a lattice plane and passes exactly through triangle edges in that plane; a
// segment through an edge is moved off it symbolically (by (e, e^2) across the axis, e -> 0,
// Edelsbrunner & Muecke's simulation of simplicity), which puts it inside exactly one of the
// two triangles sharing the edge whenever the mesh does cross there, so no crossing is counted
// twice or lost.
int segment_crosses_triangle(const Vec3& a, const Vec3& b, int axis, const std::array<const Vec3*, 3>& p) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  double w[3];  // w[i]: twice the signed area of (p[i+1], p[i+2], a) projected: p[i]'s weight
  int sign[3];
  for (int i = 0; i < 3; ++i) {
    const Vec3& s = *p[(i + 1) % 3];
    const Vec3& t = *p[(i + 2) % 3];
    const double du = t[u] - s[u], dv = t[v] - s[v];
    w[i] = du * (a[v] - s[v]) - dv * (a[u] - s[u]);
    // The perturbed area is w - dv e + du e^2: its sign is w's, else -dv's, else du's.
    sign[i] = w[i] != 0 ? (w[i] > 0 ? 1 : -1) : dv != 0 ? (dv < 0 ? 1 : -1) : du != 0 ? (du > 0 ? 1 : -1) : 0;
  }
  if (sign[0] == 0 || sign[1] == 0 || sign[2] == 0) return -1;
  if (sign[0] != sign[1] || sign[1] != sign[2]) return 0;
  const double x = (w[0] * (*p[0])[axis] + w[1] * (*p[1])[axis] + w[2] * (*p[2])[axis]) / (w[0] + w[1] + w[2]);
  if (x > a[axis] && x < b[axis]) return 1;
  return x < a[axis] || x > b[axis] ? 0 : -1;
}

// How many triangles of the mesh cross the seed-grid edge a -> b (parallel to `axis`, a below
// b); -1 when undecided. A triangle lies in the closed box of the cube that made it, or within
// half a cell of it for a fan around a projected centre vertex, so the cubes within one cell of
// the edge hold every triangle that can cross it.
int LatticeMesher::mesh_crossings(const Vec3& a, const Vec3& b, int axis) {
  Cell lo, hi;
  for (int q = 0; q < 3; ++q) {
    const auto index = [&](double x) { return static_cast<long>(std::floor((x - lattice_.origin[q]) / h_)); };
    lo[q] = std::max(0L, index(a[q]) - 1);
    hi[q] = std::min(n_[q] - 1, index(b[q]) + 1);
  }
  int crossings = 0;
  for (long k = lo[2]; k <= hi[2]; ++k)
    for (long j = lo[1]; j <= hi[1]; ++j)
      for (long i = lo[0]; i <= hi[0]; ++i) {
        const std::uint64_t* range = visited_.find(cell_key({i, j, k}));
        if (!range) continue;
        const std::size_t first = *range >> kTriangleRangeBits, count = *range & ((1u << kTriangleRangeBits) - 1);
        for (std::size_t t = first; t < first + count; ++t) {
          const auto& tri = mesh.triangles[t];
          const int c = segment_crosses_triangle(
              a, b, axis, {&mesh.positions[tri[0]], &mesh.positions[tri[1]], &mesh.positions[tri[2]]});
          if (c < 0) return -1;
          crossings += c;
        }
      }
  return crossings;
}

// The seeds give one start per 26-connected cluster of crossed seed-grid cells, and a cluster can
// hold several components (the two sheets of a thin shell, blobs closer than a seed cell), which
// the walks from the seeds then never reach. Every sign change of the seed grid is a place the
// surface crosses: it is reached when the mesh crosses its grid edge an odd number of times
// (the mesh separates the edge's two nodes, as the surface does). Coverage rather than
// proximity, so a second sheet near the first still counts as missing. Anything else, which
// includes the mesh passing a grid node on the other side of where the surface does, is looked
// at where the surface crosses the edge: the crossed cube nearest that point (the cube holding
// it first) is either visited, or starts a walk. A sign change with no crossed cube near it lies
// in detail the lattice does not resolve: `unreached_sign_changes`. Costs no evaluation while
// the mesh covers every sign change.
void LatticeMesher::complete_from_sign_changes(const SeedGrid& grid, std::size_t clusters) {
  grid.for_each_sign_change([&](const std::array<int, 3>& ia, const std::array<int, 3>& ib) {
    ++sign_changes;
    resolve_pending();  // the walk the last sign change started, before the mesh is tested
    const Vec3 a = grid.point(ia[0], ia[1], ia[2]), b = grid.point(ib[0], ib[1], ib[2]);
    const int axis = ia[0] != ib[0] ? 0 : ia[1] != ib[1] ? 1 : 2;
    const int crossings = mesh_crossings(a, b, axis);
    if (crossings > 0 && crossings % 2 == 1) return;
    const double fa = grid.value(ia[0], ia[1], ia[2]), fb = grid.value(ib[0], ib[1], ib[2]);
    const EdgeRoot root = find_edge_root(field_, a, fa, b, fb, kSignChangeRootTolerance * h_);
    completion_evaluations += root.evaluations;
    const Vec3& p = root.point;
    const Vec3 top = point(n_[0], n_[1], n_[2]);
    for (int q = 0; q < 3; ++q)
      if (p[q] < lattice_.origin[q] || p[q] > top[q]) return;  // outside the lattice: clipped, not missed
    const std::optional<Cell> c = crossed_cube_near(p);
    if (!c) {
      ++unreached_sign_changes;
      return;
    }
    if (follow(*c, clusters - 1, clusters)) ++completion_starts;
  });
}

void LatticeMesher::run_continuation() {
  SeedOptions seed_options;
  seed_options.resolution = options_.seed_resolution;
  seed_options.threads = options_.threads;
  seed_options.require_closed_in_box = options_.require_closed_in_box;
  const SeedGrid grid = sample_seed_grid(field_, seed_options);
  const std::vector<SurfaceSeed> found = find_surface_seeds(field_, grid, seed_options.resolution);
  seeds = found.size();
  for (std::size_t s = 0; s < found.size(); ++s) {
    const std::optional<Cell> start = crossed_cube_near(found[s].point);
    if (!start) {
      ++unresolved_seeds;
      continue;
    }
    follow(*start, s, found.size());
  }
  complete_from_sign_changes(grid, found.size());
}

}  // namespace

PolygonizeResult run_marching(const Field& field, const MarchingOptions& options, const char* method,
                              const CubeMesher& mesher, const std::string& face_ambiguity) {
  const auto t0 = std::chrono::steady_clock::now();
  const EvaluationCounts before = field.counts();
  LatticeMesher lm(field, options, method, mesher);
  // A root search that the cubes walked before an error asked for would have failed first, so
  // the pending roots are searched before the error leaves.
  try {
    if (options.traversal == Traversal::Grid) lm.run_grid();
    else lm.run_continuation();
  } catch (const InvalidInputError&) {
    lm.resolve_pending();
    throw;
  } catch (const NoSurfaceError&) {
    lm.resolve_pending();
    throw;
  } catch (const LimitExceededError&) {
    lm.resolve_pending();
    throw;
  }
  lm.resolve_pending();
  const CollapseReport collapse = collapse_short_edges(lm.mesh, lm.vertex_keys, kShortEdge * lm.h_);
  if (lm.mesh.triangles.empty())
    throw NoSurfaceError(std::string(method) + ": no cube of the lattice (cell " + std::to_string(lm.h_) +
                         ") is crossed by the surface; it is absent or smaller than a cell");
  compute_field_normals(field, lm.mesh);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  PolygonizeResult result;
  PolygonizeStats& st = result.stats;
  st.method = method;
  st.triangles = lm.mesh.num_triangles();
  st.vertices = lm.mesh.num_vertices();
  st.components = analyze_topology(lm.mesh).components;
  st.field_evaluations = field.counts() - before;
  LatticeReport& r = st.lattice.emplace();
  r.traversal = to_string(options.traversal);
  r.face_ambiguity = face_ambiguity;
  r.cell_size = lm.h_;
  if (options.precision >= 0) r.precision = options.precision;
  r.cells = {lm.lattice_.cells[0], lm.lattice_.cells[1], lm.lattice_.cells[2]};
  r.root_tolerance = lm.tolerance_;
  r.cubes_visited = lm.cubes_visited;
  r.cubes_crossed = lm.cubes_crossed;
  r.corner_evaluations = lm.corner_evaluations;
  r.root_evaluations = lm.root_evaluations;
  r.centre_vertices = lm.centre_vertices;
  r.collapsed_edges = collapse.collapsed_edges;
  r.dropped_components = collapse.dropped_components;
  r.short_edges_left = collapse.short_edges_left;
  if (options.traversal == Traversal::Continuation)
    r.seeding = LatticeSeedingReport{.seed_resolution = options.seed_resolution,
                                     .seeds = lm.seeds,
                                     .unresolved_seeds = lm.unresolved_seeds,
                                     .starts = lm.starts,
                                     .seed_search_cubes = lm.seed_search_cubes,
                                     .sign_changes = lm.sign_changes,
                                     .completion_starts = lm.completion_starts,
                                     .unreached_sign_changes = lm.unreached_sign_changes,
                                     .completion_evaluations = lm.completion_evaluations};
  if (!options.require_closed_in_box) r.open_boundary_faces = lm.open_boundary_faces;
  result.mesh = std::move(lm.mesh);
  // Like the adaptive polygonizer's: the polygonization, not the topology count for the stats.
  st.seconds = seconds;
  if (options.progress) options.progress(1.0);
  return result;
}

}  // namespace cdp::marching
