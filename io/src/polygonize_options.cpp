#include <cdp/io/polygonize_options.h>

#include <cdp/core/errors.h>
#include <cdp/io/json_reader.h>

#include <algorithm>
#include <climits>
#include <charconv>
#include <cmath>
#include <stdexcept>

namespace cdp {
namespace {

// The help texts are the program's; Python's docstring and the README list the same table.
const std::vector<OptionSpec>& table() {
  static const std::vector<OptionSpec> options = {
      {"factor", OptionKind::Number, OptionMethods::Adaptive, "K", "2", "sizing", {}, {}, 0, 0,
       "edge = minimum radius of curvature / K (the paper's heuristic)"},
      {"tolerance", OptionKind::Number, OptionMethods::Adaptive, "EPS", "", "sizing", {}, {}, 0, 0,
       "edges for a chord deviation of EPS instead of factor, and (variant improved) every triangle measured and "
       "split until it lies within EPS of the surface where it can (the stats name the rest)"},
      {"chord", OptionKind::Number, OptionMethods::Adaptive, "EPS", "", "sizing", {}, {}, 0, 0,
       "edges for a chord deviation of EPS at each point's smallest radius of curvature, without tolerance's bound: "
       "nothing measured or refined (the Igea VIS-4004 at the same sizing: 129k field evaluations against 485k), "
       "the distance not bounded; with variant paper the same as tolerance"},
      {"min_edge", OptionKind::Number, OptionMethods::Adaptive, "L", "", "", {}, {}, 0, 0,
       "shortest edge (default 2e-3 of the box diagonal; a default run that fails where the surface bends more "
       "tightly is made once more with a quarter of that radius, not below 2e-4 of the diagonal)"},
      {"max_edge", OptionKind::Number, OptionMethods::Adaptive, "L", "", "", {}, {}, 0, 0,
       "longest edge (default 0.1 of the box diagonal)"},
      {"triangle_count", OptionKind::Choice, OptionMethods::Adaptive, "RULE", "hartmann", "", {"hartmann", "paper_floor"},
       {{"paper", "paper_floor"}}, 0, 0,
       "triangles per expansion: hartmann or paper_floor (the paper's formula with its floor; \"paper\" is "
       "accepted for it)"},
      {"variant", OptionKind::Choice, OptionMethods::Adaptive, "NAME", "improved", "", {"improved", "paper"}, {}, 0, 0,
       "improved (the paper plus grading, local repair of triangles under 30 degrees, a tolerance that bounds the "
       "distance, and a second run looking ahead where a mesh misses the angle, edge-ratio or distance bounds) or "
       "paper (the algorithm as printed)"},
      {"creases", OptionKind::Choice, OptionMethods::Adaptive, "HOW", "follow", "", {"follow", "ignore"}, {}, 0, 0,
       "follow (trace the creases of a min/max/abs field first and mesh along them; a field without branch data, a "
       "Python function, stops at the first crease it meets) or ignore (mesh across them as across curvature)"},
      {"curvature", OptionKind::Flag, OptionMethods::Adaptive, "", "false", "", {}, {}, 0, 0,
       "mac and shape_index per vertex (vertex scalars; PLY files keep them)"},
      {"blocks", OptionKind::Boolean, OptionMethods::Adaptive, "BOOL", "", "", {}, {}, 0, 0,
       "cut the box into blocks of about 2500 triangles, trace the seams where the surface crosses the cuts, and "
       "mesh the blocks from them on all threads (a surface without followed creases; the same mesh on any number "
       "of threads; stats blocks); default: true (a Python function's blocks are smaller and meshed in lockstep, "
       "every call of it gathering their evaluations: about a third of its calls tracked alone); false "
       "tracks the surface alone"},
      {"check_self_intersections", OptionKind::Boolean, OptionMethods::Adaptive, "BOOL", "true", "", {}, {}, 0, 0,
       "refuse a mesh whose triangles intersect (the last of the final checks; false skips it, for speed on a "
       "surface known to mesh)"},
      {"cell", OptionKind::Number, OptionMethods::Marching, "H", "", "cell", {}, {}, 0, 0,
       "cell edge (default 1/64 of the box's longest side)"},
      {"precision", OptionKind::Integer, OptionMethods::Marching, "P", "", "cell", {}, {}, 0, 5,
       "the paper's precision for data-driven models, an integer in [0, 5], instead of cell"},
      {"traversal", OptionKind::Choice, OptionMethods::Marching, "HOW", "continuation", "", {"continuation", "grid"}, {},
       0, 0, "continuation or grid"},
      {"face_ambiguity", OptionKind::Choice, OptionMethods::MarchingCubes, "RULE", "asymptotic_decider", "",
       {"asymptotic_decider", "join_inside", "separate_inside"}, {}, 0, 0,
       "how Marching Cubes splits an ambiguous face: asymptotic_decider, join_inside or separate_inside"},
      {"level", OptionKind::Real, OptionMethods::All, "C", "0", "", {}, {}, 0, 0,
       "mesh the surface F = C instead of F = 0 (an iso-value; the inside is where F < C)"},
      {"seed_resolution", OptionKind::Integer, OptionMethods::All, "N", "32", "", {}, {}, 2, INT_MAX,
       "cells along the longest side of the seed grid"},
      {"max_triangles", OptionKind::Integer, OptionMethods::All, "N", "", "", {}, {}, 1, INT_MAX,
       "stop with an error beyond N triangles"},
      {"threads", OptionKind::Integer, OptionMethods::All, "N", "0", "", {}, {}, 0, INT_MAX,
       "threads of the seed grid (thread-safe fields), the adaptive method's blocks (--blocks) and groups of crease "
       "patches (meshed, then repaired, side by side), relaxation and final check, and a second for half of each costly evaluation while it tracks (a VIS from 1024 centres) (0: all cores this "
       "process may use, at most 8); the mesh is the same on any number"},
  };
  return options;
}

// As Python prints a float (the shortest decimal that reads back, "2.0" for 2, "nan"), so that a
// message quotes the value as the caller wrote it in any of the three.
std::string number_text(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, v).ptr;
  std::string text(buffer, end);
  if (text.find_first_of(".e") == std::string::npos) text += ".0";
  return text;
}

std::string quoted_list(const std::vector<std::string_view>& choices) {
  std::string text;
  for (std::size_t i = 0; i < choices.size(); ++i)
    text += (i == 0 ? "" : i + 1 == choices.size() ? " or " : ", ") + ("\"" + std::string(choices[i]) + "\"");
  return text;
}

// The value of `spec` checked against its kind: a number, an integer, a choice (aliases
// resolved) or a boolean, as JSON.
nlohmann::json checked(const OptionSpec& spec, const nlohmann::json& v) {
  const std::string name(spec.name);
  switch (spec.kind) {
    case OptionKind::Number: {
      if (!v.is_number()) throw InvalidInputError(name + " must be a positive number, not " + v.dump());
      const double x = v.get<double>();
      if (!(std::isfinite(x) && x > 0)) throw InvalidInputError(name + " must be a positive number, not " + number_text(x));
      return x;
    }
    case OptionKind::Real: {
      if (!v.is_number()) throw InvalidInputError(name + " must be a number, not " + v.dump());
      const double x = v.get<double>();
      if (!std::isfinite(x)) throw InvalidInputError(name + " must be a finite number, not " + number_text(x));
      return x;
    }
    case OptionKind::Integer: {
      const bool integral = v.is_number_integer() || (v.is_number_float() && std::isfinite(v.get<double>()) &&
                                                      std::trunc(v.get<double>()) == v.get<double>());
      const std::string range = "[" + std::to_string(spec.lo) + ", " + std::to_string(spec.hi) + "]";
      if (!integral || v.get<double>() < spec.lo || v.get<double>() > spec.hi)
        throw InvalidInputError(name + " must be an integer in " + range + ", not " + v.dump());
      return v.get<long long>();
    }
    case OptionKind::Choice: {
      if (v.is_string()) {
        const std::string s = v.get<std::string>();
        for (const auto& [alias, meaning] : spec.aliases)
          if (s == alias) return std::string(meaning);
        if (std::find(spec.choices.begin(), spec.choices.end(), s) != spec.choices.end()) return s;
      }
      throw InvalidInputError(name + " must be " + quoted_list(spec.choices) + ", not " + v.dump());
    }
    case OptionKind::Flag:
    case OptionKind::Boolean:
      if (!v.is_boolean()) throw InvalidInputError(name + " must be true or false, not " + v.dump());
      return v;
  }
  return v;
}

// Sets one checked value on the request.
void apply(PolygonizeRequest& r, std::string_view name, const nlohmann::json& v) {
  AdaptiveOptions& a = r.adaptive;
  MarchingOptions& m = r.marching;
  if (name == "factor") a.factor = v.get<double>();
  else if (name == "tolerance") a.sizing = SizingMode::Tolerance, a.tolerance = v.get<double>();
  else if (name == "chord") a.sizing = SizingMode::Chord, a.tolerance = v.get<double>();
  else if (name == "min_edge") a.min_edge = v.get<double>();
  else if (name == "max_edge") a.max_edge = v.get<double>();
  else if (name == "triangle_count")
    a.triangle_count = v == "paper_floor" ? TriangleCountRule::PaperFloor : TriangleCountRule::Hartmann;
  else if (name == "variant") a.variant = v == "paper" ? Variant::Paper : Variant::Improved;
  else if (name == "creases") a.creases = v == "ignore" ? CreaseHandling::Ignore : CreaseHandling::Follow;
  else if (name == "curvature") a.curvature_properties = v.get<bool>();
  else if (name == "check_self_intersections") a.check_self_intersections = v.get<bool>();
  else if (name == "blocks") a.blocks = v.get<bool>();
  else if (name == "cell") m.cell_size = v.get<double>();
  else if (name == "precision") m.precision = v.get<int>();
  else if (name == "traversal") m.traversal = v == "grid" ? Traversal::Grid : Traversal::Continuation;
  else if (name == "face_ambiguity")
    m.face_ambiguity = v == "join_inside"       ? FaceAmbiguity::JoinInside
                       : v == "separate_inside" ? FaceAmbiguity::SeparateInside
                                                : FaceAmbiguity::AsymptoticDecider;
  else if (name == "level") r.level = v.get<double>();
  else if (name == "seed_resolution") a.seed_resolution = m.seed_resolution = v.get<int>();
  else if (name == "max_triangles") a.max_triangles = m.max_triangles = v.get<std::size_t>();
  else if (name == "threads") a.threads = m.threads = v.get<int>();
  else throw std::logic_error("polygonize_options: no setter for " + std::string(name));
}

}  // namespace

