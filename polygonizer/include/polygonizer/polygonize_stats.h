// What every polygonization method reports (written as STATS.json by build/bin/polygonize).
#pragma once

#include <polygonizer/field.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>

namespace cdp {

struct PolygonizeStats {
  std::string method;              // "adaptive", "mc", "mt"
  std::size_t triangles = 0;
  std::size_t vertices = 0;
  std::size_t components = 0;      // connected components of the output mesh
  double seconds = 0;              // wall-clock time of the polygonization itself
  EvaluationCounts field_evaluations;
  std::size_t splits = 0;          // adaptive only: front splits
  std::size_t merges = 0;          // adaptive only: front merges
  nlohmann::json extra = nlohmann::json::object();  // method-specific figures (cell size, seeds, ...)
};

nlohmann::json to_json(const PolygonizeStats& stats);

}  // namespace cdp
