#include "seeding.h"
#include "spatial_hash.h"
#include "../surface_passes.h"
#include "../union_find.h"

#include <cdp/core/curvature.h>
#include <cdp/core/errors.h>
#include <cdp/core/newton_projection.h>
#include <cdp/core/triangle_geometry.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <utility>

namespace cdp::adaptive {

namespace {

// Bisection halvings before Newton takes a sign change's point onto the surface: 2^-16 of the
// segment is well inside Newton's basin on any segment the grid resolves.
constexpr int kBisections = 16;

// A sign change's surface point is where the surface passes only if F changes sign across it
// within this share of min_edge along its normal: where two solids touch (a table's leg flush
// under a top thinner than a seed cell, a seed grid node on their common face with the leg's
// inside below it and the air above the top) F is zero on their common face and of one sign on
// either side, and a seed there meshed that face inside the solid. Far less than any feature
// the edges resolve (a seed beside a sharp crease has a thin wedge on one side), far more than
// the Newton tolerance.
constexpr double kTouchingDepth = 1e-4;
// How near a triangle of the same orientation a point of the surface must lie to count as meshed,
// in units of the triangle's longest edge. The mesh is a chord of the surface and deviates by
// about l / (8 k) for an edge l at factor k where the curvature is resolved; where it is not (a
// needle's tip finer than min_edge) the mesh cuts the detail off within about one edge. Two
// different sheets of the same orientation are never that close unless a feature between them is
// thinner than an edge.
constexpr double kSheetReach = 1.0;
// A triangle within reach (kSheetReach) stands for the surface point x only where x is about as
// far from the triangle's nearest point y as the triangle is from the surface (the first-order
// distance |F| / |grad F| at its centroid, see Seeder::deviation, plus x's own where x is not on
// the surface), or where F keeps one sign from x to y (see meshed_at): a chord lies over its own
// sheet, at most a few times its deviation from the surface point it stands for, while a triangle
// of another sheet is farther from x than from its own. Within an edge alone, the coarse
// triangles of a ball's sphere (edges 0.38) passed for 21 of 60 small voids (diameter 0.1)
// inside it, a Schwarz D surface cut by the ball: 40 components meshed of 61, exit 0. Where the
// surface bends across the chord (a needle's tip, a crease cut off) the walk (walks_to_mesh)
// follows the surface until the test holds. kFootFloor, in grid cells, covers rounding where
// both distances vanish.
constexpr double kFootSlack = 2.0;
constexpr double kFootFloor = 1e-6;
// Samples of F along the segment from a surface point to the nearest triangle that fails the
// test above (see meshed_at).
constexpr int kSegmentSamples = 8;
// Bound on the cells the small-component search splits, so that a field whose bounds are far too
// loose cannot make the search cost far more than the meshing: kRefinedCellsPerTriangle for each
// triangle meshed when the search begins, at least kMinRefinedCells, at most kMaxRefinedCells;
// cells left over count as `unsearched_cells`. A split costs a few microseconds, a triangle of
// tracking about 5-10. Over the test suite and the topology sweep no run split more than 8,192
// cells; a sampled volume of noise (a sphere's distance on 16^3 samples plus noise of 0.03,
// whose prefiltered coefficients ring: value ranges over a cell of [-0.81, 0.17] where F is
// -0.53, a Lipschitz bound of 27) left all but 2,016 of the 32,768 grid cells to the search,
// which split 2^20 cells in 10 s for a mesh of 23,824 triangles made in 1 s. Milder noise (a
// unit sphere's distance on 16^3 to 64^3 samples over [-2, 2]^3 plus Gaussian noise of 0.01 to
// 0.03) needs 11,600 to 282,000 splits, 3 to 27 a triangle, and meshes in 0.1 to 1.4 s.
constexpr std::size_t kRefinedCellsPerTriangle = 8;
constexpr std::size_t kMinRefinedCells = 1u << 18;
constexpr std::size_t kMaxRefinedCells = 1u << 20;
// Lattice steps along a seed-grid cell's side in the band scan of sampled volumes (scan_band):
// ceil(grid cell / min_edge), at most this, so that the scan costs at most 13^3 samples a cell of
// the band (a volume's sample costs about 0.2 us).
constexpr int kMaxBandSteps = 12;
// The band's nodes probed by Newton (Seeder::probe): those where h times the mean curvature of
// the level set through the node, measured on the grid (level_sets_curl), exceeds this: a
// radius under two cells for a distance field. A component small enough to cross no grid edge
// holds no node, so the nearest node is within a cell of it and its level set curls at about
// that radius. With 0.5 (four cells) the grid's measure alone passed 5,032 of the tanglecube's
// nodes at factor 6 (a run 19 % longer) for one more bead of the forty below (Seeder::probe);
// with 1 it passes 96, and F's own curvature there (keep_curling) none.
constexpr double kBandCurl = 1.0;
// A probe's landing this share of the box's diagonal beyond the box lies outside it (Newton
// leaves points within 1e-10 of the diagonal of the surface; a face the surface touches is kept).
constexpr double kOutsideBox = 1e-9;
// Steps of min_edge a surface point may be from the mesh and still belong to a meshed component.
constexpr int kWalkSteps = 32;
// A point that walks to the mesh is detail of that component finer than min_edge only if the
// surface, followed from it the other way, ends (a needle's tip): it turns to face the walk, its
// normal within acos(kTipFacing) = 60 degrees of the way walked. Where it runs instead onto
// another component of the mesh within kOtherWaySteps steps, it is a bridge between them
// thinner than min_edge (Seeder::other_way): cdp.sdf's two balls joined by a capsule 0.005-0.02
// wide were meshed as two balls, exit 0, the probes on the rod taken for a needle's tip of one
// ball. The rod's free stretch, 0.4 long, is 57 steps of min_edge at factor 3; a probe nearer
// one end than kWalkSteps steps has the rest to go, and one farther from both is a seed anyway.
constexpr double kTipFacing = 0.5;
constexpr int kOtherWaySteps = 4 * kWalkSteps;
// A component seeded late whose mesh runs into the earlier mesh is a bridge (Bridges) only where
// its seed lies apart from that mesh: farther than kApartMinEdges times min_edge and than
// kApartEdges of the nearest triangle's longest edge. Seeds that coverage missed between two
// sheets closer than the edges (a hollow cylinder 0.004 thick at factor 8: 1 to 3 min_edges, 0.06
// to 0.2 edges from the earlier mesh) run into it too, and meshing them first mends nothing (four
// more failed attempts, +42 s); the rod's seed between two balls lay 16 min_edges and 0.67 edges
// from them, the late blobs' of the topology sweep 3 to 6 edges.
constexpr double kApartMinEdges = 4;
constexpr double kApartEdges = 0.25;
// The checks between components poll the cancel token every so many sign changes, witnesses or
// triangles indexed: well under a millisecond of work each.
constexpr std::size_t kPollEvery = 256;

struct SignChange {
  Vec3 a = Vec3::Zero(), b = Vec3::Zero();  // F(a) and F(b) differ in sign (F < 0 counts as inside)
  double fa = 0, fb = 0;
};

struct SurfacePoint {
  Vec3 point, normal;
};

// p with F's unit normal there, or nothing where the gradient vanishes or is not finite.
std::optional<SurfacePoint> with_normal(const Field& field, const Vec3& p) {
  const Vec3 g = field.gradient(p);
  if (!(g.squaredNorm() > 0) || !g.allFinite()) return std::nullopt;
  return SurfacePoint{p, g.normalized()};
}

// The surface point on a sign change: Newton from the linear interpolant; where it wanders off,
// bisection first keeps the bracket and Newton finishes.
std::optional<SurfacePoint> surface_point(const Field& field, const SignChange& c) {
  const double length = (c.b - c.a).norm();
  ProjectionOptions po;
  po.max_travel = 2 * length;
  ProjectionResult r = project_to_surface(field, c.a + c.fa / (c.fa - c.fb) * (c.b - c.a), po);
  if (!r.ok()) {
    Vec3 a = c.a, b = c.b;
    double fa = c.fa;
    for (int it = 0; it < kBisections; ++it) {
      const Vec3 m = 0.5 * (a + b);
      const double fm = field.value(m);
      if ((fm < 0) == (fa < 0)) a = m, fa = fm;
      else b = m;
    }
    po.max_travel = length;
    po.max_step = length;
    r = project_to_surface(field, 0.5 * (a + b), po);
  }
  if (!r.ok()) return std::nullopt;
  return with_normal(field, r.point);
}

// The mesh tracked so far, for the seeding's questions: does a triangle cross this segment, does
// one stand for this point or this box (within reach: kSheetReach times its own longest edge)?
// Its triangles are binned by the cells their bounding boxes overlap, indexed lazily (coverage is
// asked between components, never inside the tracker's loop), and kept by size: a hash per
// binary order of their longest edge, which the questions of reach (explains,
// nearest_within_reach) search within the reach of that class's longest edge. One hash searched
// within the reach of the longest edge of the whole mesh looked through thousands of small
// triangles for every question where a few edges of max_edge lay among edges of min_edge (a raw
// MRI scan: 31 % of a 50 s run). A class whose triangles' box misses a question's box is not
// looked up. The answers do not depend on the classes: a triangle found in any of them, the
// nearest points' ties broken by triangle index (nearest_same_sheet's by the hash's order
// before).
class MeshCoverage {
 public:
  MeshCoverage(const Mesh& mesh, double cell, const CancelToken& cancel) : mesh_(mesh), h_(cell), cancel_(cancel) {}
  std::size_t triangles() const { return mesh_.triangles.size(); }
  const Mesh& mesh() const { return mesh_; }

