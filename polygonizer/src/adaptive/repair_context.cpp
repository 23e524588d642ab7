// The context the repair's algorithms share (repair_context.h): geometry, distance estimates,
// crease vertices, adjacency, and the intersection tests against the triangles nearby.
#include "repair_context.h"

namespace cdp::adaptive::repair {

double RepairContext::cell_size(const Mesh& m) {
  // About two typical edges, so that a query box around a new triangle touches a few cells.
  std::vector<double> lengths;
  const std::size_t stride = std::max<std::size_t>(1, m.triangles.size() / 256);
  for (std::size_t t = 0; t < m.triangles.size(); t += stride)
    lengths.push_back((m.positions[m.triangles[t][0]] - m.positions[m.triangles[t][1]]).norm());
  if (lengths.empty()) return 1;
  std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
  return std::max(2 * lengths[lengths.size() / 2], 1e-12);
}

RepairContext::Mid RepairContext::midpoint_distance(int x, int y, MidpointMemo* memo) const {
  const std::pair<int, int> key = std::minmax(x, y);
  if (memo && memo->table)
    if (const std::optional<std::size_t> i = memo->table->find(x, y)) return memo->table->d[*i];
  if (memo)
    for (const auto& [k, d] : memo->known)
      if (k == key) return d;
  const Mid d = midpoint_sample(x, y);
  if (memo) memo->known.push_back({key, d});
  return d;
}

RepairContext::Mid RepairContext::midpoint_sample(int x, int y) const {
  if (predict_)
    if (const std::optional<Mid> m = predicted_midpoint(x, y)) return *m;
  return {signed_distance(0.5 * (P(x) + P(y))), -1};
}

void RepairContext::signed_distances(const std::vector<Vec3>& ps, std::vector<double>& out) const {
  out.resize(ps.size());
  std::vector<double> f;
  std::vector<Vec3> g;
  for (std::size_t begin = 0; begin < ps.size(); begin += kDistanceBatch) {
    poll();
    const std::size_t n = std::min(kDistanceBatch, ps.size() - begin);
    f.resize(n), g.resize(n);
    field_.values_gradients(ps.data() + begin, f.data(), g.data(), n);
    for (std::size_t i = 0; i < n; ++i) out[begin + i] = signed_distance(f[i], g[i]);
  }
}

double RepairContext::estimate_distance(const Tri& t, int slot, MidpointMemo* memo, const Mid* centroid) const {
  if (static_cast<std::size_t>(slot) >= estimates_.size()) estimates_.resize(static_cast<std::size_t>(slot) + 1);
  EstimateEntry& e = estimates_[static_cast<std::size_t>(slot)];
  const std::array<bool, 3> kept = kept_corners(e, t);
  if (kept[0] && kept[1] && kept[2]) return e.d;
  const std::array<Vec3, 3> p{P(t[0]), P(t[1]), P(t[2])};
  std::array<Mid, 3> mid;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (kept[i] && kept[j]) {
      mid[i] = e.mid[i];
      if (memo) memo->known.push_back({std::minmax(t[i], t[j]), mid[i]});
    } else {
      mid[i] = midpoint_distance(t[i], t[j], memo);
    }
  }
  e = {t, p, mid, estimate_from(t, mid, centroid)};
  return e.d;
}

double RepairContext::estimate_from(const Tri& t, const std::array<Mid, 3>& mid, const Mid* centroid) const {
  double margin = 0;
  for (const Mid& m : mid) margin = std::max(margin, m.u);
  std::optional<Mid> c = centroid ? std::optional<Mid>(*centroid) : predicted_centroid(t, mid);
  if (!c) c = Mid{signed_distance((P(t[0]) + P(t[1]) + P(t[2])) / 3), -1};
  // A midpoint off by u moves the quadratic through them by up to 4/3 u (at the centroid).
  return estimate_from_samples(mid[0].d, mid[1].d, mid[2].d, c->d) + 4.0 / 3.0 * margin + std::max(c->u, 0.0);
}

const RepairContext::Jet& RepairContext::jet(int v) const {
  Jet& j = jets_[static_cast<std::size_t>(v)];
  const Vec3& p = P(v);
  if (j.p == p) return j;
  if (spare_v_ == v && spare_.p == p) {
    std::swap(j, spare_);
    return j;
  }
  Jet fresh;
  fresh.f = field_.gradient_hessian(p, fresh.g, fresh.h);
  fresh.p = p;
  spare_ = std::move(j), spare_v_ = v;
  j = std::move(fresh);
  return j;
}

