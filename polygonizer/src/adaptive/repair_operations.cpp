// The mesh operations of the repair's algorithms (repair_context.h): edge flips, tangential
// vertex moves, edge collapses and edge splits, each tested before it is applied.
#include "repair_context.h"

namespace cdp::adaptive::repair {

std::optional<RepairContext::FlipQuad> RepairContext::flip_candidate(int t, int k, bool for_ratio) const {
  const Tri& T = mesh_.triangles[t];
  const int a = T[k], b = T[(k + 1) % 3], c = T[(k + 2) % 3];
  const int u = across(t, a, b);
  if (u < 0) return std::nullopt;
  const Tri& U = mesh_.triangles[u];
  int d = -1;
  for (int w : U)
    if (w != a && w != b) d = w;
  // Two boundary vertices may already share an edge beyond the piece (a neighbouring block's
  // seam edge, a triangle outside the band) that has_edge cannot see.
  if (d < 0 || d == c || (fixed(c) && fixed(d))) return std::nullopt;
  // Each relaxation flip lowers the valences' summed squared distance from 6, or keeps it and
  // lowers the summed edge ratio (below): no flip can be undone, and the relaxation's moves
  // then have a more regular mesh to work on (an interior vertex of valence 6 can have six
  // equilateral triangles, one of 4 or 8 cannot). The valences first: on an even mesh nearly
  // every edge the relaxation tries fails on them (573,809 of 574,422 tries on the torus at
  // factor 20), before the other tests' edge scans and square roots.
  const auto dev = [&](int x, int add) {
    const int q = static_cast<int>(vt_[x].size()) + add - 6;
    return q * q;
  };
  const int val_before = for_ratio ? dev(a, 0) + dev(b, 0) + dev(c, 0) + dev(d, 0) : 0;
  const int val_after = for_ratio ? dev(a, -1) + dev(b, -1) + dev(c, 1) + dev(d, 1) : 0;
  if (val_after > val_before) return std::nullopt;
  if (has_edge(c, d)) return std::nullopt;
  const Tri n1{c, a, d}, n2{d, b, c};
  if (for_ratio) {
    const double ratio_before = tri_ratio(T) + tri_ratio(U), ratio_after = tri_ratio(n1) + tri_ratio(n2);
    const bool better = ratio_after < ratio_before * (1 - kRelaxMinGain)
                            ? val_after <= val_before
                            : val_after < val_before && ratio_after < ratio_before * kFlipRatioSlack;
    if (!better) return std::nullopt;
  }
  const double before = std::min(tri_min_angle(T), tri_min_angle(U));
  const double after = std::min(tri_min_angle(n1), tri_min_angle(n2));
  if (for_ratio ? !(after >= std::min(before, kRelaxKeepDegrees * std::numbers::pi / 180))
                : !(after > before + kMinGain))
    return std::nullopt;
  const double floor = facing_floor({t, u});
  if (!faces_surface(n1, floor) || !faces_surface(n2, floor)) return std::nullopt;
  return FlipQuad{u, a, b, c, d};
}

bool RepairContext::try_flip(int t, int k, bool for_ratio) {
  // The tests that need no field evaluation first.
  const std::optional<FlipQuad> q = flip_candidate(t, k, for_ratio);
  if (!q) return false;
  const auto [u, a, b, c, d] = *q;
  const Tri T = mesh_.triangles[t], U = mesh_.triangles[u];
  const Tri n1{c, a, d}, n2{d, b, c};
  // A flip must not remove a crease edge nor cut across one.
  const bool creased = on_crease(a) || on_crease(b) || on_crease(c) || on_crease(d);
  if (creased && !(face_normal(T).dot(face_normal(U)) > kCreaseFlatCos)) return false;
  // The new diagonal may lie no farther from the surface than the worst edge of the quad.
  // Those prefetch_flip_samples measured for this pass of flips are taken as they are.
  const auto mid = [&](int x, int y) {
    if (const std::optional<std::size_t> i = flip_mids_.find(x, y)) return std::abs(flip_mids_.d[*i].d);
    return std::abs(signed_distance(0.5 * (P(x) + P(y))));
  };
  const double allowed = std::max({mid(a, b), mid(a, d), mid(d, b), mid(b, c), mid(c, a)});
  if (!(mid(c, d) <= allowed)) return false;
  if (!keeps_tolerance({n1, n2}, {t, u})) return false;
  if (intersects({n1, n2}, {t, u})) return false;
  mesh_.triangles[t] = n1;
  mesh_.triangles[u] = n2;
  erase_value(vt_[a], u);
  erase_value(vt_[b], t);
  vt_[c].push_back(u);
  vt_[d].push_back(t);
  hash_box(t);
  hash_box(u);
  touch(t);
  touch(u);
  if (for_ratio) {
    ++report_.relax_flips;
    for (int w : {a, b, c, d}) flipped_[w] = 1;
  } else {
    ++report_.flips;
  }
  return true;
}

bool RepairContext::try_move(int v) {
  if (fixed(v) || on_crease(v)) return false;
  const std::vector<int> ring = neighbours(v);
  if (ring.size() < 3) return false;
  Vec3 centroid = Vec3::Zero();
  for (int w : ring) centroid += P(w);
  centroid /= static_cast<double>(ring.size());
  const Vec3 x = P(v), n = mesh_.normals[v];
  // Two targets: the centroid of the neighbours (Laplacian smoothing), and the mean of the
  // apexes of equilateral triangles over the star's outer edges (equilateral_step), which
  // pulls v towards where each of its triangles would be equilateral and opens small angles
  // the centroid leaves.
  std::vector<Vec3> steps;
  Vec3 to_centroid = centroid - x;
  to_centroid -= n * n.dot(to_centroid);
  steps.push_back(to_centroid);
  const Vec3 to_equilateral = equilateral_step(v);
  steps.push_back(to_equilateral.squaredNorm() > 0 ? to_equilateral : to_centroid);
  double shortest = std::numeric_limits<double>::infinity();
  for (int w : ring) shortest = std::min(shortest, (P(w) - x).norm());
  double before = std::numeric_limits<double>::infinity();
  for (int u : vt_[v]) before = std::min(before, tri_min_angle(mesh_.triangles[u]));
  for (const double share : kMoveShares)
  for (const Vec3& step : steps) {
    // Newton moves the point by about the sagitta of its edges, which changes the angles
    // little: a tangential position that does not raise them is not worth projecting.
    {
      mesh_.positions[v] = x + share * step;
      double guess = std::numeric_limits<double>::infinity();
      for (int u : vt_[v]) guess = std::min(guess, tri_min_angle(mesh_.triangles[u]));
      mesh_.positions[v] = x;
      if (!(guess > before)) continue;
    }
    ProjectionOptions po;
    po.tolerance = 1e-10 * options_.diagonal;
    po.max_step = shortest;
    po.max_travel = shortest;
    const ProjectionResult pr = project_to_surface(field_, x + share * step, po);
    if (!pr.ok()) continue;
    const Vec3& g = pr.gradient;  // at pr.point: no second evaluation of the same point
    if (!(g.squaredNorm() > 0)) continue;
    const Vec3 ng = g.normalized();
    if (!(ng.dot(n) > kMoveNormalCos)) continue;
    // The star with v at its new place.
    const double floor = facing_floor(vt_[v]);
    const Vec3 saved = mesh_.positions[v], saved_n = mesh_.normals[v];
    mesh_.positions[v] = pr.point;
    mesh_.normals[v] = ng;
    double after = std::numeric_limits<double>::infinity();
    bool faces = true;
    std::vector<Tri> star;
    for (int u : vt_[v]) {
      star.push_back(mesh_.triangles[u]);
      after = std::min(after, tri_min_angle(mesh_.triangles[u]));
      faces = faces && faces_surface(mesh_.triangles[u], floor);
    }
    bool ok = after > before + kMinGain && faces;
    const double new_dist = ok ? worst_star_distance(v) : 0;
    mesh_.positions[v] = saved;
    mesh_.normals[v] = saved_n;
    if (ok) {
      const Vec3 target = pr.point;
      ok = may_replace(new_dist, vt_[v]) && !intersects(star, vt_[v], v, target);
      if (ok) {
        mesh_.positions[v] = target;
        mesh_.normals[v] = ng;
        crease_[v] = -1;
        for (int u : vt_[v]) {
          hash_box(u);
          touch(u);
        }
        ++report_.moves;
        return true;
      }
    }
  }
  return false;
}

bool RepairContext::try_collapse(int t, int a, int b, bool apex_onto_crease) {
  const int u = across(t, a, b);
  if (u < 0 || fixed(a) || fixed(b)) return false;
  const bool ca = on_crease(a), cb = on_crease(b);
  if (ca && cb && !apex_onto_crease) return false;
  int c = -1, d = -1;
  for (int w : mesh_.triangles[t])
    if (w != a && w != b) c = w;
  for (int w : mesh_.triangles[u])
    if (w != a && w != b) d = w;
  // The link condition: a and b share exactly the neighbours c and d, so the collapse keeps
  // the surface manifold and its topology; c and d keep at least three neighbours.
  const std::vector<int> na = neighbours(a), nb = neighbours(b);
  std::vector<int> common;
  std::set_intersection(na.begin(), na.end(), nb.begin(), nb.end(), std::back_inserter(common));
  if (common.size() != 2 || !((common[0] == c && common[1] == d) || (common[0] == d && common[1] == c))) return false;
  if (neighbours(c).size() < 4 || neighbours(d).size() < 4) return false;
  // The merged vertex: a crease end stays where it is; otherwise the midpoint, on the surface.
  Vec3 x, nx;
  // Across a ridge narrower than the edge (the landing's normal within 30 degrees of neither
  // end's, see lands_between), the merged vertex stands for both flanks.
  bool ridge = false;
  if (ca || cb) {
    x = ca ? P(a) : P(b);
    nx = ca ? mesh_.normals[a] : mesh_.normals[b];
  } else {
    ProjectionOptions po;
    po.tolerance = 1e-10 * options_.diagonal;
    const double l = (P(a) - P(b)).norm();
    po.max_step = l;
    po.max_travel = l;
    const ProjectionResult pr = project_to_surface(field_, 0.5 * (P(a) + P(b)), po);
    if (!pr.ok()) return false;
    const Vec3& g = pr.gradient;  // at pr.point
    if (!(g.squaredNorm() > 0)) return false;
    x = pr.point;
    nx = g.normalized();
    if (!lands_between(nx, mesh_.normals[a], mesh_.normals[b])) return false;
    ridge = !(nx.dot(mesh_.normals[a]) > kMoveNormalCos && nx.dot(mesh_.normals[b]) > kMoveNormalCos);
    // Not across a crease of the field (two of its min/max/abs pieces meet within the edge):
    // that edge stands on both faces of a real crease, which a collapse would round off.
    if (ridge && field_.pieces(x, l).size() > 1) return false;
  }
  std::vector<int> old;  // every triangle around a or b
  for (int w : vt_[a]) old.push_back(w);
  for (int w : vt_[b])
    if (std::find(old.begin(), old.end(), w) == old.end()) old.push_back(w);
  std::sort(old.begin(), old.end());
  double before = std::numeric_limits<double>::infinity();
  for (int w : old) before = std::min(before, tri_min_angle(mesh_.triangles[w]));
  std::vector<Tri> added;
  std::vector<int> kept;
  for (int w : old) {
    if (w == t || w == u) continue;
    Tri x3 = mesh_.triangles[w];
    for (int& y : x3)
      if (y == b) y = a;
    added.push_back(x3);
    kept.push_back(w);
  }
  const double floor = facing_floor(old);
  const Vec3 saved = mesh_.positions[a], saved_n = mesh_.normals[a];
  const Vec3 flank_a = mesh_.normals[a], flank_b = mesh_.normals[b];
  mesh_.positions[a] = x;
  mesh_.normals[a] = nx;
  double after = std::numeric_limits<double>::infinity();
  bool faces = true;
  for (const Tri& s : added) {
    after = std::min(after, tri_min_angle(s));
    if (!ridge) {
      faces = faces && faces_surface(s, floor);
      continue;
    }
    // On a ridge the crest's normal is up to half the ridge's turn (50-75 degrees on the horse)
    // from either flank, so a triangle lying on a flank faces it edge-on; at the merged corner
    // it must face one of the three normals the vertex stands for (crest, either flank), at the
    // other corners their own as everywhere.
    const Vec3 fn = face_normal(s);
    for (int v : s) {
      const double c = v == a ? std::max({fn.dot(nx), fn.dot(flank_a), fn.dot(flank_b)}) : fn.dot(mesh_.normals[v]);
      faces = faces && c > floor;
    }
  }
  bool ok = after > before + kMinGain && faces;
  const double new_dist = ok ? worst_distance(added) : 0;
  mesh_.positions[a] = saved;
  mesh_.normals[a] = saved_n;
  ok = ok && may_replace(new_dist, old);
  if (ok) ok = !intersects(added, old, a, x);
  if (!ok) return false;
  mesh_.positions[a] = x;
  mesh_.normals[a] = nx;
  crease_[a] = ca || cb ? 1 : -1;
  alive_[t] = alive_[u] = 0;
  for (std::size_t i = 0; i < kept.size(); ++i) mesh_.triangles[kept[i]] = added[i];
  std::vector<int> star;
  for (int w : old)
    if (w != t && w != u) star.push_back(w);
  vt_[a] = star;
  vt_[b].clear();
  erase_value(vt_[c], t);
  erase_value(vt_[d], u);
  dead_vertex_.push_back(b);
  for (int w : star) {
    hash_box(w);
    touch(w);
  }
  ++report_.collapses;
  return true;
}

bool RepairContext::try_split(int t, int a, int b, bool repair, double shortest) {
  const int u = across(t, a, b);
  if (u < 0) return false;
  if ((P(a) - P(b)).norm() < 2 * (shortest > 0 ? shortest : options_.min_edge)) return false;
  int c = -1, d = -1;
  for (int w : mesh_.triangles[t])
    if (w != a && w != b) c = w;
  for (int w : mesh_.triangles[u])
    if (w != a && w != b) d = w;
  // Next to a crease, a repair insertion keeps to one face: the quad flat (the flip's test,
  // kCreaseFlatCos), the edge it removes not both of whose ends lie on the crease (it may run
  // along it), and the new vertex landing with its gradient on that face (below). The Barth
  // ball's crease patches left caps there that nothing else could open: a crease finely
  // spaced for the steep side, the flat side's vertices far off along its tangent (0.61
  // degrees at factor 6).
  const bool creased = repair && (on_crease(a) || on_crease(b) || on_crease(c) || on_crease(d));
  const Vec3 face_t = creased ? face_normal(mesh_.triangles[t]) : Vec3::Zero();
  const Vec3 face_u = creased ? face_normal(mesh_.triangles[u]) : Vec3::Zero();
  if (creased && ((on_crease(a) && on_crease(b)) || !(face_t.dot(face_u) > kCreaseFlatCos))) return false;
  ProjectionOptions po;
  po.tolerance = 1e-10 * options_.diagonal;
  const double l = (P(a) - P(b)).norm();
  po.max_step = 0.5 * l;
  po.max_travel = 0.5 * l;
  const Vec3 start = repair ? Vec3(0.25 * (P(a) + P(b) + P(c) + P(d))) : Vec3(0.5 * (P(a) + P(b)));
  const ProjectionResult pr = project_to_surface(field_, start, po);
  if (!pr.ok()) return false;
  const Vec3& g = pr.gradient;  // at pr.point
  if (!(g.squaredNorm() > 0)) return false;
  const Vec3 ng = g.normalized();
  if (!(ng.dot(mesh_.normals[a]) > 0 && ng.dot(mesh_.normals[b]) > 0)) return false;
  if (creased && !(ng.dot(face_t) > kCreaseFlatCos && ng.dot(face_u) > kCreaseFlatCos)) return false;
  // t = (a, b, c) in its own rotation, u = (b, a, d).
  const int m = static_cast<int>(mesh_.positions.size());
  add_vertex(pr.point, ng);
  const std::vector<Tri> added{{a, m, c}, {m, b, c}, {b, m, d}, {m, a, d}};
  bool ok = true;
  const double floor = facing_floor({t, u});
  for (const Tri& s : added) ok = ok && faces_surface(s, floor);
  if (ok && repair) {
    double after = std::numeric_limits<double>::infinity();
    for (const Tri& s : added) after = std::min(after, tri_min_angle(s));
    ok = after > std::min(tri_min_angle(mesh_.triangles[t]), tri_min_angle(mesh_.triangles[u])) + kMinGain;
    const auto mid = [&](int x, int y) { return std::abs(signed_distance(0.5 * (P(x) + P(y)))); };
    const double allowed = std::max({mid(a, b), mid(a, d), mid(d, b), mid(b, c), mid(c, a)});
    ok = ok && std::max({mid(m, a), mid(m, b), mid(m, c), mid(m, d)}) <= allowed;
    ok = ok && keeps_tolerance(added, {t, u});
  }
  if (ok) ok = !intersects(added, {t, u});
  if (!ok) {
    drop_last_vertex();
    return false;
  }
  make_room_for_triangles(2);
  const int t2 = tri_count(), u2 = t2 + 1;
  mesh_.triangles[t] = added[0];
  mesh_.triangles.push_back(added[1]);
  mesh_.triangles[u] = added[2];
  mesh_.triangles.push_back(added[3]);
  alive_.push_back(1);
  alive_.push_back(1);
  stamp_.push_back(0);
  stamp_.push_back(0);
  // a: t, u2 (was t, u); b: t2, u (was t, u); c: t, t2; d: u, u2; m: all four.
  erase_value(vt_[a], u);
  vt_[a].push_back(u2);
  erase_value(vt_[b], t);
  vt_[b].push_back(t2);
  vt_[c].push_back(t2);
  vt_[d].push_back(u2);
  vt_[m] = {t, t2, u, u2};
  for (int s : {t, t2, u, u2}) {
    hash_box(s);
    touch(s);
  }
  ++(repair ? report_.inserts : report_.splits);
  return true;
}

}  // namespace cdp::adaptive::repair