  void update() {
    const auto& P = mesh_.positions;
    for (; indexed_ < mesh_.triangles.size(); ++indexed_) {
      if (indexed_ % kPollEvery == 0) cancel_.check("adaptive: seeding");
      const auto& t = mesh_.triangles[indexed_];
      const Vec3 lo = P[t[0]].cwiseMin(P[t[1]]).cwiseMin(P[t[2]]);
      const Vec3 hi = P[t[0]].cwiseMax(P[t[1]]).cwiseMax(P[t[2]]);
      const double longest = longest_edge(t);
      // A point exactly on a cell face belongs to the cells on both sides.
      const double pad = 1e-9 * h_;
      SizeClass& c = classes_.try_emplace(longest > 0 ? std::ilogb(longest) : kNoLength, h_).first->second;
      c.longest = std::max(c.longest, longest);
      c.lo = c.lo.array().min(lo.array() - pad), c.hi = c.hi.array().max(hi.array() + pad);
      c.cells.insert_box(static_cast<int>(indexed_), lo.array() - pad, hi.array() + pad);
    }
  }

  // A triangle meets the segment a-b.
  bool crosses(const Vec3& a, const Vec3& b) const {
    const auto& P = mesh_.positions;
    const Vec3 lo = a.cwiseMin(b), hi = a.cwiseMax(b);
    return any_in([&](const SizeClass&) { return BoxQuery{{lo, hi}}; }, [&](int f) {
      const auto& t = mesh_.triangles[f];
      const Vec3 &p = P[t[0]], &q = P[t[1]], &r = P[t[2]];
      return !beside_box(p, q, r, lo, hi) && segment_meets_triangle(a, b, p, q, r);
    });
  }

  // Whether triangle pqr's corners all lie beyond one face of the box lo-hi. Most triangles of
  // the cells lie beside a segment's box (a grid edge is as long as a few triangles): this
  // settles them with comparisons, exactly (the triangle's points lie between its corners).
  static bool beside_box(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& lo, const Vec3& hi) {
    for (int axis = 0; axis < 3; ++axis)
      if ((p[axis] < lo[axis] && q[axis] < lo[axis] && r[axis] < lo[axis]) ||
          (p[axis] > hi[axis] && q[axis] > hi[axis] && r[axis] > hi[axis]))
        return true;
    return false;
  }

  // Whether an edge of the triangles from `first` on (a component just meshed, not indexed yet)
  // passes through an indexed triangle that is not its own corner's and faces the same way (the
  // normals of the two within 90 degrees): two meshes of one sheet, the later grown from a seed
  // onto the earlier one, which closed over where they join. Triangles facing opposite ways are
  // two sheets closer than the edges (a shell, a plate), which meeting the later one first does
  // not mend: a hollow cylinder 0.004 thick at factor 8 was meshed four more times so (+42 s).
  bool runs_into_indexed(std::size_t first) const {
    const auto& P = mesh_.positions;
    const auto normal = [&](const std::array<int, 3>& f) { return (P[f[1]] - P[f[0]]).cross(P[f[2]] - P[f[0]]); };
    for (std::size_t t = first; t < mesh_.triangles.size(); ++t) {
      const Vec3 n = normal(mesh_.triangles[t]);
      for (int e = 0; e < 3; ++e) {
        const int i = mesh_.triangles[t][e], j = mesh_.triangles[t][(e + 1) % 3];
        if (i > j) continue;  // each edge of a closed mesh once
        const Vec3 &a = P[i], &b = P[j];
        const Vec3 lo = a.cwiseMin(b), hi = a.cwiseMax(b);
        const bool meets = any_in([&](const SizeClass&) { return BoxQuery{{lo, hi}}; }, [&](int f) {
          const auto& g = mesh_.triangles[f];
          const Vec3 &p = P[g[0]], &q = P[g[1]], &r = P[g[2]];
          if (beside_box(p, q, r, lo, hi)) return false;
          if (std::find(g.begin(), g.end(), i) != g.end() || std::find(g.begin(), g.end(), j) != g.end()) return false;
          return segment_meets_triangle(a, b, p, q, r) && n.dot(normal(g)) > 0;
        });
        if (meets) return true;
      }
    }
    return false;
  }