void RepairContext::fill_jets(const std::vector<int>& corners) const {
  reserve_jets();
  // Each vertex not kept once, in the order met, claimed by its position (no sort: this ran once
  // a refinement round over three corners a triangle).
  std::vector<int> vs;
  vs.reserve(corners.size());  // so that no push_back throws after a claim
  for (const int v : corners) {
    Jet& j = jets_[static_cast<std::size_t>(v)];
    if (j.p == P(v)) continue;
    j.p = P(v);
    vs.push_back(v);
  }
  try {
    const bool shared = field_.thread_safe();
    detail::parallel_blocks(vs.size(), shared ? kRepairBlock : kDistanceBatch, shared ? workers_ : 1u,
                            [&](std::size_t begin, std::size_t end, unsigned) {
                              poll();
                              const std::size_t n = end - begin;
                              std::vector<Vec3> points(n), gradients(n);
                              std::vector<double> values(n);
                              std::vector<Mat3> hessians(n);
                              for (std::size_t i = 0; i < n; ++i) points[i] = P(vs[begin + i]);
                              field_.gradients_hessians(points.data(), values.data(), gradients.data(),
                                                        hessians.data(), n);
                              for (std::size_t i = 0; i < n; ++i)
                                jets_[static_cast<std::size_t>(vs[begin + i])] = {points[i], values[i], gradients[i],
                                                                                   hessians[i]};
                            });
  } catch (...) {
    for (const int v : vs) jets_[static_cast<std::size_t>(v)] = Jet{};  // claimed, not evaluated
    throw;
  }
}

std::optional<RepairContext::Mid> RepairContext::predicted_midpoint(int x, int y) const {
  reserve_jets();
  const Jet& a = jet(x);
  const Jet& b = jet(y);
  const Vec3 e = b.p - a.p, h = 0.5 * e;
  // A: the mean of the two ends' Taylor expansions; H: the Hermite cubic of the ends' values and
  // slopes along the edge. Both are exact for cubics; (A + 3H) / 4 for quartics (kPredictShare).
  const double from_a = a.f + a.g.dot(h) + 0.5 * h.dot(a.h * h);
  const double from_b = b.f - b.g.dot(h) + 0.5 * h.dot(b.h * h);
  const double A = 0.5 * (from_a + from_b);
  const double H = 0.5 * (a.f + b.f) + (a.g - b.g).dot(e) / 8;
  // The gradient's Hermite cubic at the midpoint (exact for quartics, the same bits with the
  // ends swapped, as A and H are). Its error moves the distance by a share of the distance, far
  // under |A - H| (across the seam of the repair tests, 3e-6 where the tolerance is 5e-3).
  const Vec3 g = 0.5 * (a.g + b.g) + 0.25 * ((a.h - b.h) * h);
  const double l = g.norm();
  if (!(l > 0)) return std::nullopt;
  const Mid m{0.25 * (A + 3 * H) / l, std::abs(A - H) / l};
  if (!std::isfinite(m.d) || !(m.u <= kPredictShare * options_.tolerance)) return std::nullopt;
  return m;
}

