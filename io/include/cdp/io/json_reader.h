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
  // \pre `object` outlives the reader and the readers made from it (they keep a pointer to it).
  // \throw InvalidInputError "SOURCE: PATH: expected a JSON object, ..." when `object` is not one.
  JsonReader(const nlohmann::json& object, std::string source, std::string path = "",
             std::filesystem::path base_dir = {});

  bool has(const std::string& key) const;
  // \return the number at `key`; with a fallback, the fallback when the key is absent.
  // \throw InvalidInputError "SOURCE: KEY: problem" for a missing key (without a fallback; a present
  //        key not yet asked for, within two edits of it, is named as misspelled instead), or a value
  //        that is not a finite number.
  double number(const std::string& key);
  double number(const std::string& key, double fallback);
  // \return the number at `key`; with a fallback, the fallback when the key is absent.
  // \throw InvalidInputError as number(), and for a value not above 0.
  double positive_number(const std::string& key);
  double positive_number(const std::string& key, double fallback);
  // \return the integer at `key`; with a fallback, the fallback when the key is absent.
  // \throw InvalidInputError for a missing key (as number()) or a value that is not a JSON integer.
  long long integer(const std::string& key);
  long long integer(const std::string& key, long long fallback);
  // \return the boolean at `key`, the fallback when the key is absent.
  // \throw InvalidInputError for a value that is not true or false.
  bool boolean(const std::string& key, bool fallback);
  // \return the string at `key`; with a fallback, the fallback when the key is absent.
  // \throw InvalidInputError for a missing key (as number()) or a value that is not a string.
  std::string string(const std::string& key);
  std::string string(const std::string& key, const std::string& fallback);
  // One of `choices`; the message lists them.
  // \throw InvalidInputError as string(), and for a string not among `choices`.
  std::string choice(const std::string& key, const std::vector<std::string>& choices);
  std::string choice(const std::string& key, const std::vector<std::string>& choices, const std::string& fallback);
  // \return the vector [x, y, z] at `key`; with a fallback, the fallback when the key is absent.
  // \throw InvalidInputError as numbers(), and for an array of other than 3 numbers.
  Vec3 vec3(const std::string& key);
  Vec3 vec3(const std::string& key, const Vec3& fallback);
  // \throw InvalidInputError for a missing key (as number()), a value that is not an array of
  //        numbers, or a number that is not finite.
  std::vector<double> numbers(const std::string& key);
  // A box written [[xmin,ymin,zmin],[xmax,ymax,zmax]].
  // \throw InvalidInputError for a missing key (as number()), another shape, or a box that is not
  //        valid (Box::valid: every max above its min, all finite).
  Box box(const std::string& key);
  // An existing file named relative to base_dir.
  // \return the name, joined to base_dir when it is relative and base_dir is not empty.
  // \throw InvalidInputError as string().
  // \throw FileError (an InvalidInputError) "SOURCE: KEY: file not found: PATH" when the name is not
  //        an existing regular file.
  std::filesystem::path file(const std::string& key);
  // \return the value at `key`, unchecked (it counts as read).
  // \throw InvalidInputError for a missing key (as number()).
  const nlohmann::json& raw(const std::string& key);
  // \return a reader of the object at `key`, its path extended by the key.
  // \throw InvalidInputError for a missing key (as number()) or a value that is not an object.
  JsonReader object(const std::string& key);
  // \return a reader of each element, in order, its path KEY[i].
  // \throw InvalidInputError for a missing key (as number()), a value that is not an array, or an
  //        element that is not an object.
  std::vector<JsonReader> objects(const std::string& key);  // an array of objects

  // Throws on the first key not in `allowed` (with a suggestion), before any is read, so that a
  // misspelled key is reported as such rather than as the required key it failed to be.
  // \throw InvalidInputError "SOURCE: KEY: unknown key" for that key, with the nearest spelling if any.
  void check_keys(const std::vector<std::string>& allowed) const;

  // Throws on the first key that was never read, suggesting the nearest known spelling.
  // `known` lists keys that are valid but were not read on this path (for the suggestion).
  // \throw InvalidInputError "SOURCE: KEY: unknown key" for that key, with the nearest spelling if any.
  void finish(const std::vector<std::string>& known = {}) const;

  // \throw InvalidInputError "SOURCE: KEY: problem" (the key with its path), or "SOURCE: PATH:
  //        problem" for the second form, always.
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
// \throw FileError (an InvalidInputError) "FILE: problem" for a folder, or a file that cannot be
//        opened or read.
// \throw InvalidInputError "FILE: problem" for malformed JSON (a number out of range included) or a
//        key given twice in one object.
nlohmann::json read_json_file(const std::filesystem::path& path);

}  // namespace cdp