  // Whether no indexed triangle lies within `floor` of x, nor within kApartEdges of its own
  // longest edge.
  bool apart_from_indexed(const Vec3& x, double floor) const {
    const auto& P = mesh_.positions;
    const auto around_x = [&](const SizeClass& k) {
      const double r = std::max(floor, kApartEdges * k.longest);
      return BoxQuery{{x.array() - r, x.array() + r}};
    };
    return !any_in(around_x, [&](int f) {
      const auto& t = mesh_.triangles[f];
      const double d = (closest_point_on_triangle(x, P[t[0]], P[t[1]], P[t[2]]) - x).norm();
      return d <= std::max(floor, kApartEdges * longest_edge(t));
    });
  }

  // Every point of the box lies within one edge of a triangle (the triangle's longest edge), so
  // whatever surface the box holds would count as meshed (see kSheetReach).
  bool explains(const Box& box) const {
    const auto& P = mesh_.positions;
    const Vec3 c = box.center();
    const double hd = 0.5 * box.diagonal();
    // A triangle that explains the box lies within its longest edge minus hd of the centre.
    const auto within_reach = [&](const SizeClass& k) {
      const double r = kSheetReach * k.longest - hd;
      return r > 0 ? BoxQuery{{c.array() - r, c.array() + r}} : std::nullopt;
    };
    return any_in(within_reach, [&](int f) {
      const auto& t = mesh_.triangles[f];
      const double reach = kSheetReach * longest_edge(t) - hd;
      if (!(reach > 0)) return false;
      // The distance to the triangle's bounding box first: a cheap lower bound.
      const Vec3 lo = P[t[0]].cwiseMin(P[t[1]]).cwiseMin(P[t[2]]), hi = P[t[0]].cwiseMax(P[t[1]]).cwiseMax(P[t[2]]);
      if ((c - c.cwiseMax(lo).cwiseMin(hi)).norm() > reach) return false;
      return (closest_point_on_triangle(c, P[t[0]], P[t[1]], P[t[2]]) - c).norm() <= reach;
    });
  }

  // The nearest point within r of a triangle facing the way `normal` does (ties: the first indexed).
  std::optional<Vec3> nearest_same_sheet(const Vec3& x, const Vec3& normal, double r) const {
    std::optional<Vec3> best;
    double best_d = r;
    int best_f = -1;
    for_each_facing(x, normal, [r](const SizeClass&) { return r; }, [&](int f, const Vec3& y, double d) {
      if (d < best_d || (d == best_d && best && f < best_f)) best_d = d, best = y, best_f = f;
    });
    return best;
  }

  Vec3 centroid(int t) const {
    const auto& x = mesh_.triangles[t];
    return (mesh_.positions[x[0]] + mesh_.positions[x[1]] + mesh_.positions[x[2]]) / 3;
  }

  // The nearest point to x of the triangles facing the way `normal` does that lie within
  // kSheetReach times their longest edge of x, and its triangle (ties: the first indexed).
  struct Nearest {
    Vec3 point;
    int triangle;
  };
  std::optional<Nearest> nearest_within_reach(const Vec3& x, const Vec3& normal) const {
    std::optional<Nearest> best;
    double best_d = INFINITY;
    for_each_facing(
        x, normal, [](const SizeClass& c) { return kSheetReach * c.longest; },
        [&](int f, const Vec3& y, double d) {
          if (d <= kSheetReach * longest_edge(mesh_.triangles[f]) && (d < best_d || (d == best_d && f < best->triangle))) {
            best_d = d;
            best = Nearest{y, f};
          }
        });
    return best;
  }

 private:
  // The class of triangles whose longest edge is 0 (none survive the tracker; kept apart all the same).
  static constexpr int kNoLength = std::numeric_limits<int>::min();
  // A class's triangles: their hash, their longest edge and the box around their boxes as the hash
  // holds them, padded (a question whose box misses it looks up none of its cells).
  struct SizeClass {
    explicit SizeClass(double cell) : cells(cell) {}
    bool meets(const Vec3& qlo, const Vec3& qhi) const {
      return (qlo.array() <= hi.array()).all() && (qhi.array() >= lo.array()).all();
    }
    SpatialHash cells;
    double longest = 0;
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  };
  using BoxQuery = std::optional<std::pair<Vec3, Vec3>>;  // a question's box in a class, or none

  // fn(f, y, d) for every triangle f facing the way `normal` does that the cells within
  // radius(its class) of x hold (maybe more than once), y the point of f nearest to x, d their distance.
  template <class Radius, class Fn>
  void for_each_facing(const Vec3& x, const Vec3& normal, const Radius& radius, const Fn& fn) const {
    const auto& P = mesh_.positions;
    const auto around_x = [&](const SizeClass& k) {
      const double r = radius(k);
      return BoxQuery{{x.array() - r, x.array() + r}};
    };
    any_in(around_x, [&](int f) {
      const auto& t = mesh_.triangles[f];
      if (!((P[t[1]] - P[t[0]]).cross(P[t[2]] - P[t[0]]).dot(normal) > 0)) return false;
      const Vec3 y = closest_point_on_triangle(x, P[t[0]], P[t[1]], P[t[2]]);
      fn(f, y, (y - x).norm());
      return false;
    });
  }

  // Whether pred(f) holds for a triangle f that the cells of a class within the box box_of(class)
  // hold (a class where it gives no box, or whose own box misses it, not looked up); stops at the
  // first.
  template <class BoxOf, class Pred>
  bool any_in(const BoxOf& box_of, const Pred& pred) const {
    return std::any_of(classes_.begin(), classes_.end(), [&](const auto& entry) {
      const BoxQuery box = box_of(entry.second);
      return box && entry.second.meets(box->first, box->second) && entry.second.cells.any_in(box->first, box->second, pred);
    });
  }

  double longest_edge(const std::array<int, 3>& t) const {
    const auto& P = mesh_.positions;
    return std::max({(P[t[0]] - P[t[1]]).norm(), (P[t[1]] - P[t[2]]).norm(), (P[t[2]] - P[t[0]]).norm()});
  }

  const Mesh& mesh_;
  double h_;
  std::size_t indexed_ = 0;
  std::map<int, SizeClass> classes_;  // by std::ilogb of the longest edge: one per binary order between the shortest and the longest
  CancelToken cancel_;
};

class Seeder {
 public:
  Seeder(const Field& field, const SeedGrid& grid, double min_edge, double cell, Tracker& tracker, const Mesh& mesh,
         Bridges* bridges)
      : field_(field),
        grid_(grid),
        min_edge_(min_edge),
        tracker_(tracker),
        cover_(mesh, std::max(cell, grid.h), tracker.cancel_token()),
        bridges_(bridges) {}

  SeedingReport run() {
    if (bridges_) bridges_first();
    grid_sign_changes();
    const std::vector<char> near = near_crossed_cells();
    const bool bounded = field_.lipschitz_bound().has_value(), sampled = field_.sample_spacing().has_value();
    if (bounded) search_small_components(near);
    probe(near, /*local_minima=*/!bounded, /*band=*/!sampled);
    if (sampled) scan_band(near);
    seed_deferred();
    recheck();
    return report_;
  }

 private:
  // A place the surface passes, checked again after the run.
  struct Witness {
    SignChange change;
    bool has_segment;
    std::optional<SurfacePoint> at;
  };

