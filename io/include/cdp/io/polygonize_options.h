// The options of the three polygonizers in one table: the polygonize program's flags, the Python
// keywords of cdp.polygonize and the keys of an experiment file's runs are made from it, with
// the same names (a flag is --NAME with '-' for '_'), defaults and spellings of choices.
#pragma once

#include <cdp/baselines/marching_options.h>
#include <cdp/core/adaptive_polygonizer.h>

#include <nlohmann/json.hpp>

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace cdp {

enum class OptionKind {
  Number,   // a finite number above 0
  Integer,  // an integer in [lo, hi]
  Choice,   // one of `choices`
  Flag,     // true or false; on the command line a flag without a value turns it on
  Boolean,  // true or false; on the command line a value ("true" or "false"), its default being true
  Real,     // any finite number
};

// Which methods an option applies to (the others refuse it).
enum class OptionMethods { All, Adaptive, Marching, MarchingCubes };

struct OptionSpec {
  std::string_view name;  // the Python keyword and the experiment key; the flag is --name with '-' for '_'
  OptionKind kind;
  OptionMethods methods;
  // What the option's value is called in the program's help (K, EPS, N, ...).
  std::string_view value_name;
  // The default as text ("2", "follow"); empty where it follows from the field (its box).
  std::string_view default_text;
  // Options of one group exclude each other (factor, tolerance, chord; cell, precision); empty: none.
  std::string_view exclusive;
  std::vector<std::string_view> choices;  // Choice: the spellings, the first the default
  // Choice: older spellings still accepted, each with the choice it means ("paper" for
  // triangle_count's "paper_floor", the spelling the stats report).
  std::vector<std::pair<std::string_view, std::string_view>> aliases;
  long long lo = 0, hi = 0;               // Integer: the range
  std::string_view help;
};

// Every option, in the order the program's help and Python's docstring list them.
std::span<const OptionSpec> polygonize_options();

// The option named `name`, or none.
const OptionSpec* find_polygonize_option(std::string_view name);

// The known option nearest to a misspelled `name` (fewer than three edits), or none.
std::optional<std::string_view> nearest_polygonize_option(std::string_view name);

// "--min-edge" for "min_edge".
std::string option_flag(const OptionSpec& spec);

// Whether `spec` applies to `method` ("adaptive", "mc" or "mt").
bool applies_to(const OptionSpec& spec, std::string_view method);

// A run of one method with its options.
struct PolygonizeRequest {
  std::string method = "adaptive";
  // The value of F whose level set is meshed (option "level"): a run on another level than 0
  // meshes LevelShift(field, level) (cdp/core/models/level_shift.h).
  double level = 0;
  AdaptiveOptions adaptive;
  MarchingOptions marching;
};

// The request for `method` with `options` (an object: name -> value, a JSON number for Number
// and Integer, a string for Choice, a boolean for Flag and Boolean; null means "the default").
// \throw InvalidInputError (one line, naming the option as it is named in Python and JSON) for
//        an unknown method, an unknown name (with the nearest known one), a value of the wrong
//        kind, outside its range or not among its choices, an option `method` does not use,
//        and two options that exclude each other.
// \throw InvalidInputError also for `options` that is neither an object nor null.
PolygonizeRequest polygonize_request(const std::string& method, const nlohmann::json& options);

}  // namespace cdp
