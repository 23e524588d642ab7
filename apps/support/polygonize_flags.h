// The polygonize program's method options, made from the table of cdp/io/polygonize_options.h
// (the Python keywords and the experiment keys come from the same table).
#pragma once

#include <cdp/io/polygonize_options.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <deque>
#include <string>
#include <vector>

namespace cdp::app {

class PolygonizeFlags {
 public:
  // Adds every option of the table to `app`: those of every method on the app itself, the
  // others in a group per method ("adaptive method", "mc and mt methods"), so that the help
  // sorts them. Options of one exclusive group exclude each other (CLI11's "--a excludes --b").
  explicit PolygonizeFlags(CLI::App& app);

  // After parsing: the options given, name -> value as cdp::polygonize_request takes them.
  nlohmann::json given() const;

  // After parsing: the flag of the first option given that `method` does not use, or "".
  std::string not_applying(const std::string& method) const;

 private:
  struct Entry {
    const OptionSpec* spec;
    CLI::Option* option;
  };
  std::vector<Entry> entries_;
  // Storage the options write to (a deque: stable addresses).
  std::deque<double> numbers_;
  std::deque<long long> integers_;
  std::deque<std::string> texts_;
  std::deque<bool> flags_;
};

}  // namespace cdp::app