std::optional<RepairContext::Mid> RepairContext::predicted_centroid(const Tri& t, const std::array<Mid, 3>& mid) const {
  // Only where the three midpoints were predicted: an edge across a seam or a crease is not, and
  // a seam that enters a triangle crosses two of its edges.
  double edges = 0;
  for (const Mid& m : mid) {
    if (!(m.u >= 0)) return std::nullopt;
    edges = std::max(edges, m.u);
  }
  reserve_jets();
  const std::array<const Jet*, 3> j{&jet(t[0]), &jet(t[1]), &jet(t[2])};
  const Vec3 c = (j[0]->p + j[1]->p + j[2]->p) / 3;
  // Each corner's Taylor expansion to c with its third-order term estimated from the Hessians
  // (the third derivative along h = c - a_i is about mean(H) - H_i): each is then exact for
  // cubics. Their bound: the largest of their spread, that term's mean (the difference from the
  // second-order prediction) and twice the edges' bound `edges` (for the fourth-order remainder,
  // alike at the three corners, which the spread misses: on the unit sphere of 1,280 triangles
  // the spread alone was half the error, the edges' bound alone 0.99 of it at worst). All are far
  // larger where a seam, a crease or a feature lies inside.
  const Mat3 mean_h = (j[0]->h + j[1]->h + j[2]->h) / 3;
  std::array<double, 3> f;
  double third = 0;
  Vec3 g = Vec3::Zero();
  for (int i = 0; i < 3; ++i) {
    const Jet& k = *j[i];
    const Vec3 h = c - k.p;
    const Vec3 hh = k.h * h, mh = mean_h * h;
    const double t3 = (h.dot(mh) - h.dot(hh)) / 6;
    f[i] = k.f + k.g.dot(h) + 0.5 * h.dot(hh) + t3;
    third += t3;
    g += k.g + 0.5 * (hh + mh);  // the gradient's expansion, exact for cubics likewise
  }
  const double l = (g / 3).norm();
  if (!(l > 0)) return std::nullopt;
  const auto [lo, hi] = std::minmax({f[0], f[1], f[2]});
  const Mid m{(f[0] + f[1] + f[2]) / 3 / l, std::max((hi - lo) / l, std::max(std::abs(third) / 3 / l, 2 * edges))};
  if (!std::isfinite(m.d) || !(m.u <= kPredictShare * options_.tolerance)) return std::nullopt;
  return m;
}

double RepairContext::estimate_from_samples(double mab, double mbc, double mca, double centroid) {
  if (!std::isfinite(mab + mbc + mca + centroid)) return std::numeric_limits<double>::infinity();
  const double predicted = std::abs(4.0 / 9.0 * (mab + mbc + mca));
  const double scale = predicted > 0 ? std::max(1.0, std::abs(centroid) / predicted) : 1.0;
  // quadratic_max is at least every midpoint's |m| (its edges), and scale at least 1.
  return std::max(quadratic_max(mab, mbc, mca) * scale, std::abs(centroid));
}

double RepairContext::quadratic_max(double x, double y, double z) {
  // q = 4 (x a b + y b c + z c a) over a + b + c = 1, a, b, c >= 0 is 0 at the corners and
  // 4 x a b on the edge c = 0, at most |x| there (at its midpoint): so the edges give the
  // largest of |x|, |y|, |z|. Inside, q's one critical point (where the quadratic is not
  // degenerate, D != 0) is (a, b, c) = (y (x - y + z), z (x + y - z), x (y + z - x)) / D with
  // D = 2 (x y + y z + z x) - x^2 - y^2 - z^2, and q = 4 x y z / D there. A saddle's value lies
  // between q's extremes, so taking it too changes nothing. Where rounding makes D nearly 0 and
  // the point inside, the value is held to the bound |q| <= 4 max|m| (a b + b c + c a) <= 4/3 max|m|.
  const double edges = std::max({std::abs(x), std::abs(y), std::abs(z)});
  const double d = 2 * (x * y + y * z + z * x) - (x * x + y * y + z * z);
  if (!(d != 0)) return edges;
  const double a = y * (x - y + z) / d, b = z * (x + y - z) / d, c = x * (y + z - x) / d;
  if (!(a >= 0 && b >= 0 && c >= 0)) return edges;
  return std::max(edges, std::min(std::abs(4 * x * y * z / d), 4.0 / 3.0 * edges));
}

double RepairContext::sampled_distance(const Tri& t, double fallback, ProjectionResult* worst_at) const {
  constexpr int kDenseGrid = 6;
  const std::array<Vec3, 3> p{P(t[0]), P(t[1]), P(t[2])};
  ProjectionOptions po;
  po.tolerance = 1e-10 * options_.diagonal;
  po.max_travel = std::sqrt(std::max({(p[1] - p[0]).squaredNorm(), (p[2] - p[1]).squaredNorm(), (p[0] - p[2]).squaredNorm()}));
  double worst = 0;
  // A field whose calls cost more than their points (Field::costly_calls) projects the grid's
  // points together, a batched call a Newton round (BatchProjector: the same points where its
  // batched calls give the same numbers as single ones): the random blobs as a numpy function at
  // tolerance 1e-3 spent a third of their run here, one point a call.
  std::vector<Vec3> grid;
  grid.reserve((kDenseGrid + 1) * (kDenseGrid + 2) / 2);
  for (int i = 0; i <= kDenseGrid; ++i)
    for (int j = 0; i + j <= kDenseGrid; ++j) {
      const double a = double(i) / kDenseGrid, b = double(j) / kDenseGrid;
      grid.push_back(a * p[0] + b * p[1] + (1 - a - b) * p[2]);
    }
  std::span<const ProjectionResult> batched;
  BatchProjector projector;
  if (field_.costly_calls()) {
    const std::vector<ProjectionOptions> options(grid.size(), po);
    batched = projector.project(field_, grid, options);
  }
  for (std::size_t k = 0; k < grid.size(); ++k) {
    const Vec3& x = grid[k];
    const ProjectionResult r = batched.empty() ? project_to_surface(field_, x, po) : batched[k];
    if (!r.ok()) return fallback;
    const double d = (r.point - x).norm();
    if (d > worst) {
      worst = d;
      if (worst_at) *worst_at = r;
    }
  }
  return worst;
}

