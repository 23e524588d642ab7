#include <cdp/core/autodiff.h>
#include <cdp/core/errors.h>
#include <cdp/core/models/expression.h>

#include "interval.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <map>
#include <limits>
#include <memory>
#include <mutex>
#include <new>
#include <numbers>
#include <vector>

namespace cdp {

namespace detail {

// An operation is computed in ExpressionProgram::run and, for the flips of a piece, in apply:
// a new one goes in both (Expression.FlipsAndCombinationsFromOneRunGiveTheBitsOfARunEach
// compares them on the formulas it uses).
enum class Op {
  Const, X, Y, Z, Add, Sub, Mul, Div, Neg, PowConst, Pow, Sqrt, Exp, Log, Sin, Cos, Tan, Atan, Atan2, Floor, Round,
  Abs, Min, Max,
  Store, Load  // a named sub-expression: pop it into slot `constant`; push slot `constant`
};

struct Instruction {
  Op op;
  double constant = 0;
};

// Deep enough for any formula a person writes; the evaluator keeps its stack in a fixed array.
constexpr int kMaxStack = 64;
// The parser recurses once per level of parentheses, calls, signs and exponents (4000 levels of
// parentheses overflowed the default 8 MB stack), and emitting and destroying the formula tree
// recurse once per level of its height (a sum of 300000 terms overflowed it). Both limits are
// far beyond any formula a person writes and leave a wide margin for sanitizer builds' frames.
constexpr int kMaxNesting = 256;
constexpr int kMaxHeight = 10000;
// Named sub-expressions ("define"), each evaluated once per run into a slot of a fixed array:
// far more than a model written by hand names.
constexpr int kMaxDefinitions = 256;

// What a run does at the branch points (min, max, abs, numbered in program order): nothing
// beyond taking the branch (Free); also report at each the branch taken and how far the surface
// where it would switch lies, to first order (Record: Jet1 only; the given branches where there
// are, else as the values choose); take given branches (Forced).
// ForcedLive: as Forced, and also report which branch points the value depends on
// (Field::eval_piece_live).
// Taped: as Forced, and also keep each instruction's result (a Store's: the value it stores) in
// BranchLog::tape (Expression::eval_first_order_flips).
enum class Branching { Free, Record, Forced, ForcedLive, Taped };

struct BranchLog {
  const std::uint8_t* forced = nullptr;      // Forced (Record: or null): the branch to take at each branch point
  Field::BranchRecord* record = nullptr;     // Record: the branch taken and where it switches
  const std::int8_t* bit = nullptr;          // ForcedLive: each branch point's bit in *live, or -1
  std::uint64_t* live = nullptr;             // ForcedLive: the bits of the branch points the value depends on
  void* tape = nullptr;                      // Taped: a T per instruction
};

struct ExpressionProgram {
  std::vector<Instruction> code;
  int branch_points = 0;
  int slots = 0;  // named sub-expressions kept
  // The program as a graph, for choices_reaching: each instruction's operands (the instructions
  // that pushed them, -1 for none; a Load's is the Store it reads), its branch point's number
  // (-1 if none), and the instruction whose result is the value.
  std::vector<std::array<int, 2>> operands;
  std::vector<int> branch_number;
  // Each branch point's instruction, and each instruction's consumers (the instructions whose
  // operand it is; a Store's are the Loads that read it): consumers_of[consumer_start[i] ..
  // consumer_start[i + 1]), for eval_first_order_flips.
  std::vector<int> branch_instruction;
  std::vector<int> consumer_start, consumers_of;
  int result = -1;
  int depth = 0;  // the most operands pending at once (the evaluator's stack holds kMaxStack)
  // A program specialized to a region (specialize) only: the branch points it took out, each with
  // the branch it takes there.
  std::vector<std::pair<int, std::uint8_t>> fixed;

  // Fills the graph, branch_points and depth from `code`.
  void link() {
    operands.assign(code.size(), {-1, -1});
    branch_number.assign(code.size(), -1);
    std::vector<int> pushed, stored(static_cast<std::size_t>(std::max(slots, 1)), -1);
    branch_points = depth = 0;
    for (std::size_t i = 0; i < code.size(); ++i) {
      const auto pop = [&] {
        const int top = pushed.back();
        pushed.pop_back();
        return top;
      };
      Instruction& in = code[i];
      auto& args = operands[i];
      switch (in.op) {
        case Op::Const: case Op::X: case Op::Y: case Op::Z: break;
        case Op::Load: args[0] = stored[static_cast<std::size_t>(in.constant)]; break;
        case Op::Store: stored[static_cast<std::size_t>(in.constant)] = static_cast<int>(i); args[0] = pop(); break;
        case Op::Add: case Op::Sub: case Op::Mul: case Op::Div: case Op::Pow: case Op::Atan2: case Op::Min: case Op::Max:
          args[1] = pop();
          args[0] = pop();
          break;
        default: args[0] = pop(); break;
      }
      // A branch point's number is also its instruction's constant, which a specialized program
      // (specialize) keeps for the branch points it keeps.
      if (in.op == Op::Min || in.op == Op::Max || in.op == Op::Abs) {
        branch_number[i] = branch_points++;
        in.constant = branch_number[i];
      }
      if (in.op != Op::Store) pushed.push_back(static_cast<int>(i));
      depth = std::max(depth, static_cast<int>(pushed.size()));
    }
    result = pushed.empty() ? -1 : pushed.back();
    branch_instruction.assign(static_cast<std::size_t>(branch_points), -1);
    consumer_start.assign(code.size() + 1, 0);
    for (std::size_t i = 0; i < code.size(); ++i) {
      if (branch_number[i] >= 0) branch_instruction[static_cast<std::size_t>(branch_number[i])] = static_cast<int>(i);
      for (const int from : operands[i])
        if (from >= 0) ++consumer_start[static_cast<std::size_t>(from) + 1];
    }
    for (std::size_t i = 0; i < code.size(); ++i) consumer_start[i + 1] += consumer_start[i];
    consumers_of.assign(static_cast<std::size_t>(consumer_start.back()), 0);
    std::vector<int> next(consumer_start.begin(), consumer_start.end() - 1);
    for (std::size_t i = 0; i < code.size(); ++i)
      for (const int from : operands[i])
        if (from >= 0) consumers_of[static_cast<std::size_t>(next[static_cast<std::size_t>(from)]++)] = static_cast<int>(i);
  }

  template <class T>
  T run(const T& x, const T& y, const T& z) const {
    return run<T, Branching::Free>(x, y, z, BranchLog{});
  }

