#include "tracker.h"

#include <polygonizer/errors.h>

#include <chrono>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace cdp::adaptive {

namespace {
// Newton leaves points within 1e-10 of the diagonal from the surface, hence from a crease they
// landed on; a probe this far away is clear of that and still on the crease's two pieces.
constexpr double kCreaseProbe = 1e-7;
// Gradients more than 10 degrees apart across such a probe mean a crease, not curvature.
constexpr double kCreaseCosine = 0.985;
// A placement walks on when Newton lands less than this share of the step from where it
// started, in up to kWalkLegs legs (a cube's crease takes three: onto the crease, off it, on).
constexpr double kShortLanding = 0.75;
constexpr int kWalkLegs = 4;
// A new point this close to a finished vertex (in units of the step) lies on finished mesh.
constexpr double kOverMesh = 0.3;
}  // namespace

Tracker::Tracker(const Field& field, const Settings& settings, Mesh& mesh)
    : field_(field), s_(settings), mesh_(mesh),
      front_hash_(settings.hash_cell), vertex_hash_(settings.hash_cell) {}

std::optional<Tracker::Placed> Tracker::measure(const Vec3& p) const {
  // Timed in two parts, so that the stats can show what the paper claims (curvature costs
  // little) for each of its costs: the field's Hessian, and the eigen-decomposition of C.
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto evaluated = start;
  std::optional<Placed> out;
  try {
    Vec3 g;
    Mat3 h;
    field_.gradient_hessian(p, g, h);
    evaluated = Clock::now();
    out = Placed{p, curvature_from_derivatives(g, h)};
  } catch (const NoSurfaceError&) {
  }
  const auto done = Clock::now();
  if (evaluated == start) evaluated = done;
  hessian_seconds_ += std::chrono::duration<double>(evaluated - start).count();
  curvature_seconds_ += std::chrono::duration<double>(done - start).count();
  if (out && !out->curvature.normal.allFinite()) out.reset();
  return out;
}

int Tracker::add_vertex(const Placed& placed) {
  const Curvature& c = placed.curvature;
  const int v = static_cast<int>(mesh_.positions.size());
  mesh_.positions.push_back(placed.point);
  mesh_.normals.push_back(c.normal);
  target_.push_back(edge_length(s_.sizing, c.min_radius));
  mac_.push_back(c.mac);
  shape_index_.push_back(c.shape_index);
  front_refs_.push_back(0);
  vertex_hash_.insert(v, placed.point);
  return v;
}

std::optional<Tracker::Placed> Tracker::place_point(int v, const Vec3& dir, double d) const {
  // Walk d along the surface in direction dir: a straight step in the tangent plane, then Newton.
  // Where Newton lands on a crease well short of d (the projection does not cross creases), the
  // walk goes on from there in the tangent plane of the crease point with what is left of d, at
  // most kWalkLegs legs, so that fronts fold over creases instead of piling points onto them.
  const Vec3& origin = mesh_.positions[v];
  ProjectionOptions po;
  po.tolerance = 1e-10 * s_.diagonal;
  Vec3 at = origin, normal = mesh_.normals[v], heading = dir;
  double left = d;
  std::optional<Placed> placed;
  for (int leg = 0; leg < kWalkLegs; ++leg) {
    po.max_step = left;
    po.max_travel = left;
    const ProjectionResult r = project_to_surface(field_, at + left * heading, po);
    if (!r.ok()) return std::nullopt;
    placed = measure(r.point);
    if (!placed) return std::nullopt;
    bool on_crease = false;
    const Vec3& landed = placed->curvature.normal;
    // Newton runs along the gradient, which turns little on the way over a smooth surface; a
    // gradient at the start that points elsewhere than the one where it lands means the path
    // crossed a crease, and the landing point may lie on it even though its own gradient is
    // one side's (at a tie of max or min, the cube's edges, the gradient is one piece's, the
    // same as the origin's face).
    const Vec3& g0 = r.start_gradient;
    const bool turned = !(g0.squaredNorm() > 0) || g0.normalized().dot(landed) < kCreaseCosine;
    if (turned || !same_side(normal, landed)) {
      // Across a crease of a CSG shape the gradient turns at once; a point on the crease gets
      // the mean of the normals on both sides, so that both sides see it as theirs.
      const auto crease = crease_normal(r.point, landed);
      if (crease) {
        if (!same_side(normal, *crease)) return std::nullopt;
        placed->curvature.normal = *crease;
        ++crease_points_;
        on_crease = true;
      } else if (!same_side(normal, landed)) {
        return std::nullopt;
      }
    }
    if (leg == 0 && !on_crease && d > s_.sizing.min_edge && normal.dot(placed->curvature.normal) < kMaxTurnCosine)
      return std::nullopt;
    const double moved = (r.point - at).norm();
    left -= moved;
    at = r.point;
    if (!on_crease || left <= (1 - kShortLanding) * d || leg + 1 == kWalkLegs) break;
    normal = placed->curvature.normal;
    heading -= normal * normal.dot(heading);
    if (!(heading.squaredNorm() > 1e-12)) break;
    heading.normalize();
  }
  // Newton may jump to a nearby sheet of the surface; such a point is not a neighbour of v.
  const double dist = (at - origin).norm();
  if (dist < 0.25 * d || dist > 1.75 * d) return std::nullopt;
  if (over_finished_mesh(placed->point, placed->curvature.normal, d)) return std::nullopt;
  return placed;
}