double RepairContext::worst_distance(const std::vector<Tri>& ts) const {
  double worst = 0;
  if (options_.tolerance > 0) {
    MidpointMemo memo;
    for (const Tri& t : ts) worst = std::max(worst, estimate_distance(t, &memo));
  }
  return worst;
}

double RepairContext::worst_star_distance(int v) const {
  double worst = 0;
  if (options_.tolerance > 0) {
    MidpointMemo memo;
    for (int u : vt_[v]) worst = std::max(worst, estimate_distance(mesh_.triangles[u], u, &memo));
  }
  return worst;
}

bool RepairContext::may_replace(double worst_new, const std::vector<int>& removed) const {
  if (!(options_.tolerance > 0) || worst_new <= kToleranceMargin * options_.tolerance) return true;
  double worst_old = 0;
  MidpointMemo memo;
  for (int t : removed) worst_old = std::max(worst_old, estimate_distance(mesh_.triangles[t], t, &memo));
  return worst_new <= worst_old;
}

bool RepairContext::on_crease(int v) {
  if (smooth_) return false;  // no crease to find (Field::smooth): no probes
  if (crease_[v] >= 0) return crease_[v];
  const Vec3& x = P(v);
  Vec3 g0;
  field_.value_gradient(x, g0);
  bool crease = !(g0.squaredNorm() > 0) || !(g0.normalized().dot(mesh_.normals[v]) > kCreaseNormalCosine);
  if (!crease) {
    const std::array<Vec3, 2> around = CreaseProbe(options_.diagonal).points(x, g0.normalized());
    const Vec3 g1 = field_.gradient(around[1]), g2 = field_.gradient(around[0]);
    crease = !(g1.squaredNorm() > 0 && g2.squaredNorm() > 0) ||
             !(g1.normalized().dot(g2.normalized()) > kCreaseCosine);
  }
  crease_[v] = crease;
  if (crease) ++report_.crease_vertices;
  return crease;
}

void RepairContext::probe_creases(const std::vector<int>& vs) {
  if (smooth_) return;
  std::vector<int> todo;
  for (const int v : vs)
    if (crease_[v] < 0) crease_[v] = 2, todo.push_back(v);  // 2: being probed (vs may repeat one)
  // In chunks, polled between them: a batch of a Python field holds 7 points a probe.
  for (std::size_t begin = 0; begin < todo.size(); begin += kCreaseProbeBatch) {
    const std::vector<int> chunk(todo.begin() + static_cast<std::ptrdiff_t>(begin),
                                 todo.begin() + static_cast<std::ptrdiff_t>(std::min(todo.size(), begin + kCreaseProbeBatch)));
    try {
      poll();
      probe_chunk(chunk);
    } catch (...) {
      for (const int v : todo)
        if (crease_[v] == 2) crease_[v] = -1;  // not probed after all
      throw;
    }
  }
}

void RepairContext::prefetch_distances(const std::vector<Vec3>& points) {
  // Each point once: the first of equal bits (a star's edges are shared by two of its triangles).
  std::vector<Vec3> todo;
  todo.reserve(points.size());
  {
    std::unordered_map<PointBits, char, PointBitsHash> seen;
    for (const Vec3& p : points)
      if (!known_distances_.contains(point_bits(p)) && seen.emplace(point_bits(p), 0).second) todo.push_back(p);
  }
  // Stored only once measured: a call that throws leaves nothing behind.
  std::vector<double> d;
  signed_distances(todo, d);
  for (std::size_t i = 0; i < todo.size(); ++i) known_distances_.emplace(point_bits(todo[i]), d[i]);
}

