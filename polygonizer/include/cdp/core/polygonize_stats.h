// What every polygonization method reports (written as STATS.json by build/bin/polygonize). A
// plain struct: the core carries no JSON; `to_json` (polygonize_stats_json.h) serialises it.
#pragma once

#include <cdp/core/field.h>

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

namespace cdp {

// One method-specific figure: a flag, an integer count, a number, a name, or a short list of
// integers (a lattice's cells per axis).
class StatValue {
 public:
  using Variant = std::variant<bool, long long, unsigned long long, double, std::string, std::vector<long long>>;

  StatValue() = default;
  StatValue(bool v) : v_(v) {}
  StatValue(double v) : v_(v) {}
  StatValue(const char* v) : v_(std::string(v)) {}
  StatValue(std::string v) : v_(std::move(v)) {}
  StatValue(std::vector<long long> v) : v_(std::move(v)) {}
  // Every integer type: signed ones as long long, unsigned ones (counts) as unsigned long long.
  template <class T, std::enable_if_t<std::is_integral_v<T> && !std::is_same_v<T, bool>, int> = 0>
  StatValue(T v) {
    if constexpr (std::is_signed_v<T>) v_ = static_cast<long long>(v);
    else v_ = static_cast<unsigned long long>(v);
  }

  // The value as T: numbers convert to any arithmetic type, strings to std::string; anything
  // else throws std::logic_error (a test asking for the wrong kind of figure).
  template <class T>
  T get() const {
    if constexpr (std::is_same_v<T, std::string>) {
      if (const auto* s = std::get_if<std::string>(&v_)) return *s;
      throw std::logic_error("StatValue: not a string");
    } else if constexpr (std::is_arithmetic_v<T>) {
      return std::visit(
          [](const auto& x) -> T {
            using X = std::decay_t<decltype(x)>;
            if constexpr (std::is_arithmetic_v<X>) return static_cast<T>(x);
            else throw std::logic_error("StatValue: not a number");
          },
          v_);
    } else {
      return std::get<T>(v_);
    }
  }
  const Variant& variant() const { return v_; }
  bool operator==(const StatValue& o) const { return v_ == o.v_; }
  bool operator==(const std::string& s) const {
    const auto* mine = std::get_if<std::string>(&v_);
    return mine && *mine == s;
  }
  bool operator==(const char* s) const { return *this == std::string(s); }

 private:
  Variant v_ = 0.0;
};

struct PolygonizeStats {
  std::string method;              // "adaptive", "mc", "mt"
  std::size_t triangles = 0;
  std::size_t vertices = 0;
  std::size_t components = 0;      // connected components of the output mesh
  double seconds = 0;              // wall-clock time of the polygonization itself
  EvaluationCounts field_evaluations;
  std::size_t splits = 0;          // adaptive only: front splits
  std::size_t merges = 0;          // adaptive only: front merges
  // Method-specific figures (cell size, seeds, ...), by name. A dotted name ("edge_length.min")
  // is a member of an object in STATS.json ({"edge_length": {"min": ...}}).
  std::map<std::string, StatValue> extra;
};

}  // namespace cdp
