#include <cdp/core/errors.h>
#include <cdp/io/json_reader.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

namespace cdp {

namespace {

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

std::string type_name_of(const nlohmann::json& j) {
  if (j.is_number()) return "a number";
  if (j.is_string()) return "a string";
  if (j.is_boolean()) return "a boolean";
  if (j.is_array()) return "an array";
  if (j.is_object()) return "an object";
  return "null";
}

}  // namespace

std::optional<std::string> nearest_spelling(const std::string& word, const std::vector<std::string>& known) {
  std::optional<std::string> best;
  std::size_t best_d = 3;  // suggest only close spellings
  for (const auto& k : known) {
    const std::size_t d = edit_distance(word, k);
    if (d < best_d) best_d = d, best = k;
  }
  return best;
}

JsonReader::JsonReader(const nlohmann::json& object, std::string source, std::string path,
                       std::filesystem::path base_dir)
    : object_(&object), source_(std::move(source)), path_(std::move(path)), base_dir_(std::move(base_dir)) {
  if (!object.is_object()) fail("expected a JSON object, found " + type_name_of(object));
}

std::string JsonReader::where(const std::string& key) const {
  std::string w = source_ + ": ";
  if (!path_.empty()) w += path_ + (key.empty() ? "" : ".");
  w += key;
  return w;
}

void JsonReader::fail(const std::string& key, const std::string& problem) const {
  throw InvalidInputError(where(key) + ": " + problem);
}

void JsonReader::fail(const std::string& problem) const {
  throw InvalidInputError(source_ + ": " + (path_.empty() ? "" : path_ + ": ") + problem);
}

bool JsonReader::has(const std::string& key) const {
  asked_.insert(key);
  return object_->contains(key);
}

const nlohmann::json& JsonReader::get(const std::string& key) {
  asked_.insert(key);
  auto it = object_->find(key);
  if (it == object_->end()) {
    // A misspelling of the missing key is the likelier mistake; name it rather than the key.
    for (const auto& [present, value] : object_->items())
      if (!asked_.count(present) && edit_distance(present, key) < 3)
        fail(present, "unknown key (did you mean \"" + key + "\"?)");
    fail(key, "missing required key");
  }
  used_.insert(key);
  return *it;
}

const nlohmann::json& JsonReader::raw(const std::string& key) { return get(key); }

double JsonReader::number(const std::string& key) {
  const auto& j = get(key);
  if (!j.is_number()) fail(key, "expected a number, found " + type_name_of(j));
  const double v = j.get<double>();
  if (!std::isfinite(v)) fail(key, "not a finite number");
  return v;
}
double JsonReader::number(const std::string& key, double fallback) {
  return has(key) ? number(key) : fallback;
}
double JsonReader::positive_number(const std::string& key) {
  const double v = number(key);
  if (!(v > 0)) fail(key, "must be positive, found " + std::to_string(v));
  return v;
}
double JsonReader::positive_number(const std::string& key, double fallback) {
  return has(key) ? positive_number(key) : fallback;
}
long long JsonReader::integer(const std::string& key) {
  const auto& j = get(key);
  if (!j.is_number_integer()) fail(key, "expected an integer, found " + type_name_of(j));
  return j.get<long long>();
}
long long JsonReader::integer(const std::string& key, long long fallback) {
  return has(key) ? integer(key) : fallback;
}
bool JsonReader::boolean(const std::string& key, bool fallback) {
  if (!has(key)) return fallback;
  const auto& j = get(key);
  if (!j.is_boolean()) fail(key, "expected true or false, found " + type_name_of(j));
  return j.get<bool>();
}
std::string JsonReader::string(const std::string& key) {
  const auto& j = get(key);
  if (!j.is_string()) fail(key, "expected a string, found " + type_name_of(j));
  return j.get<std::string>();
}
std::string JsonReader::string(const std::string& key, const std::string& fallback) {
  return has(key) ? string(key) : fallback;
}
std::string JsonReader::choice(const std::string& key, const std::vector<std::string>& choices) {
  const std::string v = string(key);
  if (std::find(choices.begin(), choices.end(), v) == choices.end()) {
    std::string list;
    for (const auto& c : choices) list += (list.empty() ? "" : ", ") + ("\"" + c + "\"");
    fail(key, "\"" + v + "\" is not one of " + list);
  }
  return v;
}
std::string JsonReader::choice(const std::string& key, const std::vector<std::string>& choices,
                               const std::string& fallback) {
  return has(key) ? choice(key, choices) : fallback;
}
std::vector<double> JsonReader::numbers(const std::string& key) {
  const auto& j = get(key);
  if (!j.is_array()) fail(key, "expected an array of numbers, found " + type_name_of(j));
  std::vector<double> out;
  for (const auto& e : j) {
    if (!e.is_number()) fail(key, "expected an array of numbers, found an element that is " + type_name_of(e));
    out.push_back(e.get<double>());
    if (!std::isfinite(out.back())) fail(key, "not a finite number");
  }
  return out;
}
Vec3 JsonReader::vec3(const std::string& key) {
  const auto v = numbers(key);
  if (v.size() != 3) fail(key, "expected 3 numbers [x, y, z], found " + std::to_string(v.size()));
  return {v[0], v[1], v[2]};
}
Vec3 JsonReader::vec3(const std::string& key, const Vec3& fallback) { return has(key) ? vec3(key) : fallback; }
Box JsonReader::box(const std::string& key) {
  const auto& j = get(key);
  auto corner = [&](const nlohmann::json& c) {
    if (!c.is_array() || c.size() != 3 || !c[0].is_number() || !c[1].is_number() || !c[2].is_number())
      fail(key, "expected [[xmin, ymin, zmin], [xmax, ymax, zmax]]");
    return Vec3(c[0].get<double>(), c[1].get<double>(), c[2].get<double>());
  };
  if (!j.is_array() || j.size() != 2) fail(key, "expected [[xmin, ymin, zmin], [xmax, ymax, zmax]]");
  Box b{corner(j[0]), corner(j[1])};
  if (!b.valid()) fail(key, "empty box: every max must exceed its min");
  return b;
}
std::filesystem::path JsonReader::file(const std::string& key) {
  std::filesystem::path p = string(key);
  if (p.is_relative() && !base_dir_.empty()) p = base_dir_ / p;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(p, ec)) throw FileError(where(key) + ": file not found: " + p.string(), ENOENT);
  return p;
}
JsonReader JsonReader::object(const std::string& key) {
  const auto& j = get(key);
  return JsonReader(j, source_, path_.empty() ? key : path_ + "." + key, base_dir_);
}
std::vector<JsonReader> JsonReader::objects(const std::string& key) {
  const auto& j = get(key);
  if (!j.is_array()) fail(key, "expected an array of objects, found " + type_name_of(j));
  std::vector<JsonReader> out;
  for (std::size_t i = 0; i < j.size(); ++i)
    out.emplace_back(j[i], source_, (path_.empty() ? key : path_ + "." + key) + "[" + std::to_string(i) + "]",
                     base_dir_);
  return out;
}