void RepairContext::prefetch_flip_samples(const std::vector<int>& triangles) {
  flip_mids_ = {};
  if (!field_.costly_calls()) return;
  std::vector<int> corners;
  for (const int t : triangles) {
    if (!alive_[t]) continue;
    for (int k = 0; k < 3; ++k) {
      const std::optional<FlipQuad> q = flip_candidate(t, k, true);
      if (!q) continue;
      const auto [u, a, b, c, d] = *q;
      (void)u;
      corners.insert(corners.end(), {a, b, c, d});
      for (const auto& [x, y] : {std::pair{a, b}, {a, d}, {d, b}, {b, c}, {c, a}, {c, d}}) flip_mids_.add(x, y);
    }
  }
  probe_creases(corners);
  std::vector<Vec3> at(flip_mids_.size());
  for (std::size_t i = 0; i < at.size(); ++i) {
    const auto [x, y] = flip_mids_.ends(i);
    at[i] = 0.5 * (P(x) + P(y));
  }
  std::vector<double> d;
  signed_distances(at, d);
  flip_mids_.d.resize(d.size());
  for (std::size_t i = 0; i < d.size(); ++i) flip_mids_.d[i] = {d[i], -1};
}

void RepairContext::probe_chunk(const std::vector<int>& todo) {
  std::vector<Vec3> at(todo.size()), g0(todo.size());
  std::vector<double> values(todo.size());
  for (std::size_t i = 0; i < todo.size(); ++i) at[i] = P(todo[i]);
  field_.values_gradients(at.data(), values.data(), g0.data(), at.size());
  // Those whose gradient agrees with their normal: the gradients on either side, as on_crease.
  std::vector<std::size_t> sides;
  std::vector<Vec3> around;
  for (std::size_t i = 0; i < todo.size(); ++i) {
    const int v = todo[i];
    if (!(g0[i].squaredNorm() > 0) || !(g0[i].normalized().dot(mesh_.normals[v]) > kCreaseNormalCosine)) {
      crease_[v] = 1;
      continue;
    }
    const std::array<Vec3, 2> two = CreaseProbe(options_.diagonal).points(at[i], g0[i].normalized());
    sides.push_back(i);
    around.push_back(two[1]);
    around.push_back(two[0]);
  }
  std::vector<Vec3> g(around.size());
  values.resize(around.size());
  field_.values_gradients(around.data(), values.data(), g.data(), around.size());
  for (std::size_t k = 0; k < sides.size(); ++k) {
    const Vec3 &g1 = g[2 * k], &g2 = g[2 * k + 1];
    crease_[todo[sides[k]]] =
        !(g1.squaredNorm() > 0 && g2.squaredNorm() > 0) || !(g1.normalized().dot(g2.normalized()) > kCreaseCosine);
  }
  for (const int v : todo) report_.crease_vertices += crease_[v] == 1;
}

void RepairContext::mark_boundary() {
  // Without count_near_boundary the caller measures again around every boundary vertex.
  const char kept = options_.count_near_boundary ? 1 : 2;
  fixed_.assign(mesh_.positions.size(), 0);
  // Edge (v, w) of a triangle has no single triangle across it (across < 0: none, or several)
  // unless exactly two of v's triangles hold w: counted around each vertex once, where asking
  // across for each edge of each triangle searched a star each time (2% of the torus at factor
  // 27 in blocks, callgrind). Every triangle is alive here (the constructor calls it), and a
  // triangle with a repeated corner is left to across.
  std::vector<int> held(mesh_.positions.size(), 0);  // by neighbour of v: v's triangles holding it
  bool repeated = false;
  for (int v = 0; v < static_cast<int>(vt_.size()); ++v) {
    poll(static_cast<std::size_t>(v));
    for (const int u : vt_[v]) {
      const Tri& x = mesh_.triangles[u];
      if (x[0] == x[1] || x[1] == x[2] || x[2] == x[0]) repeated = true;
      for (const int w : x)
        if (w != v) ++held[w];
    }
    for (const int u : vt_[v])
      for (const int w : mesh_.triangles[u]) {
        if (w == v || held[w] == 0) continue;
        if (held[w] != 2) fixed_[v] = fixed_[w] = kept;
        held[w] = 0;
      }
  }
  if (!repeated) return;
  fixed_.assign(mesh_.positions.size(), 0);
  for (int t = 0; t < tri_count(); ++t) {
    poll(static_cast<std::size_t>(t));
    const Tri& x = mesh_.triangles[t];
    for (int k = 0; k < 3; ++k)
      if (across(t, x[k], x[(k + 1) % 3]) < 0) fixed_[x[k]] = fixed_[x[(k + 1) % 3]] = kept;
  }
}

