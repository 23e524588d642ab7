#include "parallel.h"
#include "union_find.h"

#include <cdp/core/errors.h>
#include <cdp/core/newton_projection.h>
#include <cdp/core/surface_seeds.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>

namespace cdp {

namespace {

std::string format_point(const Vec3& p) {
  std::ostringstream s;
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return s.str();
}

}  // namespace

// Nodes where F is zero, to rounding, between two inside nodes along an axis lie where the
// surface only touches the inside: F has a ridge at zero there, as where two solids touch (a box
// standing flush on another: the union's field is -|x - x0| across their common face, exactly 0
// on it). No surface passes there, but counted as outside (F >= 0) each such node made sign
// changes with its neighbours, and a seed there meshed the solids' common face. They count as
// inside; the grid records how many (SeedGrid::touching). A node on the surface proper is never
// so (its neighbours across the surface lie on either side), but where the surface is tangent to
// the axis through the node from inside (a cavity's wall), and there inside is as good as outside:
// the surface passes through the node either way. Decided on the values as sampled, so that the
// order of the nodes does not matter.
static void mark_touching(SeedGrid& g) {
  const double zero = kTouchingZero * g.h;
  std::vector<std::size_t> touching;
  for (int k = 0; k <= g.n[2]; ++k)
    for (int j = 0; j <= g.n[1]; ++j)
      for (int i = 0; i <= g.n[0]; ++i) {
        const double v = g.value(i, j, k);
        if (!(v >= 0 && v <= zero)) continue;
        const std::array<int, 3> at{i, j, k};
        bool ridge = false;
        for (int axis = 0; axis < 3 && !ridge; ++axis) {
          if (at[axis] == 0 || at[axis] == g.n[axis]) continue;
          std::array<int, 3> lo = at, hi = at;
          --lo[axis];
          ++hi[axis];
          ridge = g.value(lo[0], lo[1], lo[2]) < 0 && g.value(hi[0], hi[1], hi[2]) < 0;
        }
        if (ridge) touching.push_back(g.index(i, j, k));
      }
  for (const std::size_t i : touching) g.values[i] = -std::numeric_limits<double>::min();
  g.touching = touching.size();
}

SeedGrid sample_seed_grid(const Field& field, const SeedOptions& options) {
  if (options.resolution < 2) throw InvalidInputError("seeding: resolution must be at least 2");
  const Box& box = field.bounds();
  if (!box.valid()) throw NoSurfaceError("seeding: the field has no valid bounding box");
  SeedGrid g;
  g.origin = box.min;
  g.h = box.size().maxCoeff() / options.resolution;
  for (int a = 0; a < 3; ++a) g.n[a] = std::max(1, static_cast<int>(std::ceil(box.size()[a] / g.h - 1e-9)));
  const double nodes = static_cast<double>(g.n[0] + 1) * (g.n[1] + 1) * (g.n[2] + 1);
  // A node costs 32 bytes while sampling (its point and its value): 2^26 nodes is about 2 GB,
  // a resolution of about 400 on a cubic box, far above what seeding needs (default 32).
  constexpr double kMaxNodes = 67108864.0;
  if (nodes > kMaxNodes) {
    const double scale = std::cbrt(kMaxNodes / nodes);
    throw InvalidInputError("seeding: a grid of resolution " + std::to_string(options.resolution) + " has " +
                            std::to_string(static_cast<long long>(nodes)) + " nodes, more than the " +
                            std::to_string(static_cast<long long>(kMaxNodes)) +
                            " (about 2 GB) allowed; use a resolution of at most " +
                            std::to_string(std::max(2, static_cast<int>(options.resolution * scale) - 1)));
  }
  const std::size_t count = static_cast<std::size_t>(nodes);
  std::vector<Vec3> points;
  points.reserve(count);
  for (int k = 0; k <= g.n[2]; ++k)
    for (int j = 0; j <= g.n[1]; ++j)
      for (int i = 0; i <= g.n[0]; ++i) points.push_back(g.point(i, j, k));
  g.values.resize(count);
  // A thread-safe field's grid is sampled in blocks on all cores (each value lands in its own
  // slot: the same grid on any number of threads); any other field in one batched call.
  constexpr std::size_t kBlock = 4096;
  if (field.thread_safe() && count > kBlock)
    detail::parallel_blocks(count, kBlock, detail::worker_count(options.threads), [&](std::size_t begin, std::size_t end, unsigned) {
      field.values(points.data() + begin, g.values.data() + begin, end - begin);
    });
  else
    field.values(points.data(), g.values.data(), count);
  // NaN counts as outside, so that a function undefined far from its surface (scikit-image's
  // marching cubes meshes such a grid too) is meshed; but not next to the inside, where the
  // surface may pass through the part where F is undefined.
  constexpr double kFar = std::numeric_limits<double>::max();
  std::vector<char> undefined;
  for (std::size_t i = 0; i < count; ++i) {
    if (std::isfinite(g.values[i])) continue;
    if (g.non_finite++ == 0) undefined.assign(count, 0);
    if (std::isnan(g.values[i])) undefined[i] = 1;
    g.values[i] = g.values[i] < 0 ? -kFar : kFar;
  }
  if (g.non_finite > 0)
    for (int k = 0; k <= g.n[2]; ++k)
      for (int j = 0; j <= g.n[1]; ++j)
        for (int i = 0; i <= g.n[0]; ++i) {
          if (!undefined[g.index(i, j, k)]) continue;
          for (int axis = 0; axis < 3; ++axis)
            for (const int step : {-1, 1}) {
              std::array<int, 3> b{i, j, k};
              b[axis] += step;
              if (b[axis] < 0 || b[axis] > g.n[axis] || !(g.value(b[0], b[1], b[2]) < 0)) continue;
              throw NoSurfaceError("seeding: the field is not finite (nan) at " + format_point(g.point(i, j, k)) +
                                   ", next to the inside (F = " + std::to_string(g.value(b[0], b[1], b[2])) +
                                   " at " + format_point(g.point(b[0], b[1], b[2])) +
                                   "): the surface may pass where F is undefined; define F there or give "
                                   "\"bounds\" that leave it out (NaN away from the surface counts as outside)");
            }
        }
  mark_touching(g);
  if (options.require_closed_in_box) {
    std::size_t boundary_nodes = 0, negative = 0;
    std::array<int, 3> first_negative{};
    for (int k = 0; k <= g.n[2]; ++k)
      for (int j = 0; j <= g.n[1]; ++j)
        for (int i = 0; i <= g.n[0]; ++i) {
          const bool boundary = i == 0 || j == 0 || k == 0 || i == g.n[0] || j == g.n[1] || k == g.n[2];
          if (!boundary) continue;
          ++boundary_nodes;
          if (g.values[g.index(i, j, k)] < 0 && negative++ == 0) first_negative = {i, j, k};
        }
    // Negative on the whole boundary: the usual cause is a field written with the opposite sign
    // convention (positive inside), for which larger bounds would not help.
    if (negative == boundary_nodes && (g.values.empty() || *std::max_element(g.values.begin(), g.values.end()) > 0))
      throw NoSurfaceError("seeding: F < 0 on the whole boundary of the box and F > 0 inside: the field looks "
                           "inverted (the convention is F < 0 inside, F > 0 outside); negate it, or give larger "
                           "\"bounds\" if the surface really encloses the box");
    if (negative > 0)
      throw NoSurfaceError("seeding: the surface leaves the box (F < 0 at boundary point " +
                           format_point(g.point(first_negative[0], first_negative[1], first_negative[2])) +
                           "); give larger \"bounds\"");
  }
  return g;
}

namespace {

struct Crossing {
  Vec3 a, b;      // grid edge end points, F(a) < 0 <= F(b) or the reverse
  double fa, fb;
  int cell;       // a crossed cell containing the edge
};

}  // namespace

double seed_grid_spacing(const Field& field, const SeedOptions& options) {
  return field.bounds().size().maxCoeff() / std::max(options.resolution, 1);
}

namespace {

std::vector<std::pair<Crossing, int>> crossings_with_clusters(const SeedGrid& g, const Field& field, int resolution) {
  const auto inside = [&](int i, int j, int k) { return g.values[g.index(i, j, k)] < 0; };
  const int nx = g.n[0], ny = g.n[1], nz = g.n[2];
  const auto cell_id = [&](int i, int j, int k) { return (k * ny + j) * nx + i; };

  std::vector<char> crossed(static_cast<std::size_t>(nx) * ny * nz, 0);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        int n_in = 0;
        for (int c = 0; c < 8; ++c) n_in += inside(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
        crossed[cell_id(i, j, k)] = n_in > 0 && n_in < 8;
      }
  UnionFind clusters(crossed.size());
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        if (!crossed[cell_id(i, j, k)]) continue;
        for (int dk = -1; dk <= 1; ++dk)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              const int a = i + di, b = j + dj, c = k + dk;
              if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz) continue;
              if (crossed[cell_id(a, b, c)]) clusters.unite(cell_id(i, j, k), cell_id(a, b, c));
            }
      }

  std::vector<std::pair<Crossing, int>> out;
  std::vector<int> cluster_number(crossed.size(), -1);
  int next_cluster = 0;
  g.for_each_sign_change([&](const std::array<int, 3>& a, const std::array<int, 3>& b) {
    const auto [i, j, k] = a;
    // Any cell containing this edge is crossed; take the one with the smallest indices.
    const int ci = std::min(i, nx - 1), cj = std::min(j, ny - 1), ck = std::min(k, nz - 1);
    const int root = clusters.find(cell_id(ci, cj, ck));
    if (cluster_number[root] < 0) cluster_number[root] = next_cluster++;
    Crossing c{g.point(i, j, k), g.point(b[0], b[1], b[2]), g.value(i, j, k), g.value(b[0], b[1], b[2]),
               cell_id(ci, cj, ck)};
    out.emplace_back(c, cluster_number[root]);
  });
  if (out.empty()) {
    std::ostringstream msg;
    msg << "seeding: no zero crossing of the field in its box " << format_point(field.bounds().min) << " - "
        << format_point(field.bounds().max) << " at resolution " << resolution
        << " (F is " << (g.values[0] < 0 ? "negative" : "positive") << " everywhere sampled)";
    throw NoSurfaceError(msg.str());
  }
  return out;
}

}  // namespace

