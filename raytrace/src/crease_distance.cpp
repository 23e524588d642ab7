#include <cdp/raytrace/crease_distance.h>

#include <cdp/core/grid_cell.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <unordered_map>
#include <utility>

namespace cdp {

namespace {

struct Segment {
  Vec3 a, b;
};

double distance_to_segment(const Vec3& p, const Segment& s) {
  const Vec3 d = s.b - s.a;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - s.a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return (p - (s.a + t * d)).norm();
}

// Segments hashed by the cells their bounding boxes touch (cells about the longest segment, so
// each touches at most 8); a query looks at rings of cells outward until the nearest found is
// nearer than any unvisited cell can be.
class SegmentGrid {
 public:
  explicit SegmentGrid(std::vector<Segment> segments) : segments_(std::move(segments)) {
    double longest = 0;
    for (const Segment& s : segments_) longest = std::max(longest, (s.b - s.a).norm());
    cell_ = longest > 0 ? longest : 1;
    for (std::size_t i = 0; i < segments_.size(); ++i) {
      const auto lo = cell_of(segments_[i].a.cwiseMin(segments_[i].b)), hi = cell_of(segments_[i].a.cwiseMax(segments_[i].b));
      for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
        for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
          for (std::int64_t x = lo[0]; x <= hi[0]; ++x) cells_[key({x, y, z})].push_back(static_cast<int>(i));
      lo_ = i == 0 ? lo : GridCell{std::min(lo_[0], lo[0]), std::min(lo_[1], lo[1]), std::min(lo_[2], lo[2])};
      hi_ = i == 0 ? hi : GridCell{std::max(hi_[0], hi[0]), std::max(hi_[1], hi[1]), std::max(hi_[2], hi[2])};
    }
  }
  bool empty() const { return segments_.empty(); }

  double nearest(const Vec3& p) const {
    double best = std::numeric_limits<double>::infinity();
    const auto c = cell_of(p);
    // Rings beyond the grid's extent hold nothing: stop there.
    std::int64_t max_ring = 0;
    for (int a = 0; a < 3; ++a) max_ring = std::max({max_ring, c[a] - lo_[a], hi_[a] - c[a]});
    for (std::int64_t r = 0; r <= max_ring; ++r) {
      // Every point of a cell at ring r is at least (r - 1) cells from p.
      if (best <= static_cast<double>(r - 1) * cell_) break;
      // Far from every segment, rings would visit more cells than there are segments: all of
      // them, once, instead.
      if (static_cast<double>(2 * r + 1) * (2 * r + 1) * (2 * r + 1) > 8.0 * static_cast<double>(segments_.size())) {
        for (const Segment& s : segments_) best = std::min(best, distance_to_segment(p, s));
        return best;
      }
      for (std::int64_t z = -r; z <= r; ++z)
        for (std::int64_t y = -r; y <= r; ++y)
          for (std::int64_t x = -r; x <= r; ++x) {
            if (std::max({std::abs(x), std::abs(y), std::abs(z)}) != r) continue;
            const auto it = cells_.find(key({c[0] + x, c[1] + y, c[2] + z}));
            if (it == cells_.end()) continue;
            for (const int i : it->second) best = std::min(best, distance_to_segment(p, segments_[static_cast<std::size_t>(i)]));
          }
    }
    return best;
  }