  // The bridges an earlier attempt found (Bridges), each seeded unless one before it meshed it;
  // never deferred, which would let the components they join close over them again.
  void bridges_first() {
    for (const Vec3& p : bridges_->first) {
      const auto x = with_normal(field_, p);
      if (!x) continue;
      cover_.update();
      if (meshed_at(*x)) continue;
      ++report_.seeds_first;
      start_from(*x);
    }
  }

  // The places the tracker refused or moved because they landed on finished mesh or another
  // sheet: a component that met none ran into no earlier one, and is not tested (the test costs
  // a query of the triangle hash an edge: a quarter of the onion's run at factor 3.75).
  std::size_t met_mesh() const {
    const TrackerReport r = tracker_.report();
    return r.over_mesh_rejections + r.sheet_jumps;
  }

  // A component seeded after others that runs into their mesh is surface they closed over (a
  // rod thinner than their edges where it joins them), a bridge for the attempt made again
  // (Run::attempt); so is one whose tracking throws after its mesh ran into theirs.
  void start_from(const SurfacePoint& x) {
    cover_.update();
    const std::size_t before = cover_.triangles();
    const bool late = before > 0 && bridges_ && cover_.apart_from_indexed(x.point, kApartMinEdges * min_edge_);
    const std::size_t met_before = late ? met_mesh() : 0;
    bool meshed = false;
    const auto ran_into_mesh = [&] {
      if (late && met_mesh() > met_before && cover_.runs_into_indexed(before)) bridges_->found.push_back(x.point);
    };
    try {
      meshed = tracker_.mesh_from_seed(x.point);
    } catch (const CancelledError&) {
      throw;
    } catch (const std::exception&) {
      ran_into_mesh();  // what the component meshed before it stopped
      throw;
    }
    if (!meshed) {
      ++report_.failed_seeds;
      return;
    }
    ++report_.seeds;
    ran_into_mesh();
  }

  // Whether the mesh stands for the surface at x (see kFootSlack): x lies about as far from the
  // nearest triangle within reach that faces the way `normal` does as that triangle lies from the
  // surface, or the segment between them stays on the triangle's side. `offset`: x's own
  // distance from the surface (0 for a surface point; where unknown, 0 is the stricter).
  bool meshed_at(const Vec3& x, const Vec3& normal, double offset) { return meshed_by(x, normal, offset).has_value(); }
  bool meshed_at(const SurfacePoint& x) { return meshed_at(x.point, x.normal, 0); }

  // meshed_at's triangle: the one that stands for x, if any.
  std::optional<int> meshed_by(const SurfacePoint& x) { return meshed_by(x.point, x.normal, 0); }
  std::optional<int> meshed_by(const Vec3& x, const Vec3& normal, double offset) {
    const auto y = cover_.nearest_within_reach(x, normal);
    if (!y) return std::nullopt;
    const Deviation& d = deviation(y->triangle);
    if (!d.known) return std::nullopt;
    if ((x - y->point).norm() <= kFootSlack * (d.distance + offset) + kFootFloor * grid_.h) return y->triangle;
    // Farther: a mesh cut across a crease or a corner (creases ignored) lies farther from the
    // tip it cut off than from the faces beside it. It still stands for x when the segment from
    // x to the triangle stays on the triangle's side of the surface; a triangle of another sheet
    // is seen through the solid or the gap between the sheets, where the sign changes. Where the
    // triangle's nearest point lies on the surface itself (a flat face) it has no side: the
    // segment from a bead beside a box's face runs through air all the way to the face.
    Vec3 gy;
    const double f = field_.value_gradient(y->point, gy);
    if (!std::isfinite(f)) return std::nullopt;
    if (!(std::abs(f) > kFootFloor * grid_.h * gy.norm())) return std::nullopt;
    for (int k = 1; k < kSegmentSamples; ++k) {
      const double v = field_.value(x + (static_cast<double>(k) / kSegmentSamples) * (y->point - x));
      if (!std::isfinite(v) || (v < 0) != (f < 0)) return std::nullopt;
    }
    return y->triangle;
  }

  // How far triangle t lies from the surface: the first-order distance |F| / |grad F| at its
  // centroid, where a chord of a smoothly curved patch deviates most (about 3/4 of the most for
  // a cap; kFootSlack covers the rest). Evaluated once per triangle asked about.
  struct Deviation {
    bool known = false;
    double distance = 0;
  };
  const Deviation& deviation(int t) {
    if (deviations_.size() <= static_cast<std::size_t>(t)) deviations_.resize(t + 1);
    Deviation& d = deviations_[t];
    if (d.known || d.distance < 0) return d;
    Vec3 g;
    const double f = field_.value_gradient(cover_.centroid(t), g);
    const double slope = g.norm();
    if (std::isfinite(f) && slope > 0 && std::isfinite(slope)) d = {true, std::abs(f) / slope};
    else d.distance = -1;  // asked once: unknown stays unknown
    return d;
  }

  // Whether the surface leads from x to the mesh within kWalkSteps steps of min_edge: a point of
  // a meshed component whose detail is finer than min_edge (a needle's tip that the mesh cuts
  // off) rather than a new component. Each step moves in the tangent plane towards the nearest
  // triangle of the same orientation and goes back onto the surface by Newton; it fails as soon
  // as the normal turns by 90 degrees or more (another sheet) or the mesh comes no nearer.
  // A point reached after the first step is detail of the component reached only if the surface
  // does not run the other way onto another component (other_way, kTipFacing); a point that may
  // still bridge to a component not meshed yet is `open_walk_`, for the caller to look at again
  // once every component is meshed.
  bool walks_to_mesh(SurfacePoint x) {
    open_walk_ = false;
    const SurfacePoint start = x;
    Vec3 first_step = Vec3::Zero();
    const double step = min_edge_;
    for (int it = 0; it <= kWalkSteps; ++it) {
      if (const auto t = meshed_by(x)) {
        if (it == 0) return true;
        switch (other_way(start, -first_step, *t)) {
          case OtherWay::Bridge:
            ++report_.thin_bridges;
            if (bridges_) bridges_->found.push_back(start.point);
            return false;
          case OtherWay::Open: open_walk_ = true; return true;
          case OtherWay::Ends: return true;
        }
      }
      if (it == kWalkSteps) return false;
      const auto y = cover_.nearest_same_sheet(x.point, x.normal, (kWalkSteps - it) * step);
      if (!y) return false;
      const Vec3 towards = *y - x.point;
      const double before = towards.norm();
      // Along the surface; straight at the mesh where the tangent plane faces it (a tip).
      Vec3 d = towards - x.normal * x.normal.dot(towards);
      if (!(d.norm() > 0.1 * before)) d = towards;
      if (it == 0) first_step = d.normalized();
      const auto next = onto_surface(x.point + std::min(step, before) * d.normalized());
      if (!next || !(next->normal.dot(x.normal) > 0)) return false;
      if (!((*y - next->point).norm() < before)) return false;
      x = *next;
    }
    return false;
  }

  // A walk's step: p taken back onto the surface by Newton within min_edge, with its normal.
  std::optional<SurfacePoint> onto_surface(const Vec3& p) const {
    ProjectionOptions po;
    po.max_travel = min_edge_;
    po.max_step = min_edge_;
    const ProjectionResult r = project_to_surface(field_, p, po);
    if (!r.ok()) return std::nullopt;
    return with_normal(field_, r.point);
  }