std::vector<SurfaceSeed> find_surface_crossings(const Field& field, const SeedOptions& options) {
  std::vector<SurfaceSeed> out;
  for (const auto& [c, cluster] : crossings_with_clusters(sample_seed_grid(field, options), field, options.resolution)) {
    const double t = c.fa / (c.fa - c.fb);
    out.push_back({c.a + t * (c.b - c.a), cluster});
  }
  return out;
}

std::vector<SurfaceSeed> find_surface_seeds(const Field& field, const SeedOptions& options) {
  return find_surface_seeds(field, sample_seed_grid(field, options), options.resolution);
}

std::vector<SurfaceSeed> find_surface_seeds(const Field& field, const SeedGrid& grid, int resolution) {
  const auto crossings = crossings_with_clusters(grid, field, resolution);
  int n_clusters = 0;
  for (const auto& c : crossings) n_clusters = std::max(n_clusters, c.second + 1);
  std::vector<char> done(n_clusters, 0);
  std::vector<SurfaceSeed> seeds;
  const double h = grid.h;
  ProjectionOptions popt;
  popt.max_travel = 2 * h;
  for (const auto& [c, cluster] : crossings) {
    if (done[cluster]) continue;
    // Bisection keeps the bracket; 40 halvings take the edge to ~1e-12 of a cell.
    Vec3 a = c.a, b = c.b;
    double fa = c.fa;
    for (int it = 0; it < 40; ++it) {
      const Vec3 m = 0.5 * (a + b);
      const double fm = field.value(m);
      if ((fm < 0) == (fa < 0)) a = m, fa = fm;
      else b = m;
    }
    const ProjectionResult r = project_to_surface(field, 0.5 * (a + b), popt);
    if (!r.ok()) continue;
    seeds.push_back({r.point, cluster});
    done[cluster] = 1;
  }
  if (seeds.empty())
    throw NoSurfaceError("seeding: the field changes sign but no crossing could be projected onto the surface "
                         "(vanishing or non-finite gradient)");
  return seeds;
}

}  // namespace cdp
