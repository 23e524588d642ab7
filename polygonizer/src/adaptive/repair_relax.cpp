// The relaxation (repair_relax.h).
#include "repair_relax.h"

namespace cdp::adaptive::repair {
namespace {

// relax: the triangles whose longest edge exceeds this times their shortest have their edges
// flipped and their vertices moved (an equilateral triangle is 1; the fronts make 1.22 on
// average where sizes do not change). On the bunny VIS-800 at factor 3 most of the vertices are
// candidates: a smoothing of most of the mesh, though not a re-meshing (flips only, no vertex
// added or removed). Measured mean ratios, bunny VIS-800 at factor 1 / Igea MPU at 2 / horse
// MPU at 1: 1.246 / 1.255 / 1.263 with 1.15; 1.250 / 1.259 / 1.267 with 1.3; 1.0 (every
// vertex) gains under 0.001 more.
constexpr double kRelaxRatio = 1.15;
// Plain sweeps of the relaxation, each flips then moves; where they leave the mesh's mean ratio
// over the aim, the search sweeps below take over. One, because the later ones buy little for
// what they cost. Over a 343-run sweep of the quality bounds (the 9 experiment fields and the 40
// topology-sweep fields, factors 1-5 and tolerances 5e-2-1e-3), against 4:
// - every run within every bound; the same triangle counts but in 25 tolerance runs (up to 8
//   triangles either way: the tolerance's refinement sees other positions);
// - the mean over runs of the mean ratio 1.186 -> 1.208 (the worst 1.2487 -> 1.2499; 43 runs
//   instead of 5 finish with search sweeps);
// - the smallest angle over all runs the same (21.13 degrees); a run's own lower in 181 runs and
//   higher in 58, the mean 31.67 -> 30.87, by up to 11 degrees where it was far above 30 (coarse
//   meshes of few blobs), and 30.01 -> 25.50 on one (blobs37 at 1e-3);
// - 0.76 of the time and of the field evaluations;
// - the mean Phong error of bunny VIS-800, Igea VIS-4004, tanglecube and random blobs at factors
//   3 and 5 0.3-1.3 % higher (tanglecube at 5: 0.4 % lower), what edges 0.3-1.3 % shorter would
//   win back if the error goes as the edge length.
// 2 sweeps: a mean ratio of 1.194 in 0.86 of the time. Instructions in polygonize_adaptive
// (callgrind, one thread, -O2 -g): torus factor 20 3913M -> 2645M, bunny VIS-800 factor 3
// 2030M -> 1571M.
constexpr int kRelaxSweeps = 1;
// At most this many sweeps of the relaxation's search (see relax and searched_step), each made
// only while the mesh's mean edge ratio is over QualityOptions::aim_mean_edge_ratio. The four
// runs of that sweep that four plain sweeps left over 1.25 (bunny VIS-800 at 1e-2,
// Igea MPU at 5e-2 and 1e-2, Igea VIS-4004 at 5e-2: 1.253-1.258; ten plain sweeps reach only
// 1.2545 on Igea MPU at 1e-2) ended at 1.239-1.245 after the first. After one plain sweep, 43 of
// the 343 runs are over 1.25 and all end under it.
constexpr int kRelaxSearchSweeps = 4;
// Stars judged per vertex and search sweep (searched_step): a few dozen flops per triangle of
// the star each, no evaluation. Igea MPU at 1e-2 with the search in all four sweeps, as a
// measure of what the budget buys: 1.234 with 4 stars, 1.230 with 8, 1.229 with 12 or 24.
constexpr int kRelaxSearchStars = 8;
// On several threads (with a tolerance, on any number) the relaxation judges at most this many
// candidates between two tests of their moves for intersections (see relax_sweeps), few enough
// that a move refused there takes back at most this many judged after it. The chunks start at
// kRelaxBlock candidates and double up to this while no move is refused.
constexpr std::size_t kRelaxChunk = 4096;
// Moves per block of those tests: a test costs a microsecond or two, so that the first chunk's
// moves (at most kRelaxBlock) already spread over several threads.
constexpr std::size_t kTurnBlock = 64;

// A star's mean edge ratio and the cosine of its smallest angle. Each triangle's smallest
// angle faces its shortest edge; its cosine comes from the squared edge lengths by the law of
// cosines, without an arc tangent (most of the relaxation's own time went to them).
struct StarShape {
  double mean_ratio = 0, max_cos = -1;
};
// ... with v at `at` (read only: the relaxation's targets are judged on several threads).
StarShape star_shape(const RepairContext& ctx, int v, const Vec3& at) {
  const auto pos = [&](int w) -> const Vec3& { return w == v ? at : ctx.P(w); };
  StarShape s;
  for (int u : ctx.vt_[v]) {
    const Tri& t = ctx.mesh_.triangles[u];
    const Vec3 &a = pos(t[0]), &b = pos(t[1]), &c = pos(t[2]);
    const double ab = (b - a).squaredNorm(), bc = (c - b).squaredNorm(), ca = (a - c).squaredNorm();
    // In order by minima and maxima: the same values as std::sort gives, without its calls (the
    // relaxation's search takes star shapes by the hundred thousand).
    const std::array<double, 3> l{std::min({ab, bc, ca}), std::max(std::min(ab, bc), std::min(std::max(ab, bc), ca)),
                                  std::max({ab, bc, ca})};
    const double xy = l[1] * l[2];
    s.mean_ratio += l[0] > 0 ? std::sqrt(l[2] / l[0]) : std::numeric_limits<double>::infinity();
    s.max_cos = std::max(s.max_cos, xy > 0 ? std::min(1.0, (l[1] + l[2] - l[0]) / (2 * std::sqrt(xy))) : 1.0);
  }
  s.mean_ratio /= std::max<std::size_t>(1, ctx.vt_[v].size());
  return s;
}
StarShape star_shape(const RepairContext& ctx, int v) { return star_shape(ctx, v, ctx.P(v)); }

// Where in v's tangent plane v's star has the lowest mean edge ratio, as a step from v: a
// compass search (the four directions of a tangent frame, the stride halved where none of
// them gains) from the better of v and v + `first` (the equilateral step), at most
// kRelaxSearchStars stars judged, none whose smallest angle would fall under both the star's
// own and kRelaxKeepDegrees (cosine `keep_cos`). The equilateral step aims every triangle at
// its outer edge at once, which where the edges around v differ in length (a graded mesh) is
// not where their mean ratio is lowest; most of the vertices it leaves stretched gain nothing
// from it, and a step the search finds for them does. Zero when no star judged gains
// kRelaxMinGain. Read only: judged on several threads.
Vec3 searched_step(const RepairContext& ctx, int v, const Vec3& first, double keep_cos) {
  const Vec3 x = ctx.P(v), n = ctx.mesh_.normals[v];
  const StarShape start = star_shape(ctx, v);
  const double cos_cap = std::max(start.max_cos, keep_cos);
  const auto score = [&](const Vec3& step) {
    const StarShape s = star_shape(ctx, v, x + step);
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

// A move of the relaxation: the vertex, its position and normal before, and its candidate
// (index among the sweep's projected moves).
struct Turn {
  int v;
  Vec3 from, from_normal;
  std::size_t candidate;
};
// intersecting_turn's arrays, made once a sweep (the mesh's connectivity does not change
// while the relaxation moves vertices) and left clean after each call.
struct TurnScratch {
  static constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  TurnScratch(std::size_t vertices, unsigned workers)
      : turn_of(vertices, kNone), stamps(std::max(workers, 1u)), ids(stamps.size(), 0), stars(stamps.size()) {}
  std::vector<std::size_t> turn_of;  // by vertex: its turn in the call, or kNone
  std::vector<std::vector<std::uint32_t>> stamps;  // by worker, as star_hits wants them
  std::vector<std::uint32_t> ids;
  std::vector<std::vector<RepairContext::StarTriangle>> stars;
  std::vector<char> hit;
};
// The first of `turns` (moves made in this order, all applied now) whose star at the
// positions of its turn (the moves before it made, those after it not) intersects a triangle
// outside it, as star_intersects would have found then; turns.size() if none. First every
// triangle the turns changed is stored in the hash with a box over its corners before and
// after (which holds it at any turn; most already are, see hash_cover); then the turns are
// tested on all cores, the hash only read.
std::size_t intersecting_turn(RepairContext& ctx, const std::vector<Turn>& turns, TurnScratch& scratch) {
  if (turns.empty()) return 0;
  constexpr std::size_t kNone = TurnScratch::kNone;
  for (std::size_t k = 0; k < turns.size(); ++k) scratch.turn_of[static_cast<std::size_t>(turns[k].v)] = k;
  for (const Turn& turn : turns)
    for (int u : ctx.vt_[turn.v]) {
      Vec3 lo = ctx.P(ctx.mesh_.triangles[u][0]), hi = lo;
      for (int w : ctx.mesh_.triangles[u]) {
        lo = lo.cwiseMin(ctx.P(w)), hi = hi.cwiseMax(ctx.P(w));
        if (const std::size_t j = scratch.turn_of[static_cast<std::size_t>(w)]; j != kNone)
          lo = lo.cwiseMin(turns[j].from), hi = hi.cwiseMax(turns[j].from);
      }
      ctx.hash_cover(u, lo, hi);
    }
  scratch.hit.assign(turns.size(), 0);
  detail::parallel_blocks(turns.size(), kTurnBlock, ctx.workers_, [&](std::size_t begin, std::size_t end, unsigned w) {
    std::vector<std::uint32_t>& stamp = scratch.stamps[w];
    if (stamp.empty()) stamp.assign(ctx.mesh_.triangles.size(), 0);
    std::uint32_t& id = scratch.ids[w];  // a worker's stamps outlive its blocks and calls
    for (std::size_t k = begin; k < end; ++k) {
      if (id == std::numeric_limits<std::uint32_t>::max()) std::fill(stamp.begin(), stamp.end(), 0), id = 0;
      const auto at = [&](int q) -> const Vec3& {
        const std::size_t j = scratch.turn_of[static_cast<std::size_t>(q)];
        return j != kNone && j > k ? turns[j].from : ctx.P(q);
      };
      scratch.hit[k] = ctx.star_hits(turns[k].v, ctx.P(turns[k].v), at, stamp.data(), ++id, scratch.stars[w]);
    }
  });
  for (const Turn& turn : turns) scratch.turn_of[static_cast<std::size_t>(turn.v)] = kNone;
  return static_cast<std::size_t>(std::find(scratch.hit.begin(), scratch.hit.end(), 1) - scratch.hit.begin());
}

// relax_sweeps' steps: the flips of stretched triangles, the vertices to move, their targets in
// the tangent plane, projected onto the surface, and the moves judged and applied in order
// (true when one was).
struct RelaxMoves {
  std::vector<int> vertices;
  std::vector<Vec3> starts;
  std::vector<ProjectionOptions> options;
};
// First the flips (try_flip's for_ratio): each stretched triangle's edges, longest first.
void flip_stretched(RepairContext& ctx) {
  ctx.flipped_.assign(ctx.mesh_.positions.size(), 0);
  if (ctx.field_.costly_calls()) {
    std::vector<int> stretched;
    for (int t = 0; t < ctx.tri_count(); ++t) {
      ctx.poll(static_cast<std::size_t>(t));
      if (ctx.alive_[t] && ctx.tri_ratio(ctx.mesh_.triangles[t]) > kRelaxRatio) stretched.push_back(t);
    }
    ctx.prefetch_flip_samples(stretched);
  }
  for (int t = 0; t < ctx.tri_count(); ++t) {
    ctx.poll(static_cast<std::size_t>(t));
    if (!ctx.alive_[t] || !(ctx.tri_ratio(ctx.mesh_.triangles[t]) > kRelaxRatio)) continue;
    const Tri T = ctx.mesh_.triangles[t];
    int k = 0;
    double longest = 0;
    for (int i = 0; i < 3; ++i) {
      const double l = (ctx.P(T[(i + 1) % 3]) - ctx.P(T[i])).squaredNorm();
      if (l > longest) longest = l, k = i;
    }
    for (int i = 0; i < 3; ++i)
      if (ctx.try_flip(t, (k + i) % 3, true)) break;
  }
  ctx.forget_flip_samples();
}

// The corners of stretched triangles; after the first sweep (`moved` given) only those moved in
// the sweep before, flipped in this one, or with a moved vertex in their star.
std::vector<char> mark_stretched(const RepairContext& ctx, const std::vector<char>* moved_before) {
  std::vector<char> mark(ctx.mesh_.positions.size(), 0);
  for (int t = 0; t < ctx.tri_count(); ++t) {
    ctx.poll(static_cast<std::size_t>(t));
    if (!ctx.alive_[t] || !(ctx.tri_ratio(ctx.mesh_.triangles[t]) > kRelaxRatio)) continue;
    const Tri& x = ctx.mesh_.triangles[t];
    for (int v : x) mark[v] = 1;
  }
  if (moved_before) {
    const std::vector<char>& moved = *moved_before;
    for (int v = 0; v < static_cast<int>(mark.size()); ++v) {
      if (!mark[v] || moved[v] || ctx.flipped_[v]) continue;
      bool star_moved = false;
      for (int u : ctx.vt_[v])
        for (int w : ctx.mesh_.triangles[u]) star_moved = star_moved || moved[w];
      mark[v] = star_moved;
    }
  }
  return mark;
}

RelaxMoves relax_targets(RepairContext& ctx, const std::vector<char>& mark, bool search, double keep_cos) {
  // The marked vertices off creases (on_crease may evaluate and caches: one thread), then
  // their targets, each judged on its own (read only: on several threads, one slot each).
  // Reserved (nothing touched) so that no push_back copies megabytes between two polls.
  std::vector<int> eligible;
  eligible.reserve(mark.size());
  for (int v = 0; v < static_cast<int>(mark.size()); ++v) {
    ctx.poll(static_cast<std::size_t>(v));
    if (mark[v] && ctx.vt_[v].size() >= 3 && !ctx.fixed(v)) eligible.push_back(v);
  }
  ctx.probe_creases(eligible);
  std::erase_if(eligible, [&ctx](int v) { return ctx.on_crease(v); });
  std::vector<Vec3> target = ctx.polled_vector<Vec3>(eligible.size(), Vec3::Zero());
  std::vector<double> reach = ctx.polled_vector<double>(eligible.size(), 0);
  std::vector<char> moves = ctx.polled_vector<char>(eligible.size(), 0);
  detail::parallel_blocks(eligible.size(), kRepairBlock, ctx.workers_, [&](std::size_t begin, std::size_t end, unsigned) {
    ctx.poll();
    for (std::size_t i = begin; i < end; ++i) {
      const int v = eligible[i];
      Vec3 step = ctx.equilateral_step(v);
      if (!(step.squaredNorm() > 0)) continue;
      // Judged first in the tangent plane, where it costs no evaluation: Newton moves the
      // point by far less than the step (the step squared times the curvature), so a move
      // that gains nothing there gains nothing on the surface.
      if (search) {
        step = searched_step(ctx, v, step, keep_cos);
        if (!(step.squaredNorm() > 0)) continue;
      } else if (!(star_shape(ctx, v, ctx.P(v) + step).mean_ratio < star_shape(ctx, v).mean_ratio * (1 - kRelaxMinGain))) {
        continue;
      }
      double shortest = std::numeric_limits<double>::infinity();
      for (int u : ctx.vt_[v])
        for (int w : ctx.mesh_.triangles[u])
          if (w != v) shortest = std::min(shortest, (ctx.P(w) - ctx.P(v)).norm());
      target[i] = ctx.P(v) + step;
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
    ctx.poll(i);
    if (!moves[i]) continue;
    ProjectionOptions po;
    po.tolerance = 1e-10 * ctx.options_.diagonal;
    po.max_step = reach[i];
    po.max_travel = reach[i];
    out.vertices.push_back(eligible[i]);
    out.starts.push_back(target[i]);
    out.options.push_back(po);
  }
  return out;
}

std::vector<ProjectionResult> project_moves(const RepairContext& ctx, const RelaxMoves& moves) {
  const std::vector<Vec3>& starts = moves.starts;
  const std::vector<ProjectionOptions>& opts = moves.options;
  // Each projection is independent of the others (the same point in any batch): a
  // thread-safe field's are shared among threads in blocks; any other field's go in one
  // batch (one call per Newton round: a Python function is called once per batch).
  std::vector<ProjectionResult> landed = ctx.polled_vector<ProjectionResult>(starts.size());
  const bool shared = ctx.field_.thread_safe();
  detail::parallel_blocks(starts.size(), shared ? kRepairBlock : starts.size(), shared ? ctx.workers_ : 1u,
                          [&](std::size_t begin, std::size_t end, unsigned) {
                            ctx.poll();
                            const std::vector<ProjectionResult> part = project_to_surface(
                                ctx.field_, std::span(starts).subspan(begin, end - begin),
                                std::span(opts).subspan(begin, end - begin));
                            std::copy(part.begin(), part.end(), landed.begin() + static_cast<std::ptrdiff_t>(begin));
                          });
  return landed;
}

// The points whose distances judging moves [begin, end) measures (each star triangle's edge
// midpoints and centroid, its centre where it is and at its target: may_replace,
// worst_star_distance), at the positions of now: prefetch_distances. A move judged after a
// neighbour's asks for its own where they differ. Those known from the chunks before are kept
// (a chunk judged again after a refusal asks for none) up to kKnownDistances.
constexpr std::size_t kKnownDistances = std::size_t{1} << 18;
void prefetch_stars(RepairContext& ctx, const RelaxMoves& moves, const std::vector<ProjectionResult>& landed,
                    std::size_t begin, std::size_t end) {
  if (ctx.known_distances_.size() > kKnownDistances) ctx.forget_distances();
  std::vector<Vec3> points;
  for (std::size_t i = begin; i < end; ++i) {
    const int v = moves.vertices[i];
    // judge's first tests, which need no field.
    if (!landed[i].ok() || !(landed[i].gradient.squaredNorm() > 0) ||
        !(landed[i].gradient.normalized().dot(ctx.mesh_.normals[v]) > kMoveNormalCos))
      continue;
    for (const int u : ctx.vt_[v]) {
      const Tri& t = ctx.mesh_.triangles[u];
      // Before the move (may_replace) and after it, as midpoint_sample and estimate_from write
      // them, for the same bits.
      std::array<Vec3, 3> p{ctx.P(t[0]), ctx.P(t[1]), ctx.P(t[2])};
      for (int at = 0; at < 2; ++at) {
        for (int k = 0; k < 3; ++k) points.push_back(0.5 * (p[k] + p[(k + 1) % 3]));
        points.push_back((p[0] + p[1] + p[2]) / 3);
        for (int k = 0; k < 3; ++k)
          if (t[k] == v) p[k] = landed[i].point;
      }
    }
  }
  ctx.prefetch_distances(points);
}

bool apply_moves(RepairContext& ctx, const RelaxMoves& moves, const std::vector<ProjectionResult>& landed, bool search,
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
    if (!(ng.dot(ctx.mesh_.normals[v]) > kMoveNormalCos)) return std::nullopt;
    const StarShape before = star_shape(ctx, v);
    const double floor = ctx.facing_floor(ctx.vt_[v]);
    const Vec3 saved = ctx.P(v), saved_n = ctx.mesh_.normals[v];
    ctx.mesh_.positions[v] = target;
    ctx.mesh_.normals[v] = ng;
    const StarShape after = star_shape(ctx, v);
    bool ok = after.mean_ratio < before.mean_ratio * (1 - kRelaxMinGain) &&
              after.max_cos <= std::max(before.max_cos, keep_cos);
    for (int u : ctx.vt_[v]) ok = ok && ctx.faces_surface(ctx.mesh_.triangles[u], floor);
    const double new_dist = ok ? ctx.worst_star_distance(v) : 0;
    ctx.mesh_.positions[v] = saved;
    ctx.mesh_.normals[v] = saved_n;
    if (!(ok && ctx.may_replace(new_dist, ctx.vt_[v]))) return std::nullopt;
    if (test_intersections && ctx.star_intersects(v, target)) {
      ++ctx.report_.relax_crossings;
      return std::nullopt;
    }
    ctx.mesh_.positions[v] = target;
    ctx.mesh_.normals[v] = ng;
    // Unlike try_move, the crease test is not asked again (3 evaluations): v was not on a
    // crease, and Newton lands it on one piece's zero set, on a crease only by accident.
    moved[v] = 1;
    return Turn{v, saved, saved_n, i};
  };
  const auto keep = [&](const Turn& turn) {
    for (int u : ctx.vt_[turn.v]) {
      ctx.hash_box(u);
      ctx.touch(u);
    }
    ++ctx.report_.relaxed;
    if (search) ++ctx.report_.relax_searched;
    changed = true;
  };
  if (ctx.workers_ <= 1 && !(ctx.options_.tolerance > 0)) {
    for (std::size_t i = 0; i < moving.size(); ++i) {
      ctx.poll(i);
      if (const std::optional<Turn> turn = judge(i, true)) keep(*turn);
    }
  } else {
    TurnScratch scratch(ctx.mesh_.positions.size(), ctx.workers_);
    std::vector<Turn> turns;
    std::size_t chunk = kRepairBlock;
    const bool costly_tolerance = ctx.options_.tolerance > 0 && ctx.field_.costly_calls();
    for (std::size_t i = 0; i < moving.size();) {
      ctx.poll();
      turns.clear();
      if (costly_tolerance) prefetch_stars(ctx, moves, landed, i, std::min(moving.size(), i + chunk));
      // Polled within the chunk too: 4096 judgings, each measuring two stars (and, with a
      // tolerance, evaluating the field), ran 0.1-0.14 s at 2*10^6 triangles on a loaded machine.
      for (const std::size_t stop = std::min(moving.size(), i + chunk); i < stop; ++i) {
        ctx.poll(i);
        if (const std::optional<Turn> turn = judge(i, false)) turns.push_back(*turn);
      }
      const std::size_t refused = intersecting_turn(ctx, turns, scratch);
      for (std::size_t k = turns.size(); k-- > refused;) {
        ctx.mesh_.positions[turns[k].v] = turns[k].from;
        ctx.mesh_.normals[turns[k].v] = turns[k].from_normal;
        moved[turns[k].v] = 0;
      }
      for (std::size_t k = 0; k < refused; ++k) keep(turns[k]);
      if (refused < turns.size()) {
        ++ctx.report_.relax_crossings;
        i = turns[refused].candidate + 1;
      }
      // Where moves are refused, shorter chunks, down to one candidate: the moves judged
      // again after a refusal stay a bounded share of the work (a blob field at 5e-2 with a
      // refusal every few moves: 790 chunks of 4096 made the run three times as long).
      chunk = refused < turns.size() ? std::max<std::size_t>(1, chunk / 4) : std::min(kRelaxChunk, 2 * chunk);
    }
    ctx.forget_distances();
  }
  return changed;
}

// `sweeps` sweeps of the relaxation (see relax), with searched_step's moves where `search`;
// those stop once the mesh's mean edge ratio is at or under the aim.
void relax_sweeps(RepairContext& ctx, int sweeps, bool search) {
  const double keep_cos = std::cos(kRelaxKeepDegrees * std::numbers::pi / 180);
  // Vertices moved in the previous sweep: a later sweep moves only those, the vertices whose
  // star holds one, and the corners of this sweep's flips (any other would compute the same
  // target and be refused again, but for the rare move refused for crossing a triangle beyond
  // its star that has moved since).
  std::vector<char> moved;
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    if (search && sweep > 0 && mean_edge_ratio(ctx) <= ctx.options_.aim_mean_edge_ratio) break;
    if (search) ++ctx.report_.relax_search_sweeps;
    flip_stretched(ctx);
    const std::vector<char> mark = mark_stretched(ctx, sweep > 0 ? &moved : nullptr);
    moved.assign(ctx.mesh_.positions.size(), 0);
    const RelaxMoves moves = relax_targets(ctx, mark, search, keep_cos);
    if (moves.vertices.empty()) break;
    if (!apply_moves(ctx, moves, project_moves(ctx, moves), search, keep_cos, moved)) break;
  }
}

}  // namespace

double mean_edge_ratio(const RepairContext& ctx) {
  double sum = 0;
  std::size_t n = 0;
  for (int t = 0; t < ctx.tri_count(); ++t)
    if (ctx.alive_[t]) sum += ctx.tri_ratio(ctx.mesh_.triangles[t]), ++n;
  return n ? sum / n : 0;
}

void relax(RepairContext& ctx) {
  relax_sweeps(ctx, kRelaxSweeps, false);
  if (ctx.options_.aim_mean_edge_ratio > 0 && mean_edge_ratio(ctx) > ctx.options_.aim_mean_edge_ratio)
    relax_sweeps(ctx, kRelaxSearchSweeps, true);
}

}  // namespace cdp::adaptive::repair