  // Where the surface leads from x along `away` (the tangent direction opposite the walk that
  // reached triangle `reached`), in steps of min_edge, each direction the last one laid into the
  // new tangent plane: it Ends where it turns to face the walk (a tip) or the way along it
  // vanishes, is a Bridge where a triangle of another component of the mesh stands for it, and
  // Open where it reaches the same component (a crease cut off, a thin handle: not decided
  // here), leaves the surface, or runs on past kOtherWaySteps steps.
  enum class OtherWay { Ends, Bridge, Open };
  OtherWay other_way(SurfacePoint x, Vec3 away, int reached) {
    const int from = component_of(reached);
    for (int it = 0; it < kOtherWaySteps; ++it) {
      Vec3 d = away - x.normal * x.normal.dot(away);
      if (!(d.norm() > 0.1)) return OtherWay::Ends;
      d.normalize();
      const auto next = onto_surface(x.point + min_edge_ * d);
      if (!next) return OtherWay::Open;
      x = *next;
      if (x.normal.dot(d) > kTipFacing) return OtherWay::Ends;
      if (const auto t = meshed_by(x)) return component_of(*t) == from ? OtherWay::Open : OtherWay::Bridge;
      away = d;
    }
    return OtherWay::Open;
  }

  // The connected component of the mesh triangle t lies in (by shared vertices), as the lowest
  // vertex index in it; the labels are made again when the mesh has grown since.
  int component_of(int t) {
    const Mesh& mesh = cover_.mesh();
    if (labelled_ != mesh.triangles.size() || labels_.parent.size() != mesh.positions.size()) {
      labels_.reset(mesh.positions.size());
      for (const auto& f : mesh.triangles) labels_.unite(f[0], f[1]), labels_.unite(f[0], f[2]);
      labelled_ = mesh.triangles.size();
    }
    return labels_.find(mesh.triangles[t][0]);
  }

  void visit(const SignChange& c) {
    ++report_.sign_changes;
    cover_.update();
    if (cover_.crosses(c.a, c.b)) return;
    // Before paying for the surface point: the linear interpolant and the segment's direction
    // from inside to outside usually settle it.
    const double t = c.fa / (c.fa - c.fb);
    const Vec3 outward = c.fa < 0 ? Vec3(c.b - c.a) : Vec3(c.a - c.b);
    if (meshed_at(c.a + t * (c.b - c.a), outward, 0)) {
      ++report_.covered_nearby;
      return;
    }
    const auto x = surface_point(field_, c);
    if (x && to_zero_node(c) && !surface_passes(field_, x->point, x->normal, kTouchingDepth * min_edge_)) {
      ++report_.touching_crossings;
      return;
    }
    unsure_.push_back({c, true, x});
    if (!x) return;
    if (meshed_at(*x)) {
      ++report_.covered_nearby;
      return;
    }
    if (walks_to_mesh(*x)) {
      // The component the surface may bridge to from here can still be meshed by a later seed.
      if (open_walk_ && deferring_) deferred_.push_back(*x);
      else ++report_.below_resolution;
      return;
    }
    consider_seed(*x);
  }

  // Seeds where the surface is curved more tightly than min_edge can resolve (a needle's tip)
  // wait until every other seed has been meshed: started there, a component cannot grow out of
  // the detail and would close over it, apart from the rest of its sheet.
  void consider_seed(const SurfacePoint& x) {
    if (!deferring_) {
      start_from(x);
      return;
    }
    double radius = 0;
    try {
      radius = curvature_at(field_, x.point).min_radius;
    } catch (const NoSurfaceError&) {
    }
    if (radius >= min_edge_) start_from(x);
    else deferred_.push_back(x);
  }

  void seed_deferred() {
    deferring_ = false;
    for (const SurfacePoint& x : deferred_) {
      cover_.update();
      if (meshed_at(x)) continue;
      if (walks_to_mesh(x)) {
        ++report_.below_resolution;
        continue;
      }
      start_from(x);
    }
  }

  void grid_sign_changes() {
    grid_.for_each_sign_change([&](const std::array<int, 3>& a, const std::array<int, 3>& b) {
      poll();
      visit({grid_.point(a[0], a[1], a[2]), grid_.point(b[0], b[1], b[2]), grid_.value(a[0], a[1], a[2]),
             grid_.value(b[0], b[1], b[2])});
    });
  }

  // --- fields with a Lipschitz bound: refine the cells that may hold surface.
  // Corner c of a cell is (c & 1, c >> 1 & 1, c >> 2 & 1) in units of the cell's side.
  static Vec3 corner_point(const Box& box, int c) {
    return {c & 1 ? box.max.x() : box.min.x(), c & 2 ? box.max.y() : box.min.y(), c & 4 ? box.max.z() : box.min.z()};
  }

  std::size_t cell_id(int i, int j, int k) const {
    return (static_cast<std::size_t>(k) * grid_.n[1] + j) * grid_.n[0] + i;
  }
  std::array<double, 8> corners_of(int i, int j, int k) const {
    std::array<double, 8> f;
    for (int v = 0; v < 8; ++v) f[v] = grid_.value(i + (v & 1), j + (v >> 1 & 1), k + (v >> 2 & 1));
    return f;
  }

  // The seed grid's cells that a grid edge shows crossed, and their neighbours (26-neighbourhood):
  // the crossed cells dilated by one along each axis in turn, which is the same set as looking at
  // the 26 neighbours of each cell.
  std::vector<char> near_crossed_cells() const {
    const auto& n = grid_.n;
    std::vector<char> near(static_cast<std::size_t>(n[0]) * n[1] * n[2]);
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i) near[cell_id(i, j, k)] = !one_sign(corners_of(i, j, k));
    for (int axis = 0; axis < 3; ++axis) {
      const std::vector<char> from = near;
      const std::array<int, 3> d{axis == 0, axis == 1, axis == 2};
      for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
          for (int i = 0; i < n[0]; ++i) {
            const int at = std::array<int, 3>{i, j, k}[axis];
            char& x = near[cell_id(i, j, k)];
            if (at > 0) x |= from[cell_id(i - d[0], j - d[1], k - d[2])];
            if (at + 1 < n[axis]) x |= from[cell_id(i + d[0], j + d[1], k + d[2])];
          }
    }
    return near;
  }

  void search_small_components(const std::vector<char>& near) {
    const auto& n = grid_.n;
    struct Candidate {
      Box box;
      std::array<double, 8> corners;
    };
    std::vector<Candidate> candidates;
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i) {
          // Cells the grid sees crossed, and their neighbours, are the seeded surface's: a
          // component that near another is found where it crosses a grid edge, not here (the
          // band around the surface would otherwise be refined everywhere, at several times the
          // cost of the polygonization on cheap fields).
          if (near[cell_id(i, j, k)]) continue;
          Candidate c{{grid_.point(i, j, k), grid_.point(i + 1, j + 1, k + 1)}, corners_of(i, j, k)};
          if (proved_empty_by_corners(c.box, c.corners)) continue;
          candidates.push_back(c);
        }
    refine_budget_ = std::clamp(kRefinedCellsPerTriangle * cover_.triangles(), kMinRefinedCells, kMaxRefinedCells);
    std::vector<Vec3> centres;
    for (const Candidate& c : candidates) centres.push_back(c.box.center());
    std::vector<double> values(centres.size());
    field_.values(centres.data(), values.data(), centres.size());
    for (std::size_t i = 0; i < candidates.size(); ++i) search_cell(candidates[i].box, candidates[i].corners, values[i]);
  }

