// Strict reading of JSON configuration objects: every key must be known and of the right type.
// Errors are InvalidInputError with one line "<source>: <path>: <problem>", and misspelled keys
// get a suggestion. Used by the field factory, the apps and the experiment runner.
#pragma once

#include <cdp/core/field.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace cdp {

// The spelling among `known` nearest to a misspelled `word` (fewer than three edits; the first
// of a tie), or none: the suggestion of an "unknown key" message.
std::optional<std::string> nearest_spelling(const std::string& word, const std::vector<std::string>& known);

class JsonReader {
 public:
  // `source` names the file in messages; `path` is the object's place inside it ("" for the root);
  // relative file names inside the object resolve against `base_dir`.
  JsonReader(const nlohmann::json& object, std::string source, std::string path = "",
             std::filesystem::path base_dir = {});

  bool has(const std::string& key) const;
  double number(const std::string& key);
  double number(const std::string& key, double fallback);
  double positive_number(const std::string& key);
  double positive_number(const std::string& key, double fallback);
  long long integer(const std::string& key);
  long long integer(const std::string& key, long long fallback);
  bool boolean(const std::string& key, bool fallback);
  std::string string(const std::string& key);
  std::string string(const std::string& key, const std::string& fallback);
  // One of `choices`; the message lists them.
  std::string choice(const std::string& key, const std::vector<std::string>& choices);
  std::string choice(const std::string& key, const std::vector<std::string>& choices, const std::string& fallback);
  Vec3 vec3(const std::string& key);
  Vec3 vec3(const std::string& key, const Vec3& fallback);
  std::vector<double> numbers(const std::string& key);
  // A box written [[xmin,ymin,zmin],[xmax,ymax,zmax]].
  Box box(const std::string& key);
  // An existing file named relative to base_dir.
  std::filesystem::path file(const std::string& key);
  const nlohmann::json& raw(const std::string& key);
  JsonReader object(const std::string& key);
  std::vector<JsonReader> objects(const std::string& key);  // an array of objects

  // Throws on the first key not in `allowed` (with a suggestion), before any is read, so that a
  // misspelled key is reported as such rather than as the required key it failed to be.
  void check_keys(const std::vector<std::string>& allowed) const;

  // Throws on the first key that was never read, suggesting the nearest known spelling.
  // `known` lists keys that are valid but were not read on this path (for the suggestion).
  void finish(const std::vector<std::string>& known = {}) const;

  [[noreturn]] void fail(const std::string& key, const std::string& problem) const;
  [[noreturn]] void fail(const std::string& problem) const;

  const std::string& source() const { return source_; }
  const std::filesystem::path& base_dir() const { return base_dir_; }
  const nlohmann::json& json() const { return *object_; }

 private:
  const nlohmann::json& get(const std::string& key);
  std::string where(const std::string& key) const;

  const nlohmann::json* object_;
  std::string source_;
  std::string path_;
  std::filesystem::path base_dir_;
  std::set<std::string> used_;
  mutable std::set<std::string> asked_;  // every key an accessor looked for, present or not
};

// Parses a JSON file; InvalidInputError naming the file when it is missing or malformed.
nlohmann::json read_json_file(const std::filesystem::path& path);

}  // namespace cdp
