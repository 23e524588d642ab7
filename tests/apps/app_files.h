// What the app tests give the programs and read back from them.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace cdp::test {

// A torus field, as a user would write its JSON.
inline constexpr const char* kTorus = R"({"type": "torus", "major_radius": 1, "minor_radius": 0.4})";

// A JSON file a program wrote (STATS.json, an experiment's summary).
inline nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

}  // namespace cdp::test