bool Tracker::over_finished_mesh(const Vec3& x, const Vec3& normal, double d) const {
  // A new point next to a vertex that has left every front lies on finished mesh: a front has
  // run over it and would go on meshing the surface again. Refused, such placements turn a
  // runaway front into a stalled one, which the stall bounds end with an error naming the place.
  const double r = kOverMesh * d;
  bool hit = false;
  vertex_hash_.for_each_near(x, r, [&](int w) {
    if (!hit && front_refs_[w] == 0 && (mesh_.positions[w] - x).norm() < r && same_side(normal, w)) hit = true;
  });
  if (hit) ++over_mesh_;
  return hit;
}

std::optional<Vec3> Tracker::crease_normal(const Vec3& x, const Vec3& n) const {
  // On a crease of max(f, g) (or min) the gradient at x is one side's; a step just inside or
  // just outside along it makes the other side's piece the active one.
  const double eps = kCreaseProbe * s_.diagonal;
  Vec3 best = n;
  for (const double side : {-1.0, 1.0}) {
    const Vec3 g = field_.gradient(x + side * eps * n);
    if (!(g.squaredNorm() > 0) || !g.allFinite()) continue;
    const Vec3 u = g.normalized();
    if (u.dot(n) < best.dot(n)) best = u;
  }
  if (!(best.dot(n) < kCreaseCosine)) return std::nullopt;
  const Vec3 mean = n + best;
  if (!(mean.squaredNorm() > 1e-6)) return std::nullopt;
  return mean.normalized();
}

void Tracker::emit_triangle(int a, int b, int c) {
  mesh_.triangles.push_back({a, b, c});
  const Vec3& pa = mesh_.positions[a];
  area_ += 0.5 * (mesh_.positions[b] - pa).cross(mesh_.positions[c] - pa).norm();
  if (estimated_area_ > 0 && area_ > kAreaBound * estimated_area_)
    throw LimitExceededError("adaptive: the mesh covers more than " + std::to_string(static_cast<int>(kAreaBound)) +
                             " times the area the seed grid measures; a front is running over finished mesh near (" +
                             std::to_string(pa.x()) + ", " + std::to_string(pa.y()) + ", " + std::to_string(pa.z()) +
                             ")");
  if (mesh_.triangles.size() > s_.max_triangles)
    throw LimitExceededError("adaptive: more than " + std::to_string(s_.max_triangles) +
                             " triangles (AdaptiveOptions::max_triangles); raise the limit, the minimum edge "
                             "length or lower the factor");
}

void Tracker::link(int a, int b) {
  fs_.link(a, b);
  front_edges_.emplace((mesh_.positions[fs_.nodes[a].vertex] - mesh_.positions[fs_.nodes[b].vertex]).norm(), a, b);
}

double Tracker::longest_front_edge() const {
  while (!front_edges_.empty()) {
    const auto& [length, a, b] = front_edges_.top();
    if (fs_.nodes[a].front >= 0 && fs_.nodes[a].next == b) return length;
    front_edges_.pop();
  }
  return 0;
}

int Tracker::insert_node(int vertex, int front) {
  const int n = fs_.new_node(vertex, front);
  ++front_refs_[vertex];
  front_hash_.insert(n, mesh_.positions[vertex]);
  return n;
}

void Tracker::remove_node(int node) {
  FrontNode& n = fs_.nodes[node];
  --front_refs_[n.vertex];
  front_hash_.remove(node, mesh_.positions[n.vertex]);
  --fs_.fronts[n.front].size;
  n.front = -1;
  ++n.version;
}

void Tracker::refresh(int node) {
  fs_.nodes[node].angle = front_angle(node);
  fs_.push(node);
}

void Tracker::relabel(int start, int front) {
  int n = start;
  do {
    fs_.nodes[n].front = front;
    fs_.push(n);
    n = fs_.nodes[n].next;
  } while (n != start);
}

