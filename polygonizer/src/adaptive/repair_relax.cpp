// The relaxation (repair_context.h): stretched triangles' edges flipped and vertices moved
// towards equilateral stars, searched in the tangent plane where the mean edge ratio stays over the aim.
#include "repair_context.h"

namespace cdp::adaptive::repair_detail {

Vec3 Improver::equilateral_step(int v) const {
  const Vec3 x = P(v), n = m_.normals[v];
  Vec3 apex_mean = Vec3::Zero();
  int apexes = 0;
  for (int u : vt_[v]) {
    const Tri& t = m_.triangles[u];
    int k = 0;
    while (t[k] != v) ++k;
    const Vec3 &a = P(t[(k + 1) % 3]), &b = P(t[(k + 2) % 3]);
    const Vec3 side = n.cross(b - a);  // towards v's side of edge a -> b, seen from outside
    if (!(side.squaredNorm() > 0)) continue;
    apex_mean += 0.5 * (a + b) + std::sqrt(3.0) / 2 * (b - a).norm() * side.normalized();
    ++apexes;
  }
  if (apexes == 0) return Vec3::Zero();
  Vec3 step = apex_mean / apexes - x;
  return step - n * n.dot(step);
}

Vec3 Improver::searched_step(int v, const Vec3& first, double keep_cos) const {
  const Vec3 x = P(v), n = m_.normals[v];
  const StarShape start = star_shape(v);
  const double cos_cap = std::max(start.max_cos, keep_cos);
  const auto score = [&](const Vec3& step) {
    const StarShape s = star_shape(v, x + step);
    return s.max_cos <= cos_cap ? s.mean_ratio : std::numeric_limits<double>::infinity();
  };
  Vec3 best = Vec3::Zero();
  double best_score = start.mean_ratio;
  if (const double f = score(first); f < best_score) best = first, best_score = f;
  const Vec3 e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  const std::array<Vec3, 4> directions{e1, Vec3(-e1), e2, Vec3(-e2)};
  double stride = 0.5 * first.norm();
  for (int judged = 1; judged < kRelaxSearchStars;) {
    bool gained = false;
    for (const Vec3& d : directions) {
      if (judged++ >= kRelaxSearchStars) break;
      const Vec3 step = best + stride * d;
      if (const double f = score(step); f < best_score) {
        best = step, best_score = f, gained = true;
        break;
      }
    }
    if (!gained) stride *= 0.5;
  }
  return best_score < start.mean_ratio * (1 - kRelaxMinGain) ? best : Vec3::Zero();
}

auto Improver::star_shape(int v, const Vec3& at) const -> StarShape {
  const auto pos = [&](int w) -> const Vec3& { return w == v ? at : P(w); };
  StarShape s;
  for (int u : vt_[v]) {
    const Tri& t = m_.triangles[u];
    const Vec3 &a = pos(t[0]), &b = pos(t[1]), &c = pos(t[2]);
    std::array<double, 3> l{(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()};
    std::sort(l.begin(), l.end());
    const double xy = l[1] * l[2];
    s.mean_ratio += l[0] > 0 ? std::sqrt(l[2] / l[0]) : std::numeric_limits<double>::infinity();
    s.max_cos = std::max(s.max_cos, xy > 0 ? std::min(1.0, (l[1] + l[2] - l[0]) / (2 * std::sqrt(xy))) : 1.0);
  }
  s.mean_ratio /= std::max<std::size_t>(1, vt_[v].size());
  return s;
}

double Improver::mean_edge_ratio() const {
  double sum = 0;
  std::size_t n = 0;
  for (int t = 0; t < tri_count(); ++t)
    if (alive_[t]) sum += tri_ratio(m_.triangles[t]), ++n;
  return n ? sum / n : 0;
}

void Improver::relax_sweeps(int sweeps, bool search) {
  const double keep_cos = std::cos(kRelaxKeepDegrees * std::numbers::pi / 180);
  // Vertices moved in the previous sweep: a later sweep moves only those, the vertices whose
  // star holds one, and the corners of this sweep's flips (any other would compute the same
  // target and be refused again, but for the rare move refused for crossing a triangle beyond
  // its star that has moved since).
  std::vector<char> moved;
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    if (search && sweep > 0 && mean_edge_ratio() <= o_.aim_mean_edge_ratio) break;
    if (search) ++r_.relax_search_sweeps;
    flip_stretched();
    const std::vector<char> mark = mark_stretched(sweep > 0 ? &moved : nullptr);
    moved.assign(m_.positions.size(), 0);
    const RelaxMoves moves = relax_targets(mark, search, keep_cos);
    if (moves.vertices.empty()) break;
    if (!apply_moves(moves, project_moves(moves), search, keep_cos, moved)) break;
  }
}

// First the flips (try_flip's for_ratio): each stretched triangle's edges, longest first.
void Improver::flip_stretched() {
  flipped_.assign(m_.positions.size(), 0);
  for (int t = 0; t < tri_count(); ++t) {
    poll(static_cast<std::size_t>(t));
    if (!alive_[t] || !(tri_ratio(m_.triangles[t]) > kRelaxRatio)) continue;
    const Tri T = m_.triangles[t];
    int k = 0;
    double longest = 0;
    for (int i = 0; i < 3; ++i) {
      const double l = (P(T[(i + 1) % 3]) - P(T[i])).squaredNorm();
      if (l > longest) longest = l, k = i;
    }
    for (int i = 0; i < 3; ++i)
      if (try_flip(t, (k + i) % 3, true)) break;
  }
}

// The corners of stretched triangles; after the first sweep (`moved` given) only those moved in
// the sweep before, flipped in this one, or with a moved vertex in their star.
std::vector<char> Improver::mark_stretched(const std::vector<char>* moved_before) const {
  std::vector<char> mark(m_.positions.size(), 0);
  for (int t = 0; t < tri_count(); ++t) {
    if (!alive_[t] || !(tri_ratio(m_.triangles[t]) > kRelaxRatio)) continue;
    const Tri& x = m_.triangles[t];
    for (int v : x) mark[v] = 1;
  }
  if (moved_before) {
    const std::vector<char>& moved = *moved_before;
    for (int v = 0; v < static_cast<int>(mark.size()); ++v) {
      if (!mark[v] || moved[v] || flipped_[v]) continue;
      bool star_moved = false;
      for (int u : vt_[v])
        for (int w : m_.triangles[u]) star_moved = star_moved || moved[w];
      mark[v] = star_moved;
    }
  }
  return mark;
}

Improver::RelaxMoves Improver::relax_targets(const std::vector<char>& mark, bool search, double keep_cos) {
  // The marked vertices off creases (on_crease may evaluate and caches: one thread), then
  // their targets, each judged on its own (read only: on several threads, one slot each).
  // Reserved (nothing touched) so that no push_back copies megabytes between two polls.
  std::vector<int> eligible;
  eligible.reserve(mark.size());
  for (int v = 0; v < static_cast<int>(mark.size()); ++v) {
    poll(static_cast<std::size_t>(v));
    if (mark[v] && vt_[v].size() >= 3 && !on_crease(v)) eligible.push_back(v);
  }
  std::vector<Vec3> target = polled_vector<Vec3>(eligible.size(), Vec3::Zero());
  std::vector<double> reach = polled_vector<double>(eligible.size(), 0);
  std::vector<char> moves = polled_vector<char>(eligible.size(), 0);
  detail::parallel_blocks(eligible.size(), kRelaxBlock, workers_, [&](std::size_t begin, std::size_t end, unsigned) {
    poll();
    for (std::size_t i = begin; i < end; ++i) {
      const int v = eligible[i];
      Vec3 step = equilateral_step(v);
      if (!(step.squaredNorm() > 0)) continue;
      // Judged first in the tangent plane, where it costs no evaluation: Newton moves the
      // point by far less than the step (the step squared times the curvature), so a move
      // that gains nothing there gains nothing on the surface.
      if (search) {
        step = searched_step(v, step, keep_cos);
        if (!(step.squaredNorm() > 0)) continue;
      } else if (!(star_shape(v, P(v) + step).mean_ratio < star_shape(v).mean_ratio * (1 - kRelaxMinGain))) {
        continue;
      }
      double shortest = std::numeric_limits<double>::infinity();
      for (int u : vt_[v])
        for (int w : m_.triangles[u])
          if (w != v) shortest = std::min(shortest, (P(w) - P(v)).norm());
      target[i] = P(v) + step;
      reach[i] = shortest;
      moves[i] = 1;
    }
  });
  RelaxMoves out;
  const auto count = static_cast<std::size_t>(std::count(moves.begin(), moves.end(), 1));
  out.vertices.reserve(count);
  out.starts.reserve(count);
  out.options.reserve(count);
  for (std::size_t i = 0; i < eligible.size(); ++i) {
    poll(i);
    if (!moves[i]) continue;
    ProjectionOptions po;
    po.tolerance = 1e-10 * o_.diagonal;
    po.max_step = reach[i];
    po.max_travel = reach[i];
    out.vertices.push_back(eligible[i]);
    out.starts.push_back(target[i]);
    out.options.push_back(po);
  }
  return out;
}

std::vector<ProjectionResult> Improver::project_moves(const RelaxMoves& moves) const {
  const std::vector<Vec3>& starts = moves.starts;
  const std::vector<ProjectionOptions>& opts = moves.options;
  // Each projection is independent of the others (the same point in any batch): a
  // thread-safe field's are shared among threads in blocks; any other field's go in one
  // batch (one call per Newton round: a Python function is called once per batch).
  std::vector<ProjectionResult> landed = polled_vector<ProjectionResult>(starts.size());
  const bool shared = field_.thread_safe();
  detail::parallel_blocks(starts.size(), shared ? kRelaxBlock : starts.size(), shared ? workers_ : 1u,
                          [&](std::size_t begin, std::size_t end, unsigned) {
                            poll();
                            const std::vector<ProjectionResult> part = project_to_surface(
                                field_, std::span(starts).subspan(begin, end - begin),
                                std::span(opts).subspan(begin, end - begin));
                            std::copy(part.begin(), part.end(), landed.begin() + static_cast<std::ptrdiff_t>(begin));
                          });
  return landed;
}

bool Improver::apply_moves(const RelaxMoves& moves, const std::vector<ProjectionResult>& landed, bool search,
                           double keep_cos, std::vector<char>& moved) {
  const std::vector<int>& moving = moves.vertices;
  // The moves are judged in order, each at the positions the moves before it left, and
  // applied. On several threads the intersection test (star_intersects, the costliest
  // check) is left out of that loop: after every chunk of candidates judged, the moves they
  // made are tested on all cores, each at the positions of its turn (intersecting_turn). The
  // first refused there (1 in about 1250 moves kept over the 343-run sweep of kRelaxSweeps, the runs
  // made again included) and the moves after it are taken back, and the judging goes on
  // after it. So the moves kept are those of the loop with the test inside, which one thread
  // runs without a tolerance. With a tolerance, judging a move evaluates the field (its
  // star's distance estimate), and the moves judged twice after a refusal evaluate again:
  // there one thread takes the chunks too, so that the evaluation counts are the same on any
  // number of threads (the mesh is the same either way). That costs one thread about 2 % of
  // its instructions (tanglecube at 1e-3: 3.64G against 3.57G, callgrind), and two threads
  // save about 7 % of the time there.
  bool changed = false;
  // Candidate i's move, applied, or nothing when it is refused.
  const auto judge = [&](std::size_t i, bool test_intersections) -> std::optional<Turn> {
    if (!landed[i].ok() || !(landed[i].gradient.squaredNorm() > 0)) return std::nullopt;
    const int v = moving[i];
    const Vec3 ng = landed[i].gradient.normalized();
    const Vec3& target = landed[i].point;
    if (!(ng.dot(m_.normals[v]) > kMoveNormalCos)) return std::nullopt;
    const StarShape before = star_shape(v);
    const double floor = facing_floor(vt_[v]);
    const Vec3 saved = P(v), saved_n = m_.normals[v];
    m_.positions[v] = target;
    m_.normals[v] = ng;
    const StarShape after = star_shape(v);
    bool ok = after.mean_ratio < before.mean_ratio * (1 - kRelaxMinGain) &&
              after.max_cos <= std::max(before.max_cos, keep_cos);
    for (int u : vt_[v]) ok = ok && faces_surface(m_.triangles[u], floor);
    const double new_dist = ok ? worst_star_distance(v) : 0;
    m_.positions[v] = saved;
    m_.normals[v] = saved_n;
    if (!(ok && may_replace(new_dist, vt_[v]))) return std::nullopt;
    if (test_intersections && star_intersects(v, target)) {
      ++r_.relax_crossings;
      return std::nullopt;
    }
    m_.positions[v] = target;
    m_.normals[v] = ng;
    // Unlike try_move, the crease test is not asked again (3 evaluations): v was not on a
    // crease, and Newton lands it on one piece's zero set, on a crease only by accident.
    moved[v] = 1;
    return Turn{v, saved, saved_n, i};
  };
  const auto keep = [&](const Turn& turn) {
    for (int u : vt_[turn.v]) {
      hash_box(u);
      touch(u);
    }
    ++r_.relaxed;
    if (search) ++r_.relax_searched;
    changed = true;
  };
  if (workers_ <= 1 && !(o_.tolerance > 0)) {
    for (std::size_t i = 0; i < moving.size(); ++i) {
      poll(i);
      if (const std::optional<Turn> turn = judge(i, true)) keep(*turn);
    }
  } else {
    TurnScratch scratch(m_.positions.size(), workers_);
    std::vector<Turn> turns;
    std::size_t chunk = kRelaxBlock;
    for (std::size_t i = 0; i < moving.size();) {
      poll();
      turns.clear();
      for (const std::size_t stop = std::min(moving.size(), i + chunk); i < stop; ++i)
        if (const std::optional<Turn> turn = judge(i, false)) turns.push_back(*turn);
      const std::size_t refused = intersecting_turn(turns, scratch);
      for (std::size_t k = turns.size(); k-- > refused;) {
        m_.positions[turns[k].v] = turns[k].from;
        m_.normals[turns[k].v] = turns[k].from_normal;
        moved[turns[k].v] = 0;
      }
      for (std::size_t k = 0; k < refused; ++k) keep(turns[k]);
      if (refused < turns.size()) {
        ++r_.relax_crossings;
        i = turns[refused].candidate + 1;
      }
      // Where moves are refused, shorter chunks, down to one candidate: the moves judged
      // again after a refusal stay a bounded share of the work (a blob field at 5e-2 with a
      // refusal every few moves: 790 chunks of 4096 made the run three times as long).
      chunk = refused < turns.size() ? std::max<std::size_t>(1, chunk / 4) : std::min(kRelaxChunk, 2 * chunk);
    }
  }
  return changed;
}

}  // namespace cdp::adaptive::repair_detail