  // Branch 0 is the first argument of min and max and +u for abs; 1 the second argument and -u.
  template <class T, Branching mode>
  T run(const T& x, const T& y, const T& z, [[maybe_unused]] const BranchLog& record) const {
    using std::abs, std::atan, std::atan2, std::cos, std::exp, std::floor, std::log, std::max, std::min, std::pow,
        std::round, std::sin, std::sqrt, std::tan;
    // Raw storage: constructing kMaxStack jets per call would cost more than the formula.
    alignas(T) unsigned char storage[sizeof(T) * kMaxStack];
    T* stack = reinterpret_cast<T*>(storage);
    alignas(T) unsigned char slot_storage[sizeof(T) * kMaxDefinitions];
    T* slot = reinterpret_cast<T*>(slot_storage);
    int top = -1;
    // ForcedLive: beside each stack entry and slot, the bits of the branch points whose choice
    // reaches it (a min or max passes on its chosen argument's only, and its own).
    constexpr bool kLive = mode == Branching::ForcedLive;
    [[maybe_unused]] std::uint64_t dep[kLive ? kMaxStack : 1];
    [[maybe_unused]] std::uint64_t dep_slot[kLive ? kMaxDefinitions : 1];
    // A branch point's number is its instruction's constant (link).
    [[maybe_unused]] const auto own_bit = [&](int k) {
      const int b = record.bit[k];
      return b >= 0 ? std::uint64_t{1} << b : std::uint64_t{0};
    };
    // At a branch point: the branch to take, given that `natural` is the one the values choose.
    [[maybe_unused]] const auto choose = [&](int k, bool natural, const T& a, const T& b) {
      if constexpr (mode == Branching::Forced || kLive || mode == Branching::Taped)
        return record.forced[k] == Field::kFreeBranch ? natural : record.forced[k] != 0;
      if constexpr (mode == Branching::Record) {
        const bool taken =
            record.forced == nullptr || record.forced[k] == Field::kFreeBranch ? natural : record.forced[k] != 0;
        record.record->add(taken, a.v - b.v, a.g - b.g);
        return taken;
      }
      return natural;
    };
    for (std::size_t i = 0; i < code.size(); ++i) {
      const Instruction& in = code[i];
      switch (in.op) {
        case Op::Const: new (&stack[++top]) T(in.constant); if constexpr (kLive) dep[top] = 0; break;
        case Op::X: new (&stack[++top]) T(x); if constexpr (kLive) dep[top] = 0; break;
        case Op::Y: new (&stack[++top]) T(y); if constexpr (kLive) dep[top] = 0; break;
        case Op::Z: new (&stack[++top]) T(z); if constexpr (kLive) dep[top] = 0; break;
        case Op::Add: --top; stack[top] = stack[top] + stack[top + 1]; if constexpr (kLive) dep[top] |= dep[top + 1]; break;
        case Op::Sub: --top; stack[top] = stack[top] - stack[top + 1]; if constexpr (kLive) dep[top] |= dep[top + 1]; break;
        case Op::Mul: --top; stack[top] = stack[top] * stack[top + 1]; if constexpr (kLive) dep[top] |= dep[top + 1]; break;
        case Op::Div: --top; stack[top] = stack[top] / stack[top + 1]; if constexpr (kLive) dep[top] |= dep[top + 1]; break;
        case Op::Pow: --top; stack[top] = pow(stack[top], stack[top + 1]); if constexpr (kLive) dep[top] |= dep[top + 1]; break;
        case Op::Min:
          --top;
          if constexpr (mode == Branching::Free) stack[top] = min(stack[top], stack[top + 1]);
          else if (choose(static_cast<int>(in.constant), stack[top + 1].v < stack[top].v, stack[top], stack[top + 1])) {
            stack[top] = stack[top + 1];
            if constexpr (kLive) dep[top] = dep[top + 1];
          }
          if constexpr (kLive) dep[top] |= own_bit(static_cast<int>(in.constant));
          break;
        case Op::Max:
          --top;
          if constexpr (mode == Branching::Free) stack[top] = max(stack[top], stack[top + 1]);
          else if (choose(static_cast<int>(in.constant), stack[top].v < stack[top + 1].v, stack[top], stack[top + 1])) {
            stack[top] = stack[top + 1];
            if constexpr (kLive) dep[top] = dep[top + 1];
          }
          if constexpr (kLive) dep[top] |= own_bit(static_cast<int>(in.constant));
          break;
        case Op::Neg: stack[top] = -stack[top]; break;
        case Op::PowConst: stack[top] = pow(stack[top], in.constant); break;
        case Op::Sqrt: stack[top] = sqrt(stack[top]); break;
        case Op::Exp: stack[top] = exp(stack[top]); break;
        case Op::Log: stack[top] = log(stack[top]); break;
        case Op::Sin: stack[top] = sin(stack[top]); break;
        case Op::Cos: stack[top] = cos(stack[top]); break;
        case Op::Tan: stack[top] = tan(stack[top]); break;
        case Op::Atan: stack[top] = atan(stack[top]); break;
        case Op::Atan2: --top; stack[top] = atan2(stack[top], stack[top + 1]); if constexpr (kLive) dep[top] |= dep[top + 1]; break;
        case Op::Floor: stack[top] = floor(stack[top]); break;
        case Op::Round: stack[top] = round(stack[top]); break;
        case Op::Store:
          if constexpr (kLive) dep_slot[static_cast<int>(in.constant)] = dep[top];
          new (&slot[static_cast<int>(in.constant)]) T(stack[top--]);
          break;
        case Op::Load:
          new (&stack[++top]) T(slot[static_cast<int>(in.constant)]);
          if constexpr (kLive) dep[top] = dep_slot[static_cast<int>(in.constant)];
          break;
        case Op::Abs:
          if constexpr (mode == Branching::Free) stack[top] = abs(stack[top]);
          else if (choose(static_cast<int>(in.constant), stack[top].v < 0, stack[top], -stack[top])) stack[top] = -stack[top];
          if constexpr (kLive) dep[top] |= own_bit(static_cast<int>(in.constant));
          break;
      }
      if constexpr (mode == Branching::Taped)
        static_cast<T*>(record.tape)[i] = in.op == Op::Store ? slot[static_cast<int>(in.constant)] : stack[top];
    }
    if constexpr (kLive) *record.live = dep[0];
    return stack[0];
  }
};

// One instruction's result from its operands' (a the first, b the second), computed as run
// computes it, for every operation but the leaves, the branch points, Store and Load.
template <class T>
T apply(const Instruction& in, const T& a, const T& b) {
  using std::atan, std::atan2, std::cos, std::exp, std::floor, std::log, std::pow, std::round, std::sin, std::sqrt,
      std::tan;
  switch (in.op) {
    case Op::Add: return a + b;
    case Op::Sub: return a - b;
    case Op::Mul: return a * b;
    case Op::Div: return a / b;
    case Op::Pow: return pow(a, b);
    case Op::Neg: return -a;
    case Op::PowConst: return pow(a, in.constant);
    case Op::Sqrt: return sqrt(a);
    case Op::Exp: return exp(a);
    case Op::Log: return log(a);
    case Op::Sin: return sin(a);
    case Op::Cos: return cos(a);
    case Op::Tan: return tan(a);
    case Op::Atan: return atan(a);
    case Op::Atan2: return atan2(a, b);
    case Op::Floor: return floor(a);
    case Op::Round: return round(a);
    default: return a;  // not asked for
  }
}

// How far apart two ranges must be for specialize to decide a min or max between them, relative
// to their size: far more than the rounding interval.h allows for, far less than a formula's
// own differences.
constexpr double kDecisionMargin = 1e-12;

// Which runs a specialized program (specialize) stands in for.
enum class Runs {
  Free,    // Free runs: every min and max takes what the values choose
  Forced,  // also Forced runs whose given choices agree with ExpressionProgram::fixed
};

// `program` with what cannot matter inside `region` left out: a min or max whose arguments'
// ranges over the region (interval.h) do not overlap is the code of the argument it takes there,
// an abs of an argument whose sign the range fixes is that argument or its negation, and what no
// kept instruction reads goes (a shared subexpression's Store stays while a kept Load reads it).
// A run of it at a point of the region gives the bits a run of the whole program gives: the same
// operations on the same numbers, only those whose results a min or max discarded skipped.
//
// Not where a range may hold NaN or an infinity (the root or logarithm of a range reaching below
// zero, a division by a range holding zero, a pole, an overflow): min and max let a NaN through
// on one side only, so there the argument a range takes is not the one a run takes. For Forced
// runs the range of a min or max that stays is the hull of its arguments' (a given choice may
// take either), and the choices the ranges decide are `fixed`, those left out and those in code
// left out alike (another branch given there changes the ranges after it): a run whose given
// choices take another branch at one of them runs the whole program. Kept branch points keep
// their numbers (the instructions' constants).
ExpressionProgram specialize(const ExpressionProgram& program, const Box& region, Runs runs) {
  const std::vector<Instruction>& code = program.code;
  const std::size_t n = code.size();
  std::vector<Interval> range(n);
  std::vector<char> wild(n, 0);  // may be NaN or infinite somewhere in the region
  // A min or max: the argument it takes throughout (0 or 1), an abs: 0 for +u, 1 for -u; else -1.
  std::vector<signed char> takes(n, -1);
  // x below y by more than the library functions' ulp a range of them may be off by (glibc's sin,
  // exp, ... are within an ulp, which the outward rounding only just covers).
  const auto below = [](double x, double y) { return x < y - kDecisionMargin * (std::abs(x) + std::abs(y)); };
  for (std::size_t i = 0; i < n; ++i) {
    const Instruction& in = code[i];
    const auto [a, b] = program.operands[i];
    const Interval ra = a >= 0 ? range[static_cast<std::size_t>(a)] : Interval();
    const Interval rb = b >= 0 ? range[static_cast<std::size_t>(b)] : Interval();
    bool w = (a >= 0 && wild[static_cast<std::size_t>(a)]) || (b >= 0 && wild[static_cast<std::size_t>(b)]);
    Interval r;
    switch (in.op) {
      case Op::Const: r = in.constant; break;
      case Op::X: r = {region.min.x(), region.max.x()}; break;
      case Op::Y: r = {region.min.y(), region.max.y()}; break;
      case Op::Z: r = {region.min.z(), region.max.z()}; break;
      case Op::Store: case Op::Load: r = ra; break;
      case Op::Min: case Op::Max: {
        const bool max = in.op == Op::Max;
        // The argument whose range lies wholly on the side the operation takes.
        const bool first = max ? below(rb.hi, ra.lo) : below(ra.hi, rb.lo);
        const bool second = max ? below(ra.hi, rb.lo) : below(rb.hi, ra.lo);
        if (!w) takes[i] = second ? 1 : first ? 0 : -1;
        r = takes[i] >= 0 || runs == Runs::Free ? (max ? detail::max(ra, rb) : detail::min(ra, rb)) : hull(ra, rb);
        break;
      }
      case Op::Abs:
        if (!w) takes[i] = ra.lo > 0 ? 0 : ra.hi < 0 ? 1 : -1;
        r = takes[i] >= 0 || runs == Runs::Free ? abs(ra) : hull(ra, -ra);
        break;
      default:
        r = apply(in, ra, rb);
        // A sum or product of doubles that are not negative is not negative (the outward
        // rounding reached below zero): the root of a sum of squares is defined.
        if ((in.op == Op::Add || in.op == Op::Mul) && ra.lo >= 0 && rb.lo >= 0) r.lo = std::max(r.lo, 0.0);
        // The interval functions bound a root and a power only where they are defined.
        if (in.op == Op::Sqrt) w = w || ra.lo < 0;
        if (in.op == Op::Log || in.op == Op::Pow) w = w || !(ra.lo > 0);
        if (in.op == Op::PowConst) w = w || (ra.lo < 0 && in.constant != std::round(in.constant));
        break;
    }
    wild[i] = w || !std::isfinite(r.lo) || !std::isfinite(r.hi);
    range[i] = r;
  }
  // Backwards from the value: a min or max that takes one argument reads that one only.
  std::vector<char> live(n, 0);
  if (program.result >= 0) live[static_cast<std::size_t>(program.result)] = 1;
  for (std::size_t i = n; i-- > 0;) {
    if (!live[i]) continue;
    const auto [a, b] = program.operands[i];
    if ((code[i].op == Op::Min || code[i].op == Op::Max) && takes[i] >= 0) {
      live[static_cast<std::size_t>(takes[i] == 1 ? b : a)] = 1;
      continue;
    }
    if (a >= 0) live[static_cast<std::size_t>(a)] = 1;
    if (b >= 0) live[static_cast<std::size_t>(b)] = 1;
  }
  // A min or max taken out leaves the argument it takes where it would have left its result.
  ExpressionProgram out;
  out.slots = program.slots;
  for (std::size_t i = 0; i < n; ++i) {
    if (takes[i] >= 0) {
      // Fixed whether its code is left out or not: another choice given there changes the ranges
      // after it.
      out.fixed.emplace_back(program.branch_number[i], static_cast<std::uint8_t>(takes[i]));
      if (live[i] && code[i].op == Op::Abs && takes[i] == 1) out.code.push_back({Op::Neg});
      continue;
    }
    if (live[i]) out.code.push_back(code[i]);
  }
  return out;
}

// Fewer branch points than this, and a formula is run whole everywhere: a few min, max and abs
// (a rounded box) save less than finding the cell costs.
constexpr int kRegionBranchPoints = 4;

// The program specialized (specialize) to each cell of a grid over the field's box, made once the
// cell has been evaluated often enough (kEvaluationsFirst). A formula of many primitives (a union of 48 twisted boxes)
// is, near any point, the formula of a few of them.
class RegionPrograms {
 public:
  RegionPrograms(const ExpressionProgram& full, const Box& box) : full_(full), box_(box) {
    const Vec3 size = box.size();
    const double edge = std::cbrt(size.prod() / kCells);
    std::size_t count = 1;
    for (int k = 0; k < 3; ++k) {
      n_[k] = std::clamp(static_cast<int>(std::lround(size[k] / edge)), 1, kMaxPerAxis);
      cell_[k] = size[k] / n_[k];
      count *= static_cast<std::size_t>(n_[k]);
    }
    for (auto& cells : cells_) cells = std::vector<Cell>(count);
  }

