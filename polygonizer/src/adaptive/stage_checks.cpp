// The checks stage: what a run's mesh must pass before it is returned (check_mesh, check_necks,
// check_components_apart), and the quality bounds a mesh of a smooth surface is held to.
#include "stage_checks.h"

#include "../parallel.h"

#include <cdp/core/errors.h>
#include <cdp/core/mesh_topology.h>
#include <cdp/core/triangle_geometry.h>
#include <cdp/core/triangle_intersection.h>

#include "surface_gaps.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <limits>
#include <numbers>
#include <sstream>
#include <thread>
#include <utility>
#include <vector>

namespace cdp::adaptive {

std::string describe_point(const Vec3& p) {
  std::ostringstream s;
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return s.str();
}

std::size_t check_mesh(const Mesh& mesh, std::size_t seeds, bool check_intersections, int threads,
                       const CancelToken& cancel, const std::vector<char>* sealed, const Field* field,
                       double min_edge, std::optional<double>* sheets_gap) {
  std::vector<char> involved;
  if (sealed && sealed->size() == mesh.triangles.size()) {
    involved.resize(sealed->size());
    for (std::size_t i = 0; i < involved.size(); ++i) involved[i] = !(*sealed)[i];
  }
  const auto intersecting = [&] {
    return involved.empty() ? self_intersecting_pairs(mesh, 1, threads, &cancel)
                            : self_intersecting_pairs_involving(mesh, involved, 1, threads, &cancel);
  };
  // With several threads the topology check runs on one of its own beside the intersection
  // check, whose blocks the other threads share: it is the serial part of the two (the paper
  // variant's torus at factor 5: about 8.5M instructions against the intersections' 31.5M).
  // Both are pure functions of the mesh, and their failures are reported in the order below
  // either way.
  const bool side_by_side = check_intersections && detail::worker_count(threads) > 1;
  MeshTopology t;
  std::vector<std::pair<int, int>> pairs;
  if (side_by_side) {
    std::exception_ptr error;
    std::thread topology([&] {
      try {
        t = analyze_topology(mesh, cancel);
      } catch (...) {
        error = std::current_exception();
      }
    });
    try {
      pairs = intersecting();
    } catch (...) {
      topology.join();
      throw;
    }
    topology.join();
    if (error) std::rethrow_exception(error);
  } else {
    t = analyze_topology(mesh, cancel);
  }
  const auto fail = [](const std::string& what, const Vec3& where, const std::string& why = "") {
    throw NoSurfaceError("adaptive: the mesh came out " + what + " near " + describe_point(where) +
                         (why.empty() ? "; the surface may have a feature thinner than min_edge there" : why));
  };
  if (!t.closed() || !t.edge_manifold() || !t.vertex_manifold() || !t.oriented())
    fail("with " + std::to_string(t.boundary_edges) + " boundary, " + std::to_string(t.nonmanifold_edges) +
             " non-manifold and " + std::to_string(t.misoriented_edges) + " misoriented edges, " +
             std::to_string(t.nonmanifold_vertices) + " non-manifold vertices",
         mesh.positions.empty() ? Vec3::Zero() : mesh.positions.front());
  // A mesh of the surface has no zero-area triangle. Crease patches meeting at a corner where the
  // two surfaces are tangent (a ball cut by a cylinder touching it inside, whose crease crosses
  // itself at (1, 0, 0)) closed their wedges with two, split into three components, exit 0.
  if (t.degenerate_triangles > 0) {
    std::size_t f = 0;
    while (!triangle_is_zero_area(mesh, f)) ++f;
    fail("with " + std::to_string(t.degenerate_triangles) + " zero-area triangles",
         mesh.positions[static_cast<std::size_t>(mesh.triangles[f][0])],
         "; the surface may pinch to a point there (crease patches meeting where two faces are tangent), or have a "
         "feature thinner than min_edge");
  }
  if (t.components != seeds)
    fail("with " + std::to_string(t.components) + " components from " + std::to_string(seeds) + " seeds",
         mesh.positions.front());
  if (check_intersections) {
    if (!side_by_side) pairs = intersecting();
    if (!pairs.empty()) {
      const auto& t = mesh.triangles[pairs.front().first];
      const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
      // Fronts that took one of two close sheets for the other cross there (a thin shell).
      std::string why;
      if (field) {
        const double edge = longest_edge(a, b, c);
        if (const auto gap = sheets_apart(*field, a, edge)) {
          why = sheets_advice(*field, *gap, edge, min_edge);
          if (sheets_gap) *sheets_gap = gap;
        }
      }
      fail("intersecting itself (" + std::to_string(count_self_intersecting_pairs(mesh, threads)) + " pairs of triangles)",
           a, why);
    }
  }
  return t.components;
}

namespace {

// A triangle's smallest angle is the one opposite its shortest edge: at that corner, the sine
// and cosine of the angle times the product of its sides (|u x v|, u . v), and the squared
// lengths of the shortest and the longest edge.
struct SmallestCorner {
  double sine, cosine, shortest2, longest2;
};

SmallestCorner smallest_corner(const Mesh& mesh, const std::array<int, 3>& t) {
  std::array<double, 3> l2;  // l2[c]: squared length of the edge opposite corner c
  for (int c = 0; c < 3; ++c) l2[c] = (mesh.positions[t[(c + 1) % 3]] - mesh.positions[t[(c + 2) % 3]]).squaredNorm();
  const int k = static_cast<int>(std::min_element(l2.begin(), l2.end()) - l2.begin());
  const Vec3& p = mesh.positions[t[k]];
  const Vec3 u = mesh.positions[t[(k + 1) % 3]] - p, v = mesh.positions[t[(k + 2) % 3]] - p;
  return {u.cross(v).norm(), u.dot(v), l2[k], *std::max_element(l2.begin(), l2.end())};
}

}  // namespace

// A triangle's smallest corner is at most 60 degrees, so its cosine is positive and its angle
// grows with the tangent |u x v| / u . v: the arctangent is taken only for the triangles whose
// tangent is within kTieShare of the smallest so far (and those with no such tangent: zero area,
// non-finite). A triangle left out is over that share larger, far beyond the rounding of the
// quotient and of atan2, so the result is the smallest atan2 of all triangles, as when each was
// taken (an atan2 a triangle was 2.3% of a torus run at factor 40 on one thread, perf).
double min_angle_degrees(const Mesh& mesh) {
  constexpr double kTieShare = 1e-9;
  double best = 180, best_tangent = std::numeric_limits<double>::infinity();
  for (const auto& t : mesh.triangles) {
    const SmallestCorner c = smallest_corner(mesh, t);
    if (c.sine > 0 && c.cosine > 0) {
      const double tangent = c.sine / c.cosine;
      if (tangent > best_tangent * (1 + kTieShare)) continue;
      best_tangent = std::min(best_tangent, tangent);
    }
    best = std::min(best, std::atan2(c.sine, c.cosine) * 180 / std::numbers::pi);
  }
  return best;
}

// Without an arctangent: a triangle's smallest angle is under a bound b when its corner's cross
// and dot products (|u x v|, u . v) satisfy |u x v| < tan(b) u . v (angle_statistics' atan2 for
// each corner cost 1.7% of a torus run at factor 5, where this costs a fifth of that, 0.3%). The
// figures agree with angle_statistics but for rounding at the bounds themselves.
int missed_bounds(const Mesh& mesh, std::size_t over_tolerance) {
  const double tan20 = std::tan(kBoundMinDegrees * std::numbers::pi / 180), tan30 = std::tan(std::numbers::pi / 6);
  bool under20 = false;
  std::size_t under30 = 0, counted = 0;
  double ratio_sum = 0;
  for (const auto& t : mesh.triangles) {
    const SmallestCorner c = smallest_corner(mesh, t);
    if (!(c.sine > 0)) {  // zero area: no angles (angle_statistics counts it apart); a sliver all the same
      under20 = true;
      continue;
    }
    ++counted;
    if (c.sine < tan30 * c.cosine) ++under30;
    if (c.sine < tan20 * c.cosine) under20 = true;
    ratio_sum += std::sqrt(c.longest2 / c.shortest2);
  }
  const double share_under_30 = counted ? static_cast<double>(under30) / counted : 0;
  const double mean_ratio = counted ? ratio_sum / counted : 0;
  return under20 + (share_under_30 > kBoundShareUnder30) + (mean_ratio > kBoundMeanEdgeRatio) + (over_tolerance > 0);
}

namespace {

// Triangles per share of the passes below: a share's sum is the same whichever thread adds it,
// and the shares are added in order, so the result is the same on any number of threads.
constexpr std::size_t kTrianglesPerShare = std::size_t{1} << 16;

// Sums term(triangle) over the mesh's triangles, share by share on up to `threads` threads.
template <class T, class Term>
T sum_over_triangles(const Mesh& mesh, int threads, Term term) {
  const std::size_t n = mesh.triangles.size();
  std::vector<T> share((n + kTrianglesPerShare - 1) / kTrianglesPerShare, T{0});
  detail::parallel_blocks(n, kTrianglesPerShare, detail::worker_count(threads),
                          [&](std::size_t begin, std::size_t end, unsigned) {
                            T sum{0};
                            for (std::size_t i = begin; i < end; ++i) sum += term(mesh.triangles[i]);
                            share[begin / kTrianglesPerShare] = sum;
                          });
  T sum{0};
  for (const T s : share) sum += s;
  return sum;
}

}  // namespace

std::size_t triangles_under(const Mesh& mesh, double bound, int threads) {
  const double tan_bound = std::tan(bound);
  return sum_over_triangles<std::size_t>(mesh, threads, [&](const std::array<int, 3>& t) -> std::size_t {
    const SmallestCorner c = smallest_corner(mesh, t);
    return !(c.sine >= tan_bound * c.cosine);
  });
}

double mean_edge_ratio(const Mesh& mesh, int threads) {
  const double sum = sum_over_triangles<double>(mesh, threads, [&](const std::array<int, 3>& t) {
    const SmallestCorner c = smallest_corner(mesh, t);
    return c.shortest2 > 0 ? std::sqrt(c.longest2 / c.shortest2) : std::numeric_limits<double>::infinity();
  });
  return mesh.triangles.empty() ? 0 : sum / static_cast<double>(mesh.triangles.size());
}

void check_bends_kept(const Field& field, const Mesh& mesh, const Sizing& sizing) {
  std::vector<Vec3> middles;
  middles.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles)
    middles.push_back((mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3);
  std::vector<double> values(middles.size());
  std::vector<Vec3> gradients(middles.size());
  // In batches of kBendCheckBatch: a Python function's central differences make seven points of
  // each, and its arrays for 146,440 points at once (the torus callable at factor 8) were fresh
  // pages, faulted in one by one: 2/3 of the check's time.
  for (std::size_t begin = 0; begin < middles.size(); begin += kBendCheckBatch) {
    const std::size_t n = std::min(kBendCheckBatch, middles.size() - begin);
    field.values_gradients(middles.data() + begin, values.data() + begin, gradients.data() + begin, n);
  }
  // The triangle whose longest edge most exceeds what its bend asks for, beyond kBendChordRatio.
  struct Worst {
    double ratio = kBendChordRatio;
    std::size_t at = 0;
    double off = 0, edge = 0, asked = 0;
  } worst;
  for (std::size_t i = 0; i < middles.size(); ++i) {
    const double g = gradients[i].norm();
    if (!(g > 0) || !std::isfinite(values[i])) continue;
    const double off = std::abs(values[i]) / g;
    if (!(off > 0)) continue;
    const auto& t = mesh.triangles[i];
    double edge = 0;
    for (int k = 0; k < 3; ++k) edge = std::max(edge, (mesh.positions[t[k]] - mesh.positions[t[(k + 1) % 3]]).norm());
    const double asked = edge_length(sizing, edge * edge / (6 * off));
    if (edge > worst.ratio * asked) worst = {edge / asked, i, off, edge, asked};
  }
  if (!(worst.edge > 0)) return;
  std::ostringstream os;
  os << "adaptive: a triangle at " << describe_point(middles[worst.at])
     << " cuts across a bend finer than its edges (its middle " << worst.off << " off the surface, its longest edge "
     << worst.edge << " where the bend asks for " << worst.asked << ")";
  throw NoSurfaceError(os.str());
}

void check_components_apart(const Field& field, const Mesh& mesh, std::size_t components) {
  if (components > 1)
    if (const auto at = uncovered_between_components(field, mesh))
      throw NoSurfaceError("adaptive: two components of the mesh face each other across the solid near " +
                           describe_point(*at) +
                           ", where the surface joins them: a front closed on each side of a neck narrower "
                           "than its edges");
}

void check_necks(const Field& field, const Mesh& mesh, std::span<const CriticalStart> critical_starts,
                 double min_edge, NeckSearch& necks) {
  necks = find_missed_necks(field, mesh, critical_starts);
  if (!necks.missed.empty()) {
    const MissedNeck& m = necks.missed.front();
    std::ostringstream msg;
    msg << "adaptive: the mesh " << (m.value < 0 ? "cuts a neck of the solid" : "closes a tunnel") << " about "
        << m.width << " wide near " << describe_point(m.point) << " ("
        << (m.kinked ? "its core is there, a kink of F with no saddle, as on a distance field's medial axis"
                     : "F has a saddle there")
        << ", F = " << m.value << ", and it lies " << (m.value < 0 ? "outside" : "inside") << " the mesh)"
        << (m.width < min_edge ? ", narrower than min_edge (a min_edge under its width lets the edges follow it)" : "")
        << ": a front stepped over it";
    throw MissedNeckError(msg.str());
  }
}

}  // namespace cdp::adaptive
