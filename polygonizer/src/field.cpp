#include <cdp/core/errors.h>
#include <cdp/core/field.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

namespace cdp {

std::pair<double, double> Field::derivative_range_of(const std::pair<Vec3, Vec3>& gradients, const Vec3& direction) {
  // u . grad F over the box of gradients: each term at whichever end gives its least and most.
  double lo = 0, hi = 0;
  for (int i = 0; i < 3; ++i) {
    const double a = direction[i] * gradients.first[i], b = direction[i] * gradients.second[i];
    lo += std::min(a, b);
    hi += std::max(a, b);
  }
  return {lo, hi};
}

std::optional<std::pair<double, double>> Field::derivative_range(const Box& region, const Vec3& direction) const {
  const auto g = gradient_range(region);
  if (!g) return std::nullopt;
  return derivative_range_of(*g, direction);
}

// A model without branch points is one piece: the field itself, with the empty branch.
FieldPiece Field::eval_piece(const Vec3& p, const std::vector<std::uint8_t>& branch) const {
  if (!branch.empty())
    throw InvalidInputError(type_name() + ": the model has no branch points, a piece's branch must be empty");
  FieldPiece piece;
  piece.value = eval_gradient_hessian(p, piece.gradient, piece.hessian);
  return piece;
}

void Field::BranchRecord::add(bool branch, double gap, const Vec3& slope) {
  taken.push_back(branch ? 1 : 0);
  const double s2 = slope.squaredNorm();
  const double g = std::abs(gap), s = std::sqrt(s2);
  distance.push_back(g == 0.0 ? 0.0 : s > 0.0 ? g / s : std::numeric_limits<double>::infinity());
  const bool sloped = s2 > 0.0 && std::isfinite(s2);
  seam_step.push_back(g == 0.0 || !sloped ? Vec3::Zero() : Vec3(-gap / s2 * slope));
  seam_normal.push_back(sloped ? Vec3(slope / s) : Vec3::Zero());
}

void Field::eval_first_order_flips(const Vec3& p, std::vector<std::uint8_t>& branch, std::span<const ChoiceStep> steps,
                                   const std::function<bool(double, const Vec3&)>& hidden) const {
  for (const ChoiceStep& step : steps) {
    const auto k = static_cast<std::size_t>(step.choice);
    if (step.flip) {
      std::vector<std::uint8_t> flipped = branch;
      flipped[k] ^= 1u;
      const auto [v, g] = eval_first_order(p, flipped);
      if (!hidden(v, g)) continue;
    }
    branch[k] = kFreeBranch;
  }
}

void Field::eval_first_order_combinations(const Vec3& p, const std::vector<std::uint8_t>& base,
                                          std::span<const int> split,
                                          std::vector<std::pair<double, Vec3>>& out) const {
  out.assign(std::size_t{1} << split.size(), {});
  for (std::size_t mask = 0; mask < out.size(); ++mask) {
    std::vector<std::uint8_t> branch = base;
    for (std::size_t j = 0; j < split.size(); ++j)
      if (mask >> j & 1u) branch[static_cast<std::size_t>(split[j])] ^= 1u;
    out[mask] = eval_first_order(p, branch);
  }
}

std::pair<double, Vec3> Field::eval_first_order(const Vec3& p, const std::vector<std::uint8_t>& branch) const {
  if (!branch.empty())
    throw InvalidInputError(type_name() + ": the model has no branch points, a piece's branch must be empty");
  Vec3 g;
  const double v = eval_value_gradient(p, g);
  return {v, g};
}

std::vector<FieldPiece> Field::eval_pieces(const Vec3& p, double radius, bool hessians) const {
  BranchRecord record;
  if (!has_branch_points() || !eval_branch_record(p, {}, record) || record.taken.empty()) return {};
  return pieces_near_branches(p, record, radius, hessians);
}

std::optional<Field::BranchSwitch> Field::branch_switch(const Vec3& p, std::size_t k) const {
  counter_.add_value_gradients(1);
  BranchRecord record;
  if (!eval_branch_record(p, {}, record) || k >= record.taken.size()) return std::nullopt;
  const Vec3& n = record.seam_normal[k];
  if (!(n.squaredNorm() > 0)) return std::nullopt;
  // seam_step is -(a - b) grad (a - b) / |grad (a - b)|^2, so minus its component along the
  // normal is the signed distance (a - b) / |grad (a - b)|.
  return BranchSwitch{-record.seam_step[k].dot(n), n};
}

std::optional<std::uint64_t> Field::live_branches(const Vec3& p, const std::vector<std::uint8_t>& branch) const {
  counter_.add_value_gradients(1);
  std::vector<std::int8_t> bits(branch.size(), -1);
  for (std::size_t k = 0; k < branch.size() && k < 64; ++k) bits[k] = static_cast<std::int8_t>(k);
  FieldPiece piece;
  std::uint64_t live = 0;
  if (!has_branch_points() || !eval_piece_live(p, branch, bits.data(), false, piece, live)) return std::nullopt;
  return live;
}

std::vector<Field::SmoothSide> Field::eval_smooth_sides(const Vec3& p, double radius,
                                                       const std::vector<std::uint8_t>& branch, SeamSideAt at) const {
  std::vector<SmoothSide> out;
  if (!has_branch_points()) return out;
  const std::vector<BranchKind>& kinds = branch_kinds();
  if (!any_smooth_) return out;
  BranchRecord record;
  counter_.add_value_gradients(1);
  if (!eval_branch_record(p, branch, record)) return out;
  for (std::size_t k = 0; k < std::min(kinds.size(), record.taken.size()); ++k) {
    if (kinds[k] != BranchKind::Smooth || !(record.distance[k] <= radius)) continue;
    std::vector<std::uint8_t> beyond = record.taken;
    beyond[k] ^= 1u;
    counter_.add_gradient_hessians(1);
    const Vec3 q = at == SeamSideAt::Seam ? Vec3(p + record.seam_step[k]) : p;
    out.push_back({record.distance[k], eval_piece(q, beyond)});
  }
  return out;
}

bool Field::has_pieces() const {
  if (!has_branch_points()) return false;
  const auto& kinds = branch_kinds();
  return std::find(kinds.begin(), kinds.end(), BranchKind::Creased) != kinds.end();
}

// What one test at sample p tells of branch point b (Field::branch_kinds): Hidden where flipping
// it changes nothing at p; else, where its switch meets the surface near p, Smooth or Creased
// by the normals on its two sides there; Unknown where no such point is found.
Field::BranchKind Field::switch_verdict(const Vec3& p, const BranchRecord& record, std::size_t b, double cell,
                                        std::uint64_t& evaluations) const {
  std::vector<std::uint8_t> branch = record.taken;
  branch[b] ^= 1u;
  const auto flipped = eval_first_order(p, branch);
  ++evaluations;
  if (flipped.first == record.value && flipped.second == record.gradient) return BranchKind::Hidden;
  // From p onto the switch and along it onto the surface: minimum-norm Newton steps on the two
  // equations, the switch's signed distance (from a record at each point) and F with branch 0.
  // Where the switch runs (nearly) parallel to the surface it does not meet it there: an onion's
  // abs(d) - t switches at d = 0, midway between its shells.
  branch[b] = 0;
  const double tolerance = kBranchOnSurface * cell;
  Vec3 q = p;
  BranchRecord at = record;
  for (int it = 0;; ++it) {
    const Vec3& normal = at.seam_normal[b];
    const double gap = -at.seam_step[b].dot(normal);
    const auto [v0, g0] = eval_first_order(q, branch);
    ++evaluations;
    const double n0 = g0.norm();
    if (!g0.allFinite() || !(n0 > 0.0) || !(normal.squaredNorm() > 0.0)) return BranchKind::Unknown;
    if (std::abs(v0) <= tolerance * n0 && std::abs(gap) <= tolerance) {
      // On the field's own surface, not only on the piece's: with the other branches fixed as
      // the sample takes them, the piece's zero set may lie where the field takes another
      // branch. A rounded box written as hypot(max(q, 0)) + min(max(q), 0): from a sample
      // inside its core, where the min takes max(q), the piece's zero set is the core's
      // sharp-edged box, whose edges the surface never meets; counted, they made max(q)
      // Creased, the rounded box a CSG shape, and a patch of it an endless prism.
      if (!(std::abs(at.value) <= tolerance * n0)) return BranchKind::Unknown;
      branch[b] = 1;
      const Vec3 g1 = eval_first_order(q, branch).second;
      ++evaluations;
      const double n1 = g1.norm();
      // A kink of the field off the surface does not tell (a rounded box's max(|z| - c, 0) inside
      // its flat faces, where the gradient is not finite either).
      if (!g1.allFinite() || !(n1 > 0.0)) return BranchKind::Unknown;
      if (!(g0.dot(g1) > kSamePieceCosine * n0 * n1)) return BranchKind::Creased;
      const Vec3 off = q + kBranchHiddenProbe * cell * normal;
      branch[b] = 0;
      const auto [w0, h0] = eval_first_order(off, branch);
      branch[b] = 1;
      const auto [w1, h1] = eval_first_order(off, branch);
      evaluations += 2;
      return same_to_rounding(w0, h0, w1, h1) ? BranchKind::Unknown : BranchKind::Smooth;
    }
    if (it == kBranchSurfaceSteps) return BranchKind::Unknown;
    const Vec3 u = g0 / n0;
    const double c = normal.dot(u), det = 1 - c * c;  // the Gram matrix of the unit rows
    if (!(det > kBranchSwitchAcross * kBranchSwitchAcross)) return BranchKind::Unknown;
    // J = [normal; u], rhs [gap; v0 / n0]: step = -J^T (J J^T)^-1 rhs.
    const double r0 = gap, r1 = v0 / n0;
    const double l0 = (r0 - c * r1) / det, l1 = (r1 - c * r0) / det;
    Vec3 step = -(l0 * normal + l1 * u);
    if (step.norm() > cell) step *= cell / step.norm();
    q += step;
    at = BranchRecord{};
    ++evaluations;
    if (!eval_branch_record(q, {}, at) || at.taken.size() != record.taken.size()) return BranchKind::Unknown;
  }
}

const std::vector<Field::BranchKind>& Field::branch_kinds() const {
  std::call_once(kinds_once_, [&] {
    if (!has_branch_points()) return;
    const Box& box = bounds();
    const Vec3 cell = box.size() / kBranchSamples;
    const double reach = 0.5 * cell.norm();
    std::vector<BranchKind> kinds;
    std::vector<int> smooth_tests;
    std::uint64_t evaluations = 0;
    for (int k = 0; k < kBranchSamples; ++k)
      for (int j = 0; j < kBranchSamples; ++j)
        for (int i = 0; i < kBranchSamples; ++i) {
          const Vec3 p = box.min + Vec3((i + 0.5) * cell.x(), (j + 0.5) * cell.y(), (k + 0.5) * cell.z());
          BranchRecord record;
          ++evaluations;
          if (!eval_branch_record(p, {}, record)) continue;
          if (kinds.empty()) {
            kinds.assign(record.taken.size(), BranchKind::Unknown);
            smooth_tests.assign(record.taken.size(), 0);
          }
          for (std::size_t b = 0; b < std::min(kinds.size(), record.taken.size()); ++b) {
            if (!(record.distance[b] <= reach) || kinds[b] == BranchKind::Creased || smooth_tests[b] >= kBranchTests)
              continue;
            const BranchKind verdict = switch_verdict(p, record, b, cell.minCoeff(), evaluations);
            if (verdict == BranchKind::Hidden && kinds[b] == BranchKind::Unknown) kinds[b] = BranchKind::Hidden;
            if (verdict == BranchKind::Smooth) {
              kinds[b] = BranchKind::Smooth;
              ++smooth_tests[b];
            }
            if (verdict == BranchKind::Creased) kinds[b] = BranchKind::Creased;
          }
        }
    counter_.add_value_gradients(evaluations);
    // Free in every piece: the Smooth branch points, and beside them the Hidden ones, which may
    // show where the Smooth ones let them (a rounded box's abs(z) under max(|z| - c, 0)): a
    // piece fixed to z > 0 there would go on flat where the box rounds below. In a field without
    // Smooth branch points a Hidden one stays hidden, and is split as it always was.
    const bool any_smooth = std::find(kinds.begin(), kinds.end(), BranchKind::Smooth) != kinds.end();
    any_smooth_ = any_smooth;
    free_.assign(kinds.size(), false);
    for (std::size_t b = 0; b < kinds.size(); ++b)
      free_[b] = kinds[b] == BranchKind::Smooth || (any_smooth && kinds[b] == BranchKind::Hidden);
    kinds_ = std::move(kinds);
  });
  return kinds_;
}

namespace {

// Two pieces with the same numbers at a point, bit for bit: one function there.
bool same_numbers(const FieldPiece& a, const FieldPiece& b) {
  return a.value == b.value && a.gradient == b.gradient && a.hessian == b.hessian;
}

}  // namespace

std::optional<std::vector<FieldPiece>> Field::pieces_of_live_choices(const Vec3& p, const std::vector<std::uint8_t>& base,
                                                                    const std::vector<int>& split, bool hessians) const {
  std::vector<std::int8_t> bits(base.size(), -1);
  for (std::size_t j = 0; j < split.size(); ++j) bits[static_cast<std::size_t>(split[j])] = static_cast<std::int8_t>(j);
  struct Leaf {
    std::size_t mask;
    FieldPiece piece;
  };
  std::vector<Leaf> leaves;
  // Combinations still to evaluate: the flips (bit j: split[j]) and which of the split choices
  // are settled (the others are tried flipped only where an evaluation depends on them).
  struct Todo {
    std::size_t mask, settled;
  };
  std::vector<Todo> todo{{0, 0}};
  while (!todo.empty()) {
    const Todo t = todo.back();
    todo.pop_back();
    std::vector<std::uint8_t> branch = base;
    for (std::size_t j = 0; j < split.size(); ++j)
      if (t.mask >> j & 1u) branch[static_cast<std::size_t>(split[j])] ^= 1u;
    FieldPiece piece;
    std::uint64_t live = 0;
    if (!eval_piece_live(p, branch, bits.data(), hessians, piece, live)) return std::nullopt;
    // This evaluation stands for every combination that differs from it only in choices it does
    // not depend on; each choice it depends on is settled here and tried the other way too.
    std::size_t settled = t.settled;
    for (std::size_t j = 0; j < split.size(); ++j) {
      const std::size_t bit = std::size_t{1} << j;
      if ((settled & bit) || !(live & bit)) continue;
      settled |= bit;
      todo.push_back({t.mask | bit, settled});
    }
    piece.branch = std::move(branch);
    leaves.push_back({t.mask, std::move(piece)});
  }
  // As the loop over every combination keeps them: in order of their flips, the first of equal ones.
  std::sort(leaves.begin(), leaves.end(), [](const Leaf& a, const Leaf& b) { return a.mask < b.mask; });
  std::vector<FieldPiece> out;
  for (Leaf& leaf : leaves) {
    const auto same = [&](const FieldPiece& q) { return same_numbers(q, leaf.piece); };
    if (std::none_of(out.begin(), out.end(), same)) out.push_back(std::move(leaf.piece));
  }
  return out;
}

std::vector<FieldPiece> Field::pieces_near_branches(const Vec3& p, const BranchRecord& record, double radius,
                                                   bool hessians) const {
  const std::vector<std::uint8_t>& taken = record.taken;
  const std::vector<double>& distance = record.distance;
  branch_kinds();
  const auto is_free = [&](std::size_t k) { return k < free_.size() && free_[k]; };
  std::vector<int> split;
  for (std::size_t k = 0; k < taken.size(); ++k)
    if (distance[k] <= radius && !is_free(k)) split.push_back(static_cast<int>(k));
  // The nearest switches (ties: the earlier branch point), then back in program order.
  std::stable_sort(split.begin(), split.end(), [&](int a, int b) {
    return distance[static_cast<std::size_t>(a)] < distance[static_cast<std::size_t>(b)];
  });
  if (split.size() > static_cast<std::size_t>(kMaxSplitBranchPoints)) split.resize(kMaxSplitBranchPoints);
  std::sort(split.begin(), split.end());
  std::vector<std::uint8_t> base = taken;
  bool any_free = false;
  for (std::size_t k = 0; k < base.size(); ++k)
    if (is_free(k)) {
      base[k] = kFreeBranch;
      any_free = true;
    }
  if (!any_free && split.empty() && !hessians) {
    // One piece, the branches as the values take them: the record's own evaluation (the same
    // numbers, bit for bit, as evaluating those branches again). Most points crease tracing
    // visits lie so, inside a face.
    FieldPiece piece;
    piece.branch = taken;
    piece.value = record.value;
    piece.gradient = record.gradient;
    return {std::move(piece)};
  }
  if (!any_free && !split.empty())
    if (std::optional<std::vector<FieldPiece>> out = pieces_of_live_choices(p, base, split, hessians)) return *out;
  const std::size_t combinations = std::size_t{1} << split.size();
  std::vector<FieldPiece> all;
  std::vector<std::size_t> kept;
  all.reserve(combinations);
  std::vector<std::pair<double, Vec3>> first_order;
  if (!hessians) eval_first_order_combinations(p, base, split, first_order);
  for (std::size_t mask = 0; mask < combinations; ++mask) {
    std::vector<std::uint8_t> branch = base;
    for (std::size_t j = 0; j < split.size(); ++j)
      if (mask >> j & 1u) branch[static_cast<std::size_t>(split[j])] ^= 1u;
    if (hessians) {
      all.push_back(eval_piece(p, branch));
    } else {
      FieldPiece& piece = all.emplace_back();
      std::tie(piece.value, piece.gradient) = first_order[mask];
      piece.branch = std::move(branch);
    }
    // Different branches often give the same function (a choice inside an argument that is not
    // taken): the same numbers at p, bit for bit, are one piece.
    const auto same = [&](std::size_t i) { return same_numbers(all[i], all.back()); };
    if (std::none_of(kept.begin(), kept.end(), same)) kept.push_back(mask);
  }
  std::vector<FieldPiece> out;
  // Beside a free branch point, a fixed one may matter where the piece is evaluated away from p
  // even though it does not at p: a rounded box's abs(x) under max(abs(x) - a, 0), which the
  // max hides near x = 0 and shows past |x| = a. So where the field has free branch points, a
  // choice that changes nothing at p is free too: the piece is then the field's own continuation
  // there. (Without free branch points a hidden choice stays hidden, and the pieces are as
  // they always were.) Each piece is asked for itself: a choice the field's own branches hide
  // may show in a piece that flips another. A tetrahedron written max(|x + y| - z, |x - y| + z)
  // hides |x - y| where the max takes its first argument, not in the piece that takes the
  // second; made free there, that piece held two faces and the crease between them, and the
  // patches of a tetrahedron with a ball blended in crossed at its corners.
  std::uint64_t evaluations = 0;
  out.reserve(kept.size());
  for (const std::size_t mask : kept) {
    // Moved: the comparisons below read the other pieces' numbers, never their branches.
    FieldPiece piece = std::move(all[mask]);
    if (any_free) {
      // A choice whose result a later given choice discards changes nothing: free without an
      // evaluation (a knurled cylinder's 253 branch points, a few dozen of them reaching the value).
      std::vector<std::uint8_t> reaches;
      const bool known = choices_reaching(piece.branch, reaches);
      std::vector<ChoiceStep> steps;
      for (std::size_t k = 0; k < piece.branch.size(); ++k) {
        if (base[k] == kFreeBranch || std::binary_search(split.begin(), split.end(), static_cast<int>(k))) continue;
        const bool flip = !known || reaches[k];
        steps.push_back({static_cast<int>(k), flip});
        evaluations += flip;
      }
      eval_first_order_flips(p, piece.branch, steps, [&](double v, const Vec3& g) {
        return same_to_rounding(piece.value, piece.gradient, v, g);
      });
      // Likewise a split choice this piece does not depend on at p.
      for (std::size_t j = 0; j < split.size(); ++j) {
        if (same_numbers(all[mask ^ (std::size_t{1} << j)], piece))
          piece.branch[static_cast<std::size_t>(split[j])] = kFreeBranch;
      }
    }
    out.push_back(std::move(piece));
  }
  counter_.add_value_gradients(evaluations);
  return out;
}

}  // namespace cdp