double Tracker::local_edge_length(int node) const {
  // The paper evaluates the heuristic at the point and at both front neighbours and keeps the
  // smallest, so that an expansion never outruns a region of higher curvature next to it.
  const FrontNode& n = fs_.nodes[node];
  return std::min({target_[n.vertex], target_[fs_.nodes[n.prev].vertex], target_[fs_.nodes[n.next].vertex]});
}

bool Tracker::mesh_from_seed(const Vec3& seed) {
  const auto seed_placed = measure(seed);
  if (!seed_placed) return false;
  const int c = add_vertex(*seed_placed);
  const Vec3 n = mesh_.normals[c];
  Vec3 axis = Vec3::UnitX();
  if (std::abs(n.y()) < std::abs(n[0]) && std::abs(n.y()) <= std::abs(n.z())) axis = Vec3::UnitY();
  else if (std::abs(n.z()) < std::abs(n[0]) && std::abs(n.z()) < std::abs(n.y())) axis = Vec3::UnitZ();
  const Vec3 e0 = axis.cross(n).normalized();
  const Vec3 e1 = n.cross(e0);

  // The hexagon of Figure 5a; shrink it where Newton cannot place its corners.
  std::vector<Placed> corners;
  for (double d = target_[c]; d >= 0.24 * s_.sizing.min_edge && corners.size() < 6; d *= 0.5) {
    corners.clear();
    for (int k = 0; k < 6; ++k) {
      const double t = k * std::numbers::pi / 3;
      const auto p = place_point(c, std::cos(t) * e0 + std::sin(t) * e1, d);
      if (!p) break;
      corners.push_back(*p);
    }
  }
  if (corners.size() < 6) {
    // Keep the mesh free of an isolated vertex: the seed vertex is the last one added.
    vertex_hash_.remove(c, mesh_.positions[c]);
    mesh_.positions.pop_back();
    mesh_.normals.pop_back();
    target_.pop_back();
    mac_.pop_back();
    shape_index_.pop_back();
    front_refs_.pop_back();
    return false;
  }
  std::vector<int> v(6);
  for (int k = 0; k < 6; ++k) v[k] = add_vertex(corners[k]);
  for (int k = 0; k < 6; ++k) emit_triangle(c, v[k], v[(k + 1) % 6]);

  const int f = fs_.new_front();
  std::vector<int> nodes(6);
  for (int k = 0; k < 6; ++k) nodes[k] = insert_node(v[k], f);
  // Triangle (c, v_k, v_k+1) owns the edge v_k -> v_k+1, so the front runs the other way.
  for (int k = 0; k < 6; ++k) link(nodes[(k + 1) % 6], nodes[k]);
  for (int k = 0; k < 6; ++k) refresh(nodes[k]);
  stack_.push_back(f);
  run_fronts();
  return true;
}

void Tracker::check_limits() {
  if (++steps_ > s_.max_steps)
    throw LimitExceededError("adaptive: more than " + std::to_string(s_.max_steps) +
                             " front steps (AdaptiveOptions::max_steps) without closing the surface");
  // Every 64 steps: cheap next to a step, and often enough that a run whose steps have become
  // slow still shows it is moving (the reporter decides how often to print).
  if (progress_ && estimated_area_ > 0 && (steps_ & 63) == 0) {
    const double f = std::min(0.99, area_ / estimated_area_);
    if (f > last_progress_) {
      last_progress_ = f;
      progress_(f);
    }
  }
}

void Tracker::check_search_budget(int node) {
  if (steps_ % kSearchWindow != 0) return;
  const std::uint64_t visits = search_visits();
  const std::uint64_t in_window = visits - window_visits_;
  window_visits_ = visits;
  if (in_window <= kSearchVisitsPerStep * kSearchWindow) return;
  const Vec3& p = mesh_.positions[fs_.nodes[node].vertex];
  throw LimitExceededError("adaptive: the fronts' neighbour searches looked at " + std::to_string(in_window / kSearchWindow) +
                           " points a step over the last " + std::to_string(kSearchWindow) + " steps (bound " +
                           std::to_string(kSearchVisitsPerStep) + "), near (" + std::to_string(p.x()) + ", " +
                           std::to_string(p.y()) + ", " + std::to_string(p.z()) +
                           "): edges far shorter than elsewhere crowd the search cells there, or a front is "
                           "running over finished mesh; raise min_edge");
}