 private:
  GridCell cell_of(const Vec3& p) const { return grid_cell(p, cell_); }
  static std::uint64_t key(const GridCell& c) { return grid_cell_key(c); }
  std::vector<Segment> segments_;
  double cell_ = 1;
  GridCell lo_{0, 0, 0}, hi_{0, 0, 0};
  std::unordered_map<std::uint64_t, std::vector<int>> cells_;
};

std::vector<double> distances(const std::vector<Vec3>& points, const SegmentGrid& grid) {
  std::vector<double> out;
  if (grid.empty()) return out;
  out.reserve(points.size());
  for (const Vec3& p : points) out.push_back(grid.nearest(p));
  return out;
}

}  // namespace

CreaseDistance crease_distance(const Field& field, const Mesh& mesh, const CreaseDistanceOptions& options) {
  CreaseDistance r;
  const double diag = field.bounds().diagonal();
  CreaseTracingOptions tracing = options.tracing;
  if (!(tracing.max_spacing > 0)) tracing.max_spacing = 0.002 * diag;
  const CreaseTracingResult creases = trace_creases(field, tracing);
  std::vector<Vec3> crease_points;
  std::vector<Segment> crease_segments;
  for (const CreaseCurve& c : creases.curves) {
    crease_points.insert(crease_points.end(), c.points.begin(), c.points.end());
    for (std::size_t i = 0; i + 1 < c.points.size(); ++i) crease_segments.push_back({c.points[i], c.points[i + 1]});
    if (c.closed && c.points.size() > 1) crease_segments.push_back({c.points.back(), c.points.front()});
  }
  r.crease_curves = creases.curves.size();
  r.crease_points = crease_points.size();
  r.corners = creases.corners.size();

  // Every edge once (from the lower vertex), and whether it is sharp: two triangles whose
  // normals differ by more than the angle (a boundary or non-manifold edge is not sharp).
  std::vector<Vec3> face_normal(mesh.triangles.size());
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    face_normal[f] = (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]).normalized();
  }
  std::unordered_map<std::uint64_t, std::vector<int>> edge_faces;
  const auto edge_key = [](int a, int b) {
    return static_cast<std::uint64_t>(std::min(a, b)) << 32 | static_cast<std::uint32_t>(std::max(a, b));
  };
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
    for (int e = 0; e < 3; ++e)
      edge_faces[edge_key(mesh.triangles[f][e], mesh.triangles[f][(e + 1) % 3])].push_back(static_cast<int>(f));
  const double cos_sharp = std::cos(options.sharp_angle_degrees * std::numbers::pi / 180);
  const double spacing = options.edge_spacing > 0 ? options.edge_spacing : 0.002 * diag;
  std::vector<Segment> all_edges, sharp_edges;
  std::vector<Vec3> edge_points;
  // In a fixed order (the map's is not): sorted keys.
  std::vector<std::uint64_t> keys;
  keys.reserve(edge_faces.size());
  for (const auto& [k, faces] : edge_faces) keys.push_back(k);
  std::sort(keys.begin(), keys.end());
  for (const std::uint64_t k : keys) {
    const Segment s{mesh.positions[static_cast<std::size_t>(k >> 32)], mesh.positions[static_cast<std::size_t>(k & 0xffffffffu)]};
    all_edges.push_back(s);
    const auto& faces = edge_faces[k];
    if (faces.size() != 2) continue;
    const double c = face_normal[static_cast<std::size_t>(faces[0])].dot(face_normal[static_cast<std::size_t>(faces[1])]);
    if (!(c < cos_sharp)) continue;
    sharp_edges.push_back(s);
    const int n = std::max(1, static_cast<int>(std::ceil((s.b - s.a).norm() / spacing)));
    for (int i = 0; i <= n; ++i) edge_points.push_back(s.a + (s.b - s.a) * (static_cast<double>(i) / n));
  }
  r.sharp_edges = sharp_edges.size();
  r.edge_points = edge_points.size();

  r.crease_to_mesh_edges = sample_stats(distances(crease_points, SegmentGrid(std::move(all_edges))));
  r.crease_to_sharp_edges = sample_stats(distances(crease_points, SegmentGrid(std::move(sharp_edges))));
  r.sharp_edges_to_crease = sample_stats(distances(edge_points, SegmentGrid(std::move(crease_segments))));
  if (r.crease_to_sharp_edges.count > 0 && r.sharp_edges_to_crease.count > 0)
    r.edge_chamfer = 0.5 * (r.crease_to_sharp_edges.mean + r.sharp_edges_to_crease.mean);
  return r;
}

}  // namespace cdp
