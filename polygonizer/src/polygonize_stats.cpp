#include <polygonizer/polygonize_stats.h>

namespace cdp {

nlohmann::json to_json(const PolygonizeStats& s) {
  nlohmann::json j;
  j["method"] = s.method;
  j["triangles"] = s.triangles;
  j["vertices"] = s.vertices;
  j["components"] = s.components;
  j["seconds"] = s.seconds;
  j["field_evaluations"] = {{"value", s.field_evaluations.value},
                            {"value_gradient", s.field_evaluations.value_gradient},
                            {"gradient_hessian", s.field_evaluations.gradient_hessian},
                            {"total", s.field_evaluations.total()}};
  j["splits"] = s.splits;
  j["merges"] = s.merges;
  for (const auto& [k, v] : s.extra.items()) j[k] = v;
  return j;
}

}  // namespace cdp