  static bool one_sign(const std::array<double, 8>& f) {
    for (double v : f)
      if ((v < 0) != (f[0] < 0)) return false;
    return true;
  }

  // The model's value range excludes zero, or some corner is farther from zero than the
  // Lipschitz bound allows across the whole cell.
  bool proved_empty_by_corners(const Box& box, const std::array<double, 8>& f) const {
    if (const auto range = field_.value_range(box); range && (range->first > 0 || range->second < 0)) return true;
    const double L = *field_.lipschitz_bound(box);
    double largest = 0;
    for (double v : f) largest = std::max(largest, std::abs(v));
    return largest > L * box.diagonal();
  }

  void search_cell(const Box& box, const std::array<double, 8>& corners, double centre) {
    if ((centre < 0) != (corners[0] < 0)) {  // a component inside the cell, around its centre
      visit({box.center(), box.min, centre, corners[0]});
      return;
    }
    if (std::abs(centre) > *field_.lipschitz_bound(box) * 0.5 * box.diagonal()) return;  // no zero here
    cover_.update();
    if (cover_.explains(box)) return;  // what passes here is the meshed surface
    if (0.5 * box.size().maxCoeff() < min_edge_) {
      ++report_.unresolved_cells;
      return;
    }
    if (report_.refined_cells >= refine_budget_) {
      if (report_.unsearched_cells++ == 0) report_.first_unsearched = box.center();
      return;
    }
    ++report_.refined_cells;
    // The 3 x 3 x 3 lattice of the cell (its corners and centre are known) and the centres of its
    // children, evaluated in one batch for the children the known samples do not prove empty
    // (child c has the cell's corner c and centre as opposite corners).
    const Vec3 step = 0.5 * box.size();
    const auto lattice_point = [&](int a, int b, int c) { return Vec3(box.min + step.cwiseProduct(Vec3(a, b, c))); };
    const auto slot = [](int a, int b, int c) { return a + 3 * b + 9 * c; };
    const auto child_box = [&](int child) {
      const int ca = child & 1, cb = child >> 1 & 1, cc = child >> 2 & 1;
      return Box{lattice_point(ca, cb, cc), lattice_point(ca + 1, cb + 1, cc + 1)};
    };
    std::array<double, 27> lattice;
    std::array<bool, 27> known{};
    for (int v = 0; v < 8; ++v) {
      const int s = slot(2 * (v & 1), 2 * (v >> 1 & 1), 2 * (v >> 2 & 1));
      lattice[s] = corners[v], known[s] = true;
    }
    lattice[slot(1, 1, 1)] = centre, known[slot(1, 1, 1)] = true;
    std::array<bool, 8> open{};
    std::array<double, 8> child_centre{};
    std::vector<Vec3> points;
    std::vector<int> targets;  // a lattice slot, or -1 - child for a child's centre
    for (int child = 0; child < 8; ++child) {
      const Box sub = child_box(child);
      const double largest = std::max(std::abs(corners[child]), std::abs(centre));
      const auto range = field_.value_range(sub);
      if (largest > *field_.lipschitz_bound(sub) * sub.diagonal() || (range && (range->first > 0 || range->second < 0)))
        continue;
      open[child] = true;
      for (int v = 0; v < 8; ++v) {
        const int a = (child & 1) + (v & 1), b = (child >> 1 & 1) + (v >> 1 & 1), c = (child >> 2 & 1) + (v >> 2 & 1);
        if (known[slot(a, b, c)]) continue;
        known[slot(a, b, c)] = true;
        points.push_back(lattice_point(a, b, c));
        targets.push_back(slot(a, b, c));
      }
      points.push_back(sub.center());
      targets.push_back(-1 - child);
    }
    std::vector<double> values(points.size());
    field_.values(points.data(), values.data(), points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (targets[i] >= 0) lattice[targets[i]] = values[i];
      else child_centre[-1 - targets[i]] = values[i];
    }

    for (int child = 0; child < 8; ++child) {
      if (!open[child]) continue;
      const int ca = child & 1, cb = child >> 1 & 1, cc = child >> 2 & 1;
      const Box sub = child_box(child);
      std::array<double, 8> f;
      for (int v = 0; v < 8; ++v) f[v] = lattice[slot(ca + (v & 1), cb + (v >> 1 & 1), cc + (v >> 2 & 1))];
      if (one_sign(f)) {
        if (!proved_empty_by_corners(sub, f)) search_cell(sub, f, child_centre[child]);
        continue;
      }
      for_each_crossed_edge(f, [&](int v, int w) {
        visit({corner_point(sub, v), corner_point(sub, w), f[v], f[w]});
        return true;
      });
    }
  }

  // fn(v, w) for each of the twelve edges of a cell with corner values f (corner v to corner
  // w = v | 1 << axis, in that order) whose ends differ in sign, until fn returns false.
  template <class Fn>
  static void for_each_crossed_edge(const std::array<double, 8>& f, const Fn& fn) {
    for (int v = 0; v < 8; ++v)
      for (int axis = 0; axis < 3; ++axis) {
        const int w = v | 1 << axis;
        if (w == v || (f[v] < 0) == (f[w] < 0)) continue;
        if (!fn(v, w)) return;
      }
  }