  // The program a run of kind `runs` at p may run: its cell's, or the whole one outside the box
  // (or at NaN).
  const ExpressionProgram& at(const Vec3& p, Runs runs) const {
    std::size_t index = 0;
    int c[3];
    for (int k = 0; k < 3; ++k) {
      const double t = (p[k] - box_.min[k]) / cell_[k];
      if (!(t >= 0 && t < n_[k])) return full_;
      c[k] = static_cast<int>(t);
      index = index * static_cast<std::size_t>(n_[k]) + static_cast<std::size_t>(c[k]);
    }
    Cell& cell = cells_[static_cast<int>(runs)][index];
    if (const ExpressionProgram* made = cell.program.load(std::memory_order_acquire)) return *made;
    // Counted without a lock: a count lost between threads only specializes the cell later.
    const std::uint32_t seen = cell.evaluations.load(std::memory_order_relaxed) + 1;
    cell.evaluations.store(seen, std::memory_order_relaxed);
    return seen < kEvaluationsFirst ? full_ : make(cell, c, runs);
  }

  // For a Forced run with the choices `forced`: its cell's program if they agree with what it fixed.
  const ExpressionProgram& at(const Vec3& p, const std::uint8_t* forced) const {
    const ExpressionProgram& cell = at(p, Runs::Forced);
    for (const auto& [k, choice] : cell.fixed)
      if (forced[k] != Field::kFreeBranch && forced[k] != choice) return full_;
    return cell;
  }