void JsonReader::check_keys(const std::vector<std::string>& allowed) const {
  const std::set<std::string> ok(allowed.begin(), allowed.end());
  for (const auto& [key, value] : object_->items()) {
    if (ok.count(key)) continue;
    const std::optional<std::string> best = nearest_spelling(key, allowed);
    fail(key, best ? "unknown key (did you mean \"" + *best + "\"?)" : "unknown key");
  }
}

void JsonReader::finish(const std::vector<std::string>& known) const {
  for (const auto& [key, value] : object_->items()) {
    if (used_.count(key)) continue;
    std::vector<std::string> candidates(asked_.begin(), asked_.end());
    candidates.insert(candidates.end(), known.begin(), known.end());
    const std::optional<std::string> best = nearest_spelling(key, candidates);
    fail(key, best ? "unknown key (did you mean \"" + *best + "\"?)" : "unknown key");
  }
}

nlohmann::json read_json_file(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw FileError(path.string() + ": is a folder, not a JSON file", EISDIR);
  errno = 0;
  std::ifstream in(path);
  if (!in) {
    const int err = errno;
    throw FileError(path.string() + ": cannot open file", err);
  }
  // A key given twice in one object is an error: nlohmann keeps the last value silently, and a
  // field whose "radius" is written twice is a mistake to point at, not to guess about. One set
  // of keys per open object.
  std::vector<std::set<std::string>> keys;
  std::string duplicate;
  const nlohmann::json::parser_callback_t check = [&](int, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    using Event = nlohmann::json::parse_event_t;
    if (event == Event::object_start) keys.emplace_back();
    else if (event == Event::object_end && !keys.empty()) keys.pop_back();
    else if (event == Event::key && !keys.empty() && !keys.back().insert(parsed.get<std::string>()).second && duplicate.empty())
      duplicate = parsed.get<std::string>();
    return true;
  };
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in, check, true, /*ignore_comments=*/false);
  } catch (const nlohmann::json::exception& e) {
    // parse_error (syntax) and out_of_range (a number like 1e999 that overflows a double).
    std::string msg = e.what();
    // nlohmann's message starts with "[json.exception.parse_error.101] "; keep what follows.
    if (auto pos = msg.find("] "); pos != std::string::npos) msg = msg.substr(pos + 2);
    throw InvalidInputError(path.string() + ": malformed JSON: " + msg);
  }
  if (in.bad()) throw FileError(path.string() + ": cannot read file", EIO);
  if (!duplicate.empty()) throw InvalidInputError(path.string() + ": the key \"" + duplicate + "\" appears twice in one object");
  return j;
}

}  // namespace cdp