  // --- sampled volumes: the band around the seeded surface, at about min_edge.
  // Noise in the samples puts small components right beside the surface (a bubble 0.05 across,
  // 0.05 from a noisy sphere's surface, inside a grid cell the sphere crosses) where neither the
  // grid's edges nor the search above look. Each cell of the band (near_crossed_cells) is sampled
  // on a lattice of step at most min_edge (kMaxBandSteps); the lattice's cells that a sign change
  // crosses fall into components by their shared faces, and one sign change of each component is
  // visited like a grid edge's: the component of the meshed surface is covered, a separate one is
  // seeded. A component holding a ball of diameter sqrt(3) times the step holds a lattice node
  // and is found.
  // Cells the field proves free of critical points (Field::gradient_range) are skipped: on a
  // clean scan that is nearly all of them.
  void scan_band(const std::vector<char>& near) {
    const auto& n = grid_.n;
    const int m = std::clamp(static_cast<int>(std::ceil(grid_.h / min_edge_)), 1, kMaxBandSteps);
    const int s = m + 1;
    const double step = grid_.h / m;
    const auto node = [s](int a, int b, int c) { return (c * s + b) * s + a; };
    const auto sub = [m](int a, int b, int c) { return (c * m + b) * m + a; };
    std::vector<double> values(static_cast<std::size_t>(s) * s * s);
    std::vector<char> crossed(static_cast<std::size_t>(m) * m * m);
    UnionFind sets(crossed.size());
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i) {
          if (!near[cell_id(i, j, k)]) continue;
          poll();
          const Vec3 origin = grid_.point(i, j, k);
          const Box box{origin, grid_.point(i + 1, j + 1, k + 1)};
          if (const auto range = field_.value_range(box); range && (range->first > 0 || range->second < 0)) continue;
          if (free_of_critical_points(box, corners_of(i, j, k))) continue;
          ++report_.band_cells;
          field_.values_on_lattice(origin, step, s, values.data());
          // The values at lattice cell (a, b, c)'s corners, numbered as corner_point's.
          const auto corners = [&](int a, int b, int c) {
            std::array<double, 8> f;
            for (int v = 0; v < 8; ++v) f[v] = values[node(a + (v & 1), b + (v >> 1 & 1), c + (v >> 2 & 1))];
            return f;
          };
          bool any = false;
          for (int c = 0; c < m; ++c)
            for (int b = 0; b < m; ++b)
              for (int a = 0; a < m; ++a) {
                const bool mixed = !one_sign(corners(a, b, c));
                crossed[sub(a, b, c)] = mixed;
                any |= mixed;
              }
          if (!any) continue;
          sets.reset(crossed.size());
          for (int c = 0; c < m; ++c)
            for (int b = 0; b < m; ++b)
              for (int a = 0; a < m; ++a) {
                if (!crossed[sub(a, b, c)]) continue;
                if (a + 1 < m && crossed[sub(a + 1, b, c)]) sets.unite(sub(a, b, c), sub(a + 1, b, c));
                if (b + 1 < m && crossed[sub(a, b + 1, c)]) sets.unite(sub(a, b, c), sub(a, b + 1, c));
                if (c + 1 < m && crossed[sub(a, b, c + 1)]) sets.unite(sub(a, b, c), sub(a, b, c + 1));
              }
          // A component's root is its lowest lattice cell (UnionFind keeps the smaller index), so
          // the visits follow the lattice's order.
          for (int c = 0; c < m; ++c)
            for (int b = 0; b < m; ++b)
              for (int a = 0; a < m; ++a) {
                const int id = sub(a, b, c);
                if (!crossed[id] || sets.find(id) != id) continue;
                ++report_.band_components;
                // Its first edge whose ends differ in sign.
                const Box cell{origin + step * Vec3(a, b, c), origin + step * Vec3(a + 1, b + 1, c + 1)};
                const std::array<double, 8> f = corners(a, b, c);
                for_each_crossed_edge(f, [&](int v, int w) {
                  if (!std::isfinite(f[v]) || !std::isfinite(f[w])) return true;
                  visit({corner_point(cell, v), corner_point(cell, w), f[v], f[w]});
                  return false;
                });
              }
        }
  }

  // No critical point of F in the cell: a component that no grid edge crosses encloses one (an
  // extremum of F inside it), so this cell holds none of its inside, and the cell that does is
  // scanned (or searched, outside the band). Proved by a derivative that keeps its sign over the
  // cell (Field::gradient_range, derivative_range): along an axis, or along the slope of the
  // cell's corner values, which leans on both faces across a crease of min or max and where the
  // gradient turns within the cell, where no axis derivative need keep its sign.
  bool free_of_critical_points(const Box& box, const std::array<double, 8>& f) const {
    const auto g = field_.gradient_range(box);
    if (g && ((g->first.array() > 0).any() || (g->second.array() < 0).any())) return true;
    // The trilinear interpolant's gradient at the centre: the mean of the four edge differences
    // along each axis.
    Vec3 slope = Vec3::Zero();
    for (int v = 0; v < 8; ++v)
      for (int axis = 0; axis < 3; ++axis)
        if (!(v >> axis & 1)) slope[axis] += f[v | 1 << axis] - f[v];
    if (!slope.allFinite() || !(slope.squaredNorm() > 0)) return false;
    // From the gradient's ranges where the field gave them (not asked for twice).
    const Vec3 u = slope.normalized();
    const auto r = g ? std::optional(Field::derivative_range_of(*g, u)) : field_.derivative_range(box, u);
    return r && (r->first > 0 || r->second < 0);
  }

  // --- Newton probes: from the local minima of |F| on the grid (fields without a bound) and from
  // the band's nodes where the level sets curl (fields that are not sampled volumes, which scan
  // the band instead). A small component beside the surface, in a cell the surface crosses or
  // borders, crosses no grid edge, and the nodes around it see the surface's sign change next to
  // them, so none is a strict local minimum; but the level sets of F curl around it (see
  // level_sets_curl), and Newton from such a node lands on it. Beads of radius 0.008-0.04 at
  // 0.01-0.1 from a unit sphere, a box, a torus and voids under a sphere (expressions, factor 3,
  // 40 placed at random): 10 meshed without these probes, 35 with them, 7 probes a run (median).
  // Of three such sets (120 beads) 118 now: the misses were beads a front vertex was projected
  // onto (Tracker::jumped) or that the segment test took for a flat face (meshed_at); the two
  // left are voids a probe does not reach.
  void probe(const std::vector<char>& near, bool local_minima, bool band) {
    if (!local_minima && !band) return;
    const auto& n = grid_.n;
    // A node of the band: a corner of a near cell.
    const auto in_band = [&](int i, int j, int k) {
      for (int v = 0; v < 8; ++v) {
        const int a = i - (v & 1), b = j - (v >> 1 & 1), c = k - (v >> 2 & 1);
        if (a >= 0 && b >= 0 && c >= 0 && a < n[0] && b < n[1] && c < n[2] && near[cell_id(a, b, c)]) return true;
      }
      return false;
    };
    ProjectionOptions po;
    po.max_travel = 2 * grid_.h;
    po.max_step = 0.5 * grid_.h;
    std::vector<Vec3> starts;
    std::vector<char> from_band;
    for (int k = 0; k <= n[2]; ++k)
      for (int j = 0; j <= n[1]; ++j)
        for (int i = 0; i <= n[0]; ++i) {
          const double v = grid_.value(i, j, k);
          if (v == 0) continue;
          const bool minimum = local_minima && strict_local_minimum(i, j, k);
          if (minimum || (band && in_band(i, j, k) && level_sets_curl(i, j, k))) {
            starts.push_back(grid_.point(i, j, k));
            from_band.push_back(!minimum);
          }
        }
    keep_curling(starts, from_band);
    // The probes' projections and normals depend on the field alone, not on the mesh the
    // earlier probes' seeds grow: they are evaluated in batches up front, then taken in order.
    report_.probes += starts.size();
    const std::vector<ProjectionOptions> options(starts.size(), po);
    const std::vector<ProjectionResult> r = project_to_surface(field_, starts, options);
    std::vector<Vec3> landed;
    for (const ProjectionResult& x : r)
      if (x.ok()) landed.push_back(x.point);
    std::vector<double> values(landed.size());
    std::vector<Vec3> gradients(landed.size());
    field_.values_gradients(landed.data(), values.data(), gradients.data(), landed.size());
    // A probe from a node on the box's faces may follow F out of the box to a component wholly
    // outside it (a repetition's next ball, 0.05 beyond the face: a box of 27 balls meshed as 81).
    // The box is the caller's: what lies beyond it is not seeded; what crosses it fails as ever.
    const Box box = field_.bounds();
    const Box inside = box.inflated(kOutsideBox * box.diagonal());
    for (std::size_t i = 0; i < landed.size(); ++i) {
      const Vec3& g = gradients[i];
      if (!(g.squaredNorm() > 0) || !g.allFinite()) continue;
      if (!inside.contains(landed[i])) {
        ++report_.probes_outside;
        continue;
      }
      const SurfacePoint x{landed[i], g.normalized()};
      cover_.update();
      if (walks_to_mesh(x)) continue;  // its first test is meshed_at(x)
      unsure_.push_back({{}, false, x});
      consider_seed(x);
    }
  }

  // The level set through node (i, j, k) curls around it within about two cells (kBandCurl), as
  // it does around a small component near the node: with g = F signed so that g > 0 at the node,
  // the discrete Laplacian of g over its six neighbours against its central-difference slope,
  // about h times the level set's mean curvature (2 h / radius for a distance to a ball). A node
  // on the grid's faces is not tested.
  bool level_sets_curl(int i, int j, int k) const {
    const auto& n = grid_.n;
    const double v = grid_.value(i, j, k);
    const double s = v < 0 ? -1 : 1;
    double laplacian = 0, slope2 = 0;
    for (int axis = 0; axis < 3; ++axis) {
      std::array<int, 3> lo{i, j, k}, hi{i, j, k};
      --lo[axis], ++hi[axis];
      if (lo[axis] < 0 || hi[axis] > n[axis]) return false;
      const double a = s * grid_.value(lo[0], lo[1], lo[2]), b = s * grid_.value(hi[0], hi[1], hi[2]);
      laplacian += a + b - 2 * s * v;
      slope2 += 0.25 * (b - a) * (b - a);
    }
    return laplacian > kBandCurl * std::sqrt(slope2);
  }

  // Of the band's nodes, those where the level set through the node also curls by F's own
  // derivatives (h times its mean curvature, (|g|^2 tr H - g^T H g) / |g|^3 with g the gradient,
  // H the Hessian, signed as in level_sets_curl, over kBandCurl): the grid's measure also sees a
  // crease (max(abs(x), abs(y)) curls around a box's edge on the grid), but the piece of F
  // taken at the node is flat there, while around a small component, as Newton from the node
  // follows it, it is not. One batch of Hessians; the local minima stay.
  void keep_curling(std::vector<Vec3>& starts, std::vector<char>& from_band) const {
    std::vector<Vec3> nodes;
    for (std::size_t i = 0; i < starts.size(); ++i)
      if (from_band[i]) nodes.push_back(starts[i]);
    if (nodes.empty()) return;
    std::vector<double> values(nodes.size());
    std::vector<Vec3> gradients(nodes.size());
    std::vector<Mat3> hessians(nodes.size());
    field_.gradients_hessians(nodes.data(), values.data(), gradients.data(), hessians.data(), nodes.size());
    std::size_t kept = 0, band = 0;
    for (std::size_t i = 0; i < starts.size(); ++i) {
      bool keep = !from_band[i];
      if (from_band[i]) {
        const Vec3& g = gradients[band];
        const Mat3& H = hessians[band];
        const double slope = g.norm(), s = values[band] < 0 ? -1 : 1;
        ++band;
        const double curvature = (g.squaredNorm() * H.trace() - g.dot(H * g)) / (slope * slope * slope);
        keep = slope > 0 && std::isfinite(curvature) && s * curvature * grid_.h > kBandCurl;
      }
      if (keep) starts[kept] = starts[i], from_band[kept] = from_band[i], ++kept;
    }
    starts.resize(kept);
    from_band.resize(kept);
  }

  // |F| at node (i, j, k) below that of its 26 neighbours, all of the same sign (ties go to the
  // lower node index, so that a plateau yields one probe).
  bool strict_local_minimum(int i, int j, int k) const {
    const auto& n = grid_.n;
    const double v = grid_.value(i, j, k);
    const std::size_t self = grid_.index(i, j, k);
    for (int dk = -1; dk <= 1; ++dk)
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          const int a = i + di, b = j + dj, c = k + dk;
          if ((di == 0 && dj == 0 && dk == 0) || a < 0 || b < 0 || c < 0 || a > n[0] || b > n[1] || c > n[2]) continue;
          const double u = grid_.value(a, b, c);
          if ((u < 0) != (v < 0)) return false;
          if (std::abs(u) < std::abs(v) || (std::abs(u) == std::abs(v) && grid_.index(a, b, c) < self)) return false;
        }
    return true;
  }

  void recheck() {
    cover_.update();
    for (const Witness& w : unsure_) {
      poll();
      if (w.has_segment && cover_.crosses(w.change.a, w.change.b)) continue;
      if (w.at && walks_to_mesh(*w.at)) continue;  // its first test is meshed_at
      if (report_.uncovered++ == 0) report_.first_uncovered = w.at ? w.at->point : 0.5 * (w.change.a + w.change.b);
    }
  }

  // Whether c ends at a node where F is zero to rounding (kTouchingZero), its other end inside: a
  // sign change to a node on a face where two solids touch, which sample_seed_grid counts as
  // inside only where it lies between inside nodes (not where the other side is a table top
  // thinner than a cell, with air beyond). Where the node is outside, the surface the sign change
  // crosses is there, and its point is seeded (or, not meshed, an error) as any other.
  bool to_zero_node(const SignChange& c) const {
    const double outside = c.fa < 0 ? c.fb : c.fa;
    return outside >= 0 && outside <= kTouchingZero * grid_.h;
  }

  // The cancel poll of the checks between components (the tracker polls its own loop).
  void poll() {
    if (++polls_ % kPollEvery == 0) tracker_.cancel_token().check("adaptive: seeding");
  }

  const Field& field_;
  const SeedGrid& grid_;
  double min_edge_;
  std::size_t polls_ = 0;
  Tracker& tracker_;
  MeshCoverage cover_;
  std::vector<Deviation> deviations_;  // by triangle, see deviation()
  std::vector<Witness> unsure_;
  std::vector<SurfacePoint> deferred_;
  bool deferring_ = true;
  bool open_walk_ = false;  // the last walks_to_mesh's other way was Open
  Bridges* bridges_;        // the caller's: seeded first, and found
  UnionFind labels_{0};     // component_of's, over the mesh's vertices
  std::size_t labelled_ = 0;  // the mesh's triangles when labels_ was made
  SeedingReport report_;
  std::size_t refine_budget_ = kMinRefinedCells;  // search_small_components sets it
};

}  // namespace

SeedingReport seed_every_component(const Field& field, const SeedGrid& grid, double min_edge, double cell,
                                   Tracker& tracker, const Mesh& mesh, Bridges* bridges) {
  return Seeder(field, grid, min_edge, cell, tracker, mesh, bridges).run();
}

}  // namespace cdp::adaptive