 private:
  // About this many cells over the box, cubes as near as its shape allows.
  static constexpr double kCells = 4096;
  static constexpr int kMaxPerAxis = 64;
  // A cell keeps a program of its own only when it is this much shorter than the whole one.
  static constexpr double kShorter = 0.8;
  // Evaluations in a cell before it is specialized, which costs a few runs of the whole program
  // with intervals: the seed grid samples every cell of the box a few times, and a small model
  // (three boxes as stairs, 0.03 s) took 1.7 times as long when each cell was specialized at its
  // first evaluation.
  static constexpr std::uint32_t kEvaluationsFirst = 64;
  // Bytes of the cells' programs at most (their code at 16 bytes an instruction, and their fixed
  // choices): past them a cell runs the whole formula. fogleman/sdf's knurling (1,702
  // instructions; its cells' programs about 700 for plain runs, 1,100 for Forced ones) fills them
  // with about 2,000 programs.
  static constexpr std::size_t kMaxKept = std::size_t{32} << 20;

  struct Cell {
    std::atomic<const ExpressionProgram*> program{nullptr};  // made: the cell's, or the whole one
    std::atomic<std::uint32_t> evaluations{0};                // before it was made
  };

  const ExpressionProgram& make(Cell& slot, const int c[3], Runs runs) const {
    Box cell;
    for (int k = 0; k < 3; ++k) {
      // Widened by a hair: a point the division above put in the cell may lie a rounding outside
      // it, and the cell's corners are rounded (by up to an ulp of the box's coordinates).
      const double margin = 1e-9 * cell_[k] + 1e-15 * (std::abs(box_.min[k]) + std::abs(box_.max[k]));
      cell.min[k] = box_.min[k] + c[k] * cell_[k] - margin;
      cell.max[k] = box_.min[k] + (c[k] + 1) * cell_[k] + margin;
    }
    // Past the bound, the cells left run the whole formula without being specialized first.
    ExpressionProgram special = kept_.load(std::memory_order_relaxed) < kMaxKept ? specialize(full_, cell, runs)
                                                                                  : ExpressionProgram{};
    const ExpressionProgram* program = &full_;
    std::lock_guard lock(mutex_);
    if (const ExpressionProgram* made = slot.program.load(std::memory_order_acquire)) return *made;
    const std::size_t kept = kept_.load(std::memory_order_relaxed);
    special.code.shrink_to_fit();
    special.fixed.shrink_to_fit();
    const std::size_t bytes = special.code.size() * sizeof(Instruction) + special.fixed.size() * sizeof(special.fixed[0]);
    if (!special.code.empty() && kept + bytes <= kMaxKept &&
        static_cast<double>(special.code.size()) <= kShorter * static_cast<double>(full_.code.size())) {
      kept_.store(kept + bytes, std::memory_order_relaxed);
      program = owned_.emplace_back(std::make_unique<ExpressionProgram>(std::move(special))).get();
    }
    slot.program.store(program, std::memory_order_release);
    return *program;
  }

  const ExpressionProgram& full_;
  Box box_;
  int n_[3];
  Vec3 cell_;
  mutable std::array<std::vector<Cell>, 2> cells_;  // by Runs
  mutable std::mutex mutex_;
  mutable std::vector<std::unique_ptr<ExpressionProgram>> owned_;
  mutable std::atomic<std::size_t> kept_{0};  // bytes in owned_ (written under mutex_)
};

namespace {

struct Node {
  Op op;
  double constant = 0;
  std::vector<Node> args;
  int height = 1;  // of the tree below, this node included
  bool is_constant() const { return op == Op::Const; }
};

// The named sub-expressions of a formula: parsed when first used (so they may refer to each other
// in any order), their code emitted once, ahead of the formula's, into a slot each.
struct Definitions {
  struct Entry {
    const std::string* text;
    enum class State { Unused, Parsing, Done } state = State::Unused;
    double constant = 0;  // a definition without x, y, z is folded to its value
    bool is_constant = false;
    int slot = -1;
  };
  std::map<std::string, Entry> entries;
  std::vector<Instruction> code;  // the definitions used, each followed by its Store
  int slots = 0;
};

// Emits a tree's code with each subtree written more than once computed once: the first copy
// is stored into a slot (and loaded back), the others load it. A smooth union written out by
// hand repeats its clamp at each of its three uses, and mod repeats its dividend: as copies,
// each min, max and abs of them would be a branch point of its own, which Field::branch_kinds
// classifies and pieces() splits apart independently (the flat smooth union at factor 3 traced
// 148 crease curves where two copies switch at different points of the same seam, then fell
// back); shared, the copies are one branch point. The values are the same bits either way.
// Slots beyond kMaxDefinitions (shared with the named sub-expressions) are not taken: the
// copies are then emitted as written.
class SharedEmitter {
 public:
  SharedEmitter(std::vector<Instruction>& code, int& slots) : code_(code), slots_(slots) {}

  void emit(const Node& root) {
    number(root);
    count(root);
    out(root);
  }

 private:
  // The three passes walk the tree with stacks of their own: a formula may be kMaxHeight
  // operations deep, more than the call stack holds frames of these (under the sanitizers).
  struct Frame {
    const Node* node;
    std::size_t next = 0;  // the next argument to visit
  };