void RepairContext::mark_measured_again(const std::vector<char>& again) {
  for (std::size_t v = 0; v < std::min(again.size(), fixed_.size()); ++v)
    if (fixed_[v] && again[v]) fixed_[v] = 2;
}

bool RepairContext::near_measured_again(const Tri& T) const {
  // From the stars as they are now: flips change a boundary vertex's neighbours, and splits add
  // vertices beside it, so the band the caller cuts out after the repair is these triangles.
  const auto again = [&](int v) { return fixed(v) && fixed_[v] == 2; };
  for (int v : T) {
    if (again(v)) return true;
    for (int u : vt_[v])
      if (alive_[u])
        for (int w : mesh_.triangles[u])
          if (again(w)) return true;
  }
  return false;
}

int RepairContext::across(int t, int a, int b) const {
  int found = -1;
  for (int u : vt_[a]) {
    if (u == t || !alive_[u]) continue;
    const Tri& x = mesh_.triangles[u];
    if (x[0] == b || x[1] == b || x[2] == b) {
      if (found >= 0) return -1;  // not manifold here: leave it alone
      found = u;
    }
  }
  return found;
}

bool RepairContext::has_edge(int a, int b) const {
  for (int u : vt_[a]) {
    const Tri& x = mesh_.triangles[u];
    if (alive_[u] && (x[0] == b || x[1] == b || x[2] == b)) return true;
  }
  return false;
}