void Tracker::run_fronts() {
  while (!stack_.empty()) {
    int f = stack_.back();
    stack_.pop_back();
    while (fs_.fronts[f].alive) {
      if (fs_.fronts[f].size <= 3) {
        // Figure 6, line 21: the last three points form one triangle.
        Front& fr = fs_.fronts[f];
        if (fr.size < 3) throw std::logic_error("adaptive: a front shrank below three points");
        const int a = fs_.pop_min(f);
        if (a < 0) throw std::logic_error("adaptive: a front lost its queue");
        const int b = fs_.nodes[a].next, c = fs_.nodes[b].next;
        const int va = fs_.nodes[a].vertex, vb = fs_.nodes[b].vertex, vc = fs_.nodes[c].vertex;
        // A three-point front through one vertex twice encloses nothing (see zip_spike).
        if (va != vb && vb != vc && va != vc) emit_triangle(va, vb, vc);
        remove_node(a);
        remove_node(b);
        remove_node(c);
        fr.alive = false;
        fr.heap = {};
        break;
      }
      step(f);
    }
  }
}

bool Tracker::zip_spike(int node) {
  // After a merge a front may pass twice through one vertex. Once the points between the two
  // passes are used up, the front runs p -> y -> p (both sides of edge p-y are meshed) or
  // p -> p: a loop enclosing nothing, which is cut out without a triangle.
  FrontNode& n = fs_.nodes[node];
  const int v = n.vertex;
  if (fs_.nodes[n.next].vertex == v) {
    const int prev = n.prev;
    remove_node(node);
    link(prev, fs_.nodes[node].next);
    refresh(prev);
    refresh(fs_.nodes[node].next);
    return true;
  }
  if (fs_.nodes[n.prev].vertex != fs_.nodes[n.next].vertex) return false;
  const int before = n.prev, twin = n.next, after = fs_.nodes[twin].next;
  remove_node(node);
  remove_node(twin);
  link(before, after);
  refresh(before);
  refresh(after);
  return true;
}

namespace {
// Fronts up to this size that are stuck get closed by ears (see step).
constexpr int kSmallFront = 8;
}  // namespace

void Tracker::step(int& f) {
  check_limits();
  const int node = fs_.pop_min(f);
  if (node < 0) throw std::logic_error("adaptive: a front lost its queue");
  check_search_budget(node);
  if (zip_spike(node)) {
    fs_.fronts[f].stall = 0;
    return;
  }
  // A front whose every point has been deferred in turn is stuck at this edge length (a tube
  // thinner than the edge, a gap narrower than it): each further round retries with half the
  // length, down to a quarter of min_edge, before giving up with an error instead of spinning.
  const int size = std::max(fs_.fronts[f].size, 1);
  const int rounds = fs_.fronts[f].stall / size;
  if (rounds >= 2 && size <= kSmallFront) {
    // A small hole that no expansion fits into is closed like the paper's last three points:
    // the ear of smallest front angle first (it is below pi, since the angles of a small
    // front sum to about (size - 2) pi).
    int best = node;
    for (int x = fs_.nodes[node].next; x != node; x = fs_.nodes[x].next)
      if (fs_.nodes[x].angle < fs_.nodes[best].angle) best = x;
    if (best != node) fs_.push(node);
    close_angle(best);
    ++forced_closures_;
    fs_.fronts[f].stall = 0;
    return;
  }
  double delta = local_edge_length(node);
  if (rounds > 0) {
    const double shrunk = delta * std::ldexp(1.0, -rounds);
    if (shrunk < 0.25 * s_.sizing.min_edge && rounds > 1) {
      const Vec3& p = mesh_.positions[fs_.nodes[node].vertex];
      throw LimitExceededError("adaptive: a front of " + std::to_string(fs_.fronts[f].size) +
                               " points near (" + std::to_string(p.x()) + ", " + std::to_string(p.y()) + ", " +
                               std::to_string(p.z()) +
                               ") cannot advance even at a quarter of min_edge; lower min_edge or raise the factor");
    }
    delta = std::max(shrunk, 0.25 * s_.sizing.min_edge);
  }
  int q = find_collision(node, delta);
  if (q < 0) {
      const ExpandOutcome r = expand(node, delta);
    if (r.expanded) {
      fs_.fronts[f].stall = 0;
      return;
    }
    q = r.obstacle;
    // A stuck front looks farther for a point to bridge to.
    if (q < 0 && rounds > 0) q = find_bridge(node, 3 * s_.collision_factor * local_edge_length(node));
    if (q < 0) {
      // Nothing to bridge to and no room to expand: let the other points of the front move
      // first.
      // Keys grow with the front's stall count, so deferred points queue up behind every point
      // not deferred yet and take their turns in order.
      ++deferrals_;
      const int stall = ++fs_.fronts[f].stall;
      fs_.push_with_key(node, fs_.nodes[node].angle + 2 * std::numbers::pi * stall);
      return;
    }
  }
  if (fs_.nodes[q].front == f) split_front(node, q);
  else f = merge_fronts(node, q);
  fs_.fronts[f].stall = 0;
}

}  // namespace cdp::adaptive