  // Structurally equal subtrees get the same number (children first).
  void number(const Node& root) {
    std::vector<Frame> stack{{&root}};
    while (!stack.empty()) {
      Frame& f = stack.back();
      const Node& n = *f.node;
      if (f.next < n.args.size()) {
        const Node* child = &n.args[f.next++];
        stack.push_back({child});
        continue;
      }
      std::uint64_t bits;
      static_assert(sizeof bits == sizeof n.constant);
      std::memcpy(&bits, &n.constant, sizeof bits);
      std::vector<int> key{static_cast<int>(n.op), static_cast<int>(bits & 0xffffffffu), static_cast<int>(bits >> 32)};
      for (const Node& a : n.args) key.push_back(id_.at(&a));
      const auto [it, added] = numbers_.try_emplace(std::move(key), static_cast<int>(numbers_.size()));
      id_[&n] = it->second;
      stack.pop_back();
    }
  }
  // Uses of each subtree, a repeated copy's insides counted with its first copy only.
  void count(const Node& root) {
    std::vector<const Node*> stack{&root};
    while (!stack.empty()) {
      const Node* n = stack.back();
      stack.pop_back();
      if (uses_[id_.at(n)]++ > 0) continue;
      for (auto it = n->args.rbegin(); it != n->args.rend(); ++it) stack.push_back(&*it);
    }
  }
  void out(const Node& root) {
    std::vector<Frame> stack{{&root}};
    while (!stack.empty()) {
      Frame& f = stack.back();
      const Node& n = *f.node;
      const int id = id_.at(&n);
      const bool shared = !n.args.empty() && uses_[id] > 1;
      if (f.next == 0 && shared) {
        if (const auto it = slot_.find(id); it != slot_.end()) {
          code_.push_back({Op::Load, static_cast<double>(it->second)});
          stack.pop_back();
          continue;
        }
      }
      if (f.next < n.args.size()) {
        const Node* child = &n.args[f.next++];
        stack.push_back({child});
        continue;
      }
      code_.push_back({n.op, n.constant});
      if (shared && slots_ < kMaxDefinitions) {
        const int slot = slots_++;
        slot_[id] = slot;
        code_.push_back({Op::Store, static_cast<double>(slot)});
        code_.push_back({Op::Load, static_cast<double>(slot)});
      }
      stack.pop_back();
    }
  }

  std::vector<Instruction>& code_;
  int& slots_;
  std::map<std::vector<int>, int> numbers_;
  std::map<const Node*, int> id_;
  std::map<int, int> uses_;
  std::map<int, int> slot_;
};

// Recursive-descent parser:
//   expr  := term (('+' | '-') term)*
//   term  := unary (('*' | '/') unary)*
//   unary := ('-' | '+') unary | power
//   power := primary (('^' | '**') unary)?   right-associative, binds tighter than unary minus
//   primary := number | name | name '(' expr (',' expr)* ')' | '(' expr ')'
class Parser {
 public:
  Parser(const std::string& text, const std::map<std::string, double>& params, Definitions& definitions,
         std::string where = "")
      : s_(text), params_(params), definitions_(definitions), where_(std::move(where)) {}

  Node parse() {
    Node n = expr();
    skip_space();
    if (pos_ < s_.size()) error(std::string("unexpected '") + s_[pos_] + "'");
    return n;
  }