std::span<const OptionSpec> polygonize_options() { return table(); }

const OptionSpec* find_polygonize_option(std::string_view name) {
  for (const OptionSpec& s : table())
    if (s.name == name) return &s;
  return nullptr;
}

std::optional<std::string_view> nearest_polygonize_option(std::string_view name) {
  std::vector<std::string> names;
  for (const OptionSpec& s : table()) names.emplace_back(s.name);
  const std::optional<std::string> best = nearest_spelling(std::string(name), names);
  if (!best) return std::nullopt;
  return find_polygonize_option(*best)->name;
}

std::string option_flag(const OptionSpec& spec) {
  std::string flag = "--" + std::string(spec.name);
  std::replace(flag.begin(), flag.end(), '_', '-');
  return flag;
}

bool applies_to(const OptionSpec& spec, std::string_view method) {
  switch (spec.methods) {
    case OptionMethods::All: return true;
    case OptionMethods::Adaptive: return method == "adaptive";
    case OptionMethods::Marching: return method == "mc" || method == "mt";
    case OptionMethods::MarchingCubes: return method == "mc";
  }
  return false;
}

PolygonizeRequest polygonize_request(const std::string& method, const nlohmann::json& options) {
  if (method != "adaptive" && method != "mc" && method != "mt")
    throw InvalidInputError("method must be \"adaptive\", \"mc\" or \"mt\", not \"" + method + "\"");
  if (!options.is_null() && !options.is_object()) throw InvalidInputError("the options must be an object");
  PolygonizeRequest r;
  r.method = method;
  std::vector<const OptionSpec*> given;
  for (const auto& [key, value] : options.items()) {
    const OptionSpec* spec = find_polygonize_option(key);
    if (!spec) {
      const auto near = nearest_polygonize_option(key);
      throw InvalidInputError("unknown option \"" + key + "\"" +
                              (near ? " (did you mean \"" + std::string(*near) + "\"?)" : std::string()));
    }
    if (value.is_null()) continue;
    if (!applies_to(*spec, method))
      throw InvalidInputError(std::string(spec->name) + " does not apply to method \"" + method + "\"");
    for (const OptionSpec* other : given)
      if (!spec->exclusive.empty() && other->exclusive == spec->exclusive) {
        std::vector<std::string_view> group;
        for (const OptionSpec& s : table())
          if (s.exclusive == spec->exclusive) group.push_back(s.name);
        std::string names;
        for (std::size_t i = 0; i < group.size(); ++i)
          names += (i == 0 ? "" : i + 1 == group.size() ? " and " : ", ") + std::string(group[i]);
        throw InvalidInputError("give one of " + names + ", not several");
      }
    given.push_back(spec);
    apply(r, spec->name, checked(*spec, value));
  }
  return r;
}

}  // namespace cdp