std::vector<int> RepairContext::neighbours(int v) const {
  std::vector<int> out;
  for (int u : vt_[v])
    for (int w : mesh_.triangles[u])
      if (w != v) out.push_back(w);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

void RepairContext::hash_cover(int t, const Vec3& lo, const Vec3& hi) {
  // Stale entries of earlier shapes stay and are filtered. A triangle is stored with its box
  // grown by kHashSlack cells, and not again while its box stays inside that: the small moves
  // of the relaxation would otherwise add a copy of each triangle around v at every move.
  if (static_cast<std::size_t>(t) < hashed_lo_.size() && (lo.array() >= hashed_lo_[t].array()).all() &&
      (hi.array() <= hashed_hi_[t].array()).all())
    return;
  const auto [glo, ghi] = grown_box(lo, hi);
  if (hashed_lo_.size() <= static_cast<std::size_t>(t)) {
    detail::grow_apart(options_.cancel, "adaptive: repair", t + 1 - hashed_lo_.size(), hashed_lo_, hashed_hi_);
    hashed_lo_.resize(t + 1);
    hashed_hi_.resize(t + 1);
  }
  hashed_lo_[t] = glo;
  hashed_hi_[t] = ghi;
  hash_.insert_box(t, glo, ghi);
}

bool RepairContext::intersects(const std::vector<Tri>& added, const std::vector<int>& ignored, int mv, const Vec3& moved) {
  const auto pos = [&](int v) -> const Vec3& { return v == mv ? moved : P(v); };
  std::vector<StarTriangle>& star = star_buffer_;
  star.clear();
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  double magnitude = 0;
  for (const Tri& a : added)
    if (!add_star_triangle(star, a, {pos(a[0]), pos(a[1]), pos(a[2])}, lo, hi, magnitude)) return true;
  if (star.empty()) return false;
  ++stamp_id_;
  for (int t : ignored) stamp_[t] = stamp_id_;
  return star_meets(star, lo, hi, magnitude, pos, stamp_.data(), stamp_id_);
}

bool RepairContext::apart_by_plane(const std::array<Vec3, 3>& a, const Tri& ia, const Vec3& n, const std::array<Vec3, 3>& b,
                              const Tri& ib, double bound) {
  int side = 0;
  for (int k = 0; k < 3; ++k) {
    if (ib[k] == ia[0] || ib[k] == ia[1] || ib[k] == ia[2]) continue;
    const double s = n.dot(b[k] - a[0]);
    const int q_side = s > bound ? 1 : s < -bound ? -1 : 0;
    if (q_side == 0 || (side != 0 && q_side != side)) return false;
    side = q_side;
  }
  return side != 0;
}

bool RepairContext::apart_at_shared_corner(const std::array<Vec3, 3>& a, const Tri& ia, const std::array<Vec3, 3>& b,
                                      const Tri& ib) {
  int i = -1, j = -1;
  for (int p = 0; p < 3; ++p)
    for (int q = 0; q < 3; ++q)
      if (ia[p] == ib[q]) {
        if (i >= 0) return false;  // an edge shared: apart_by_plane's case
        i = p, j = q;
      }
  return i >= 0 && apart_at_shared_vertex(a[i], a[(i + 1) % 3], a[(i + 2) % 3], b[(j + 1) % 3], b[(j + 2) % 3]);
}

bool RepairContext::meets_star(const std::vector<StarTriangle>& star, const Vec3& lo, const Vec3& hi, double magnitude,
                          const Tri& x, const std::array<Vec3, 3>& pb) {
  const Vec3 blo = pb[0].cwiseMin(pb[1]).cwiseMin(pb[2]), bhi = pb[0].cwiseMax(pb[1]).cwiseMax(pb[2]);
  if ((blo.array() > hi.array()).any() || (bhi.array() < lo.array()).any()) return false;
  const Vec3 nb = (pb[1] - pb[0]).cross(pb[2] - pb[0]);
  // One rounding bound for x against every star triangle, from the whole star's box and
  // magnitude: at least each pair's own (plane_bound grows with both), so as safe, and the
  // exact test decides whatever it leaves unsure.
  const double bound = plane_bound(std::max(std::max(blo.cwiseAbs().maxCoeff(), bhi.cwiseAbs().maxCoeff()), magnitude),
                                   (hi.cwiseMax(bhi) - lo.cwiseMin(blo)).norm());
  for (const StarTriangle& a : star) {
    if ((blo.array() > a.hi.array()).any() || (bhi.array() < a.lo.array()).any()) continue;
    if (apart_by_plane(a.p, a.ids, a.normal, pb, x, bound) || apart_by_plane(pb, x, nb, a.p, a.ids, bound)) continue;
    if (apart_at_shared_corner(a.p, a.ids, pb, x)) continue;
    if (exact_intersect(a.p, pb)) return true;  // the star's triangles are not degenerate (star_hits)
  }
  return false;
}

Vec3 RepairContext::equilateral_step(int v) const {
  const Vec3 x = P(v), n = mesh_.normals[v];
  Vec3 apex_mean = Vec3::Zero();
  int apexes = 0;
  for (int u : vt_[v]) {
    const Tri& t = mesh_.triangles[u];
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

void RepairContext::compact() {
  if (dead_vertex_.empty()) return;
  std::vector<int> remap(mesh_.positions.size(), 0);
  for (int v : dead_vertex_) remap[v] = -1;
  // Polled: at 2*10^6 triangles this is a tenth of a second.
  Mesh out;
  out.positions.reserve(mesh_.positions.size());
  out.normals.reserve(mesh_.positions.size());
  out.triangles.reserve(mesh_.triangles.size());
  int next = 0;
  for (int v : dead_vertex_)
    if (static_cast<std::size_t>(v) < renumbered_.size()) renumbered_[v] = -1;
  for (std::size_t v = 0; v < mesh_.positions.size(); ++v) {
    poll(v);
    if (remap[v] < 0) continue;
    remap[v] = next++;
    if (v < renumbered_.size()) renumbered_[v] = remap[v];
    out.positions.push_back(mesh_.positions[v]);
    out.normals.push_back(mesh_.normals[v]);
  }
  for (int t = 0; t < tri_count(); ++t) {
    poll(static_cast<std::size_t>(t));
    if (!alive_[t]) continue;
    const Tri& x = mesh_.triangles[t];
    out.triangles.push_back({remap[x[0]], remap[x[1]], remap[x[2]]});
  }
  jets_.clear(), spare_v_ = -1;  // by the old numbers
  mesh_.positions = std::move(out.positions);
  mesh_.normals = std::move(out.normals);
  mesh_.triangles = std::move(out.triangles);
}

}  // namespace cdp::adaptive::repair