 private:
  [[noreturn]] void error(const std::string& what) const {
    throw InvalidInputError("expression: " + where_ + what + " at position " + std::to_string(pos_ + 1));
  }
  void skip_space() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }
  bool accept(char c) {
    skip_space();
    if (pos_ < s_.size() && s_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  void expect(char c) {
    if (!accept(c)) {
      skip_space();
      error(std::string("expected '") + c + "'" +
            (pos_ < s_.size() ? std::string(", found '") + s_[pos_] + "'" : ", found the end"));
    }
  }

  Node binary(Op op, Node a, Node b) {
    std::vector<Node> args;
    args.push_back(std::move(a));
    args.push_back(std::move(b));
    return node(op, std::move(args));
  }
  Node unary_node(Op op, Node a) {
    std::vector<Node> args;
    args.push_back(std::move(a));
    return node(op, std::move(args));
  }
  Node node(Op op, std::vector<Node> args) {
    Node n{op, 0, std::move(args)};
    for (const auto& a : n.args) n.height = std::max(n.height, a.height + 1);
    if (n.height > kMaxHeight)
      error("formula nested too deeply (more than " + std::to_string(kMaxHeight) + " operations in a row)");
    return fold(std::move(n));
  }
  // Constant subtrees become one constant; x^c becomes PowConst so that negative bases with
  // integer exponents stay exact.
  static Node fold(Node n) {
    bool all_const = !n.args.empty();
    for (const auto& a : n.args) all_const = all_const && a.is_constant();
    if (all_const) {
      ExpressionProgram p;
      emit(n, p.code);
      return Node{Op::Const, p.run(0.0, 0.0, 0.0), {}};
    }
    if (n.op == Op::Pow && n.args[1].is_constant()) {
      Node r{Op::PowConst, n.args[1].constant, {}, n.height};
      r.args.push_back(std::move(n.args[0]));
      return r;
    }
    return n;
  }

  Node expr() {
    Node n = term();
    for (;;) {
      if (accept('+')) n = binary(Op::Add, std::move(n), term());
      else if (accept('-')) n = binary(Op::Sub, std::move(n), term());
      else return n;
    }
  }
  Node term() {
    Node n = unary();
    for (;;) {
      if (accept('*')) n = binary(Op::Mul, std::move(n), unary());
      else if (accept('/')) n = binary(Op::Div, std::move(n), unary());
      else return n;
    }
  }
  // Every level of nesting passes here: parentheses and calls (through expr), signs, exponents.
  Node unary() {
    if (++nesting_ > kMaxNesting)
      error("formula nested too deeply (more than " + std::to_string(kMaxNesting) +
            " levels of parentheses, calls, signs and exponents)");
    Node n = signed_power();
    --nesting_;
    return n;
  }
  Node signed_power() {
    if (accept('-')) return unary_node(Op::Neg, unary());
    if (accept('+')) return unary();
    return power();
  }
  Node power() {
    Node base = primary();
    skip_space();
    if (s_.compare(pos_, 2, "**") == 0) {
      pos_ += 2;
      return binary(Op::Pow, std::move(base), unary());
    }
    if (accept('^')) return binary(Op::Pow, std::move(base), unary());
    return base;
  }
  Node primary() {
    skip_space();
    if (pos_ >= s_.size()) error("unexpected end of formula");
    const char c = s_[pos_];
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') {
      const char* begin = s_.c_str() + pos_;
      char* end = nullptr;
      const double v = std::strtod(begin, &end);
      if (end == begin) error("malformed number");
      pos_ += static_cast<std::size_t>(end - begin);
      return Node{Op::Const, v, {}};
    }
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
      const std::size_t start = pos_;
      while (pos_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_')) ++pos_;
      const std::string name = s_.substr(start, pos_ - start);
      skip_space();
      if (pos_ < s_.size() && s_[pos_] == '(') return call(name, start);
      if (name == "x") return Node{Op::X, 0, {}};
      if (name == "y") return Node{Op::Y, 0, {}};
      if (name == "z") return Node{Op::Z, 0, {}};
      if (name == "pi") return Node{Op::Const, std::numbers::pi, {}};
      if (auto it = params_.find(name); it != params_.end()) return Node{Op::Const, it->second, {}};
      if (auto it = definitions_.entries.find(name); it != definitions_.entries.end()) return use(name, it->second, start);
      pos_ = start;
      error("unknown name '" + name + "'");
    }
    if (accept('(')) {
      Node n = expr();
      expect(')');
      return n;
    }
    error(std::string("unexpected '") + c + "'");
  }
  // A named sub-expression: its code emitted the first time, a load of its slot each time.
  Node use(const std::string& name, Definitions::Entry& e, std::size_t name_pos) {
    using State = Definitions::Entry::State;
    if (e.state == State::Parsing) {
      pos_ = name_pos;
      error("definition '" + name + "' refers to itself");
    }
    if (e.state == State::Unused) {
      e.state = State::Parsing;
      Parser inner(*e.text, params_, definitions_, "in definition '" + name + "': ");
      inner.nesting_ = nesting_;
      Node n = inner.parse();
      if (n.is_constant()) {
        e.is_constant = true;
        e.constant = n.constant;
      } else {
        if (definitions_.slots >= kMaxDefinitions)
          error("more than " + std::to_string(kMaxDefinitions) + " definitions in use");
        SharedEmitter(definitions_.code, definitions_.slots).emit(n);
        if (definitions_.slots >= kMaxDefinitions)
          error("more than " + std::to_string(kMaxDefinitions) + " definitions in use");
        e.slot = definitions_.slots++;
        definitions_.code.push_back({Op::Store, static_cast<double>(e.slot)});
      }
      e.state = State::Done;
    }
    if (e.is_constant) return Node{Op::Const, e.constant, {}};
    return Node{Op::Load, static_cast<double>(e.slot), {}};
  }

  Node call(const std::string& name, std::size_t name_pos) {
    // Arity -1: two or more arguments (min, max, hypot fold them pairwise from the left).
    static const std::map<std::string, std::pair<Op, int>> functions = {
        {"sqrt", {Op::Sqrt, 1}},   {"exp", {Op::Exp, 1}},       {"log", {Op::Log, 1}},     {"sin", {Op::Sin, 1}},
        {"cos", {Op::Cos, 1}},     {"tan", {Op::Tan, 1}},       {"atan", {Op::Atan, 1}},   {"floor", {Op::Floor, 1}},
        {"round", {Op::Round, 1}}, {"abs", {Op::Abs, 1}},       {"min", {Op::Min, -1}},    {"max", {Op::Max, -1}},
        {"pow", {Op::Pow, 2}},     {"atan2", {Op::Atan2, 2}},   {"mod", {Op::Floor, 2}},   {"hypot", {Op::Sqrt, -1}},
        {"clamp", {Op::Min, 3}}};
    auto it = functions.find(name);
    if (it == functions.end()) {
      pos_ = name_pos;
      error("unknown function '" + name + "'");
    }
    expect('(');
    std::vector<Node> args;
    args.push_back(expr());
    while (accept(',')) args.push_back(expr());
    const std::size_t close = pos_;
    expect(')');
    const int arity = it->second.second;
    if (arity > 0 ? static_cast<int>(args.size()) != arity : args.size() < 2) {
      pos_ = close;
      error(name + " takes " + (arity > 0 ? std::to_string(arity) : std::string("two or more")) +
            " arguments, found " + std::to_string(args.size()));
    }
    if (name == "clamp") {  // clamp(u, lo, hi) = min(max(u, lo), hi): two branch points
      Node lo_clamped = binary(Op::Max, std::move(args[0]), std::move(args[1]));
      return binary(Op::Min, std::move(lo_clamped), std::move(args[2]));
    }
    if (name == "mod") {  // mod(a, b) = a - b floor(a / b), the sign of b (GLSL's)
      Node a = args[0], b = args[1];
      Node q = unary_node(Op::Floor, binary(Op::Div, std::move(args[0]), std::move(args[1])));
      return binary(Op::Sub, std::move(a), binary(Op::Mul, std::move(b), std::move(q)));
    }
    if (name == "hypot") {  // sqrt(a^2 + b^2 + ...)
      Node sum = square(std::move(args[0]));
      for (std::size_t i = 1; i < args.size(); ++i) sum = binary(Op::Add, std::move(sum), square(std::move(args[i])));
      return unary_node(Op::Sqrt, std::move(sum));
    }
    if (arity < 0) {  // min, max
      Node n = std::move(args[0]);
      for (std::size_t i = 1; i < args.size(); ++i) n = binary(it->second.first, std::move(n), std::move(args[i]));
      return n;
    }
    return node(it->second.first, std::move(args));
  }
  Node square(Node a) {
    Node two{Op::Const, 2.0, {}};
    return binary(Op::Pow, std::move(a), std::move(two));
  }

 public:
  static void emit(const Node& n, std::vector<Instruction>& code) {
    for (const auto& a : n.args) emit(a, code);
    code.push_back({n.op, n.constant});
  }

 private:
  const std::string& s_;
  const std::map<std::string, double>& params_;
  Definitions& definitions_;
  std::string where_;
  std::size_t pos_ = 0;
  int nesting_ = 0;
};

}  // namespace
}  // namespace detail

Expression::Expression(const std::string& formula, const std::map<std::string, double>& params, const Box& bounds,
                       const std::map<std::string, std::string>& definitions)
    : formula_(formula), program_(std::make_unique<detail::ExpressionProgram>()) {
  const auto built_in = [](const std::string& name) { return name == "x" || name == "y" || name == "z" || name == "pi"; };
  for (const auto& [name, v] : params) {
    if (built_in(name)) throw InvalidInputError("expression: parameter '" + name + "' shadows a built-in name");
    if (!std::isfinite(v)) throw InvalidInputError("expression: parameter '" + name + "' is not finite");
  }
  detail::Definitions defs;
  for (const auto& [name, text] : definitions) {
    const bool word = !name.empty() && !std::isdigit(static_cast<unsigned char>(name[0])) &&
                      std::all_of(name.begin(), name.end(),
                                  [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
    if (!word) throw InvalidInputError("expression: definition name '" + name + "' is not a name (letters, digits, _)");
    if (built_in(name)) throw InvalidInputError("expression: definition '" + name + "' shadows a built-in name");
    if (params.count(name)) throw InvalidInputError("expression: '" + name + "' is both a parameter and a definition");
    defs.entries[name].text = &text;
  }
  detail::Parser parser(formula_, params, defs);
  const detail::Node root = parser.parse();
  program_->code = std::move(defs.code);
  detail::SharedEmitter(program_->code, defs.slots).emit(root);
  program_->slots = defs.slots;
  program_->link();
  if (program_->depth > detail::kMaxStack)
    throw InvalidInputError("expression: formula nested too deeply (more than " +
                            std::to_string(detail::kMaxStack) + " pending operands)");
  if (!bounds.valid()) throw InvalidInputError("expression: bounds must be a non-empty box");
  set_bounds(bounds);
  if (program_->branch_points >= detail::kRegionBranchPoints)
    regions_ = std::make_unique<detail::RegionPrograms>(*program_, bounds);
}

Expression::~Expression() = default;

std::optional<std::pair<double, double>> Expression::value_range(const Box& region) const {
  using detail::Interval;
  const Interval r = program_->run(Interval(region.min.x(), region.max.x()), Interval(region.min.y(), region.max.y()),
                                   Interval(region.min.z(), region.max.z()));
  if (!r.known()) return Interval::entire_pair();
  return std::pair{r.lo, r.hi};
}

std::optional<std::pair<double, double>> Expression::derivative_range(const Box& region, const Vec3& direction) const {
  using detail::Interval, detail::IntervalDual;
  const auto axis = [&](int i) {
    return IntervalDual(Interval(region.min[i], region.max[i]), Interval(direction[i]));
  };
  const Interval d = program_->run(axis(0), axis(1), axis(2)).d;
  if (!d.known()) return Interval::entire_pair();
  return std::pair{d.lo, d.hi};
}

const detail::ExpressionProgram& Expression::program_at(const Vec3& p, const std::uint8_t* forced) const {
  // A trace of the branches taken (autodiff.h) sees every branch point of the whole program.
  if (!regions_ || detail::active_branch_trace) return *program_;
  return forced ? regions_->at(p, forced) : regions_->at(p, detail::Runs::Free);
}

std::size_t Expression::instructions_at(const Vec3& p) const { return program_at(p).code.size(); }

std::size_t Expression::instructions_at(const Vec3& p, const std::vector<std::uint8_t>& branch) const {
  check_branch(branch);
  return program_at(p, branch.data()).code.size();
}

std::size_t Expression::instructions() const { return program_->code.size(); }

double Expression::eval_value(const Vec3& p) const { return program_at(p).run(p.x(), p.y(), p.z()); }

double Expression::eval_value_gradient(const Vec3& p, Vec3& gradient) const {
  const Jet1 r = program_at(p).run(Jet1::variable(p.x(), 0), Jet1::variable(p.y(), 1), Jet1::variable(p.z(), 2));
  gradient = r.g;
  return r.v;
}

double Expression::eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const {
  const Jet2 r = program_at(p).run(Jet2::variable(p.x(), 0), Jet2::variable(p.y(), 1), Jet2::variable(p.z(), 2));
  gradient = r.g;
  hessian = r.h;
  return r.v;
}

bool Expression::has_branch_points() const { return program_->branch_points > 0; }

bool Expression::eval_branch_record(const Vec3& p, const std::vector<std::uint8_t>& branch,
                                    BranchRecord& record) const {
  if (program_->branch_points == 0) return false;
  if (!branch.empty()) check_branch(branch);
  // One allocation each, not one per doubling: a record is made at every point crease tracing visits.
  const auto n = static_cast<std::size_t>(program_->branch_points);
  record.taken.reserve(n);
  record.distance.reserve(n);
  record.seam_step.reserve(n);
  record.seam_normal.reserve(n);
  const Jet1 natural = program_->run<Jet1, detail::Branching::Record>(
      Jet1::variable(p.x(), 0), Jet1::variable(p.y(), 1), Jet1::variable(p.z(), 2), detail::BranchLog{branch.empty() ? nullptr : branch.data(), &record});
  record.value = natural.v;
  record.gradient = natural.g;
  return true;
}

void Expression::check_branch(const std::vector<std::uint8_t>& branch) const {
  if (branch.size() != static_cast<std::size_t>(program_->branch_points))
    throw InvalidInputError("expression: a piece's branch has " + std::to_string(branch.size()) +
                            " choices, the formula " + std::to_string(program_->branch_points) + " branch points");
  for (const std::uint8_t b : branch)
    if (b > kFreeBranch) throw InvalidInputError("expression: a piece's branch has a choice " + std::to_string(b));
}

std::pair<double, Vec3> Expression::eval_first_order(const Vec3& p, const std::vector<std::uint8_t>& branch) const {
  check_branch(branch);
  const Jet1 r = program_at(p, branch.data())
                     .run<Jet1, detail::Branching::Forced>(Jet1::variable(p.x(), 0), Jet1::variable(p.y(), 1),
                                                           Jet1::variable(p.z(), 2),
                                                           detail::BranchLog{branch.data(), nullptr});
  return {r.v, r.g};
}

namespace detail {
namespace {

// A run of the program kept instruction by instruction (Taped), and choices flipped on it: a flip
// recomputes only the instructions its choice reaches (the consumers of what changed, in program
// order; a min or max whose choice is given passes on a change of the argument it takes only),
// each from its operands' results, the same operations on the same numbers, so the same bits as
// a run with the choice flipped. Kept (commit), the flip's results replace the run's. A knurled
// cylinder's pieces (1,702 instructions) test a few dozen choices each, and up to 64
// combinations of the choices near a point: a run each before. One FlipRun at a time on a thread
// (its buffers are the thread's).
class FlipRun {
 public:
  FlipRun(const ExpressionProgram& program, std::vector<std::uint8_t>& branch, const Vec3& p)
      : program_(program), branch_(branch), x_(Jet1::variable(p.x(), 0)), y_(Jet1::variable(p.y(), 1)),
        z_(Jet1::variable(p.z(), 2)) {
    const std::size_t n = program.code.size();
    tape_.resize(n);
    flipped_.resize(n);
    state_.assign(n, kSame);
    queued_.assign((n + 63) / 64, 0);
    run();
  }

  // A run with the branch as it stands (after a choice was changed otherwise than by commit).
  void run() {
    BranchLog log{branch_.data(), nullptr};
    log.tape = tape_.data();
    program_.run<Jet1, Branching::Taped>(x_, y_, z_, log);
  }
  const Jet1& value() const { return tape_[static_cast<std::size_t>(program_.result)]; }

  // The value with choice k flipped (0 <-> 1), the run left as it was until commit or discard.
  const Jet1& flip(std::size_t k) {
    const auto m = static_cast<std::size_t>(program_.branch_instruction[k]);
    const auto& [a, b] = program_.operands[m];
    const std::uint8_t c = branch_[k];
    flipped_[m] = program_.code[m].op == Op::Abs ? (c == 0 ? -tape_[a] : tape_[a]) : tape_[c == 0 ? b : a];
    flipped_k_ = k;
    change(m);
    // The queued instructions in program order: a consumer comes after what it consumes, so the
    // bits set while one is recomputed lie ahead of it.
    for (std::size_t w = m / 64; w < queued_.size();) {
      const std::uint64_t bits = queued_[w];
      if (bits == 0) {
        ++w;
        continue;
      }
      queued_[w] = bits & (bits - 1);
      const std::size_t i = w * 64 + static_cast<std::size_t>(std::countr_zero(bits));
      const Instruction& in = program_.code[i];
      const auto& [u, v] = program_.operands[i];
      if (const int bn = program_.branch_number[i]; bn >= 0) {
        const std::uint8_t choice = branch_[static_cast<std::size_t>(bn)];
        const bool second = takes_second(i, choice);
        if (in.op == Op::Abs) {
          flipped_[i] = second ? -at(u) : at(u);
        } else {
          const int taken = second ? v : u;
          if (choice != Field::kFreeBranch && state_[static_cast<std::size_t>(taken)] != kChanged) {
            state_[i] = kSame;
            continue;
          }
          flipped_[i] = at(taken);
        }
      } else if (in.op == Op::Store || in.op == Op::Load) {
        flipped_[i] = at(u);
      } else {
        flipped_[i] = apply(in, at(u), v >= 0 ? at(v) : at(u));
      }
      change(i);
    }
    return at(program_.result);
  }
  void commit() {
    for (const int t : touched_) {
      if (state_[static_cast<std::size_t>(t)] == kChanged) tape_[static_cast<std::size_t>(t)] = flipped_[t];
      state_[static_cast<std::size_t>(t)] = kSame;
    }
    touched_.clear();
    branch_[flipped_k_] ^= 1u;
  }
  void discard() {
    for (const int t : touched_) state_[static_cast<std::size_t>(t)] = kSame;
    touched_.clear();
  }

  // Makes choice k kFreeBranch, and runs again if the values choose otherwise than it did.
  void free(std::size_t k) {
    const std::uint8_t c = branch_[k];
    branch_[k] = Field::kFreeBranch;
    if (takes_second(static_cast<std::size_t>(program_.branch_instruction[k]), Field::kFreeBranch) != (c != 0)) run();
  }

 private:
  enum : std::uint8_t { kSame, kQueued, kChanged };
  const Jet1& at(int i) const {
    return state_[static_cast<std::size_t>(i)] == kChanged ? flipped_[static_cast<std::size_t>(i)]
                                                           : tape_[static_cast<std::size_t>(i)];
  }
  // Whether branch point i takes its second argument (-u for abs) with choice c and its
  // operands as they stand (kFreeBranch: as run's choose takes them).
  bool takes_second(std::size_t i, std::uint8_t c) const {
    if (c != Field::kFreeBranch) return c != 0;
    const auto& [a, b] = program_.operands[i];
    switch (program_.code[i].op) {
      case Op::Min: return at(b).v < at(a).v;
      case Op::Max: return at(a).v < at(b).v;
      default: return at(a).v < 0;  // abs
    }
  }
  void change(std::size_t i) {
    if (state_[i] == kSame) touched_.push_back(static_cast<int>(i));
    state_[i] = kChanged;
    for (int c = program_.consumer_start[i]; c < program_.consumer_start[i + 1]; ++c) {
      const auto j = static_cast<std::size_t>(program_.consumers_of[static_cast<std::size_t>(c)]);
      if (state_[j] != kSame) continue;
      state_[j] = kQueued;
      touched_.push_back(static_cast<int>(j));
      queued_[j / 64] |= std::uint64_t{1} << (j % 64);
    }
  }

  const ExpressionProgram& program_;
  std::vector<std::uint8_t>& branch_;
  Jet1 x_, y_, z_;
  std::size_t flipped_k_ = 0;
  // Per thread, reused: a run of a large formula per piece would otherwise allocate its tape.
  static thread_local std::vector<Jet1> tape_, flipped_;
  static thread_local std::vector<std::uint8_t> state_;
  static thread_local std::vector<std::uint64_t> queued_;  // a bit an instruction
  static thread_local std::vector<int> touched_;
};

thread_local std::vector<Jet1> FlipRun::tape_, FlipRun::flipped_;
thread_local std::vector<std::uint8_t> FlipRun::state_;
thread_local std::vector<std::uint64_t> FlipRun::queued_;
thread_local std::vector<int> FlipRun::touched_;

}  // namespace
}  // namespace detail

void Expression::eval_first_order_flips(const Vec3& p, std::vector<std::uint8_t>& branch,
                                        std::span<const ChoiceStep> steps,
                                        const std::function<bool(double, const Vec3&)>& hidden) const {
  check_branch(branch);
  if (program_->result < 0) return Field::eval_first_order_flips(p, branch, steps, hidden);
  detail::FlipRun run(*program_, branch, p);
  for (const ChoiceStep& step : steps) {
    const auto k = static_cast<std::size_t>(step.choice);
    if (step.flip) {
      const Jet1& r = run.flip(k);
      const bool is_hidden = hidden(r.v, r.g);
      run.discard();
      if (!is_hidden) continue;
    }
    run.free(k);
  }
}

void Expression::eval_first_order_combinations(const Vec3& p, const std::vector<std::uint8_t>& base,
                                               std::span<const int> split,
                                               std::vector<std::pair<double, Vec3>>& out) const {
  check_branch(base);
  if (program_->result < 0 || split.size() >= 64) return Field::eval_first_order_combinations(p, base, split, out);
  // In Gray code order each combination is the one before with one choice flipped, kept.
  std::vector<std::uint8_t> branch = base;
  detail::FlipRun run(*program_, branch, p);
  const std::size_t combinations = std::size_t{1} << split.size();
  out.assign(combinations, {});
  out[0] = {run.value().v, run.value().g};
  for (std::size_t g = 1; g < combinations; ++g) {
    const Jet1& r = run.flip(static_cast<std::size_t>(split[static_cast<std::size_t>(std::countr_zero(g))]));
    out[g ^ (g >> 1)] = {r.v, r.g};
    run.commit();
  }
}

bool Expression::eval_piece_live(const Vec3& p, const std::vector<std::uint8_t>& branch, const std::int8_t* bits,
                                 bool hessian, FieldPiece& piece, std::uint64_t& live) const {
  check_branch(branch);
  const detail::BranchLog log{branch.data(), nullptr, bits, &live};
  if (hessian) {
    const Jet2 r = program_->run<Jet2, detail::Branching::ForcedLive>(
        Jet2::variable(p.x(), 0), Jet2::variable(p.y(), 1), Jet2::variable(p.z(), 2), log);
    piece.value = r.v;
    piece.gradient = r.g;
    piece.hessian = r.h;
  } else {
    const Jet1 r = program_->run<Jet1, detail::Branching::ForcedLive>(
        Jet1::variable(p.x(), 0), Jet1::variable(p.y(), 1), Jet1::variable(p.z(), 2), log);
    piece.value = r.v;
    piece.gradient = r.g;
  }
  return true;
}

bool Expression::choices_reaching(const std::vector<std::uint8_t>& branch, std::vector<std::uint8_t>& reaches) const {
  check_branch(branch);
  const detail::ExpressionProgram& program = *program_;
  std::vector<std::uint8_t> live(program.code.size(), 0);
  if (program.result >= 0) live[static_cast<std::size_t>(program.result)] = 1;
  reaches.assign(branch.size(), 0);
  // Backwards from the value: a min or max with its choice given passes on the argument it takes
  // only; one whose values choose, both (a change on either side may change what they choose).
  for (std::size_t i = program.code.size(); i-- > 0;) {
    if (!live[i]) continue;
    const int k = program.branch_number[i];
    if (k >= 0) reaches[static_cast<std::size_t>(k)] = 1;
    const detail::Op op = program.code[i].op;
    const std::uint8_t choice = k >= 0 && op != detail::Op::Abs ? branch[static_cast<std::size_t>(k)] : kFreeBranch;
    for (int a = 0; a < 2; ++a) {
      const int from = program.operands[i][static_cast<std::size_t>(a)];
      if (from >= 0 && (choice == kFreeBranch || choice == a)) live[static_cast<std::size_t>(from)] = 1;
    }
  }
  return true;
}

FieldPiece Expression::eval_piece(const Vec3& p, const std::vector<std::uint8_t>& branch) const {
  check_branch(branch);
  const Jet2 r = program_at(p, branch.data()).run<Jet2, detail::Branching::Forced>(
      Jet2::variable(p.x(), 0), Jet2::variable(p.y(), 1), Jet2::variable(p.z(), 2),
      detail::BranchLog{branch.data(), nullptr});
  return piece_from_jet(branch, r);
}

}  // namespace cdp
