#include <cdp/io/polygonize_stats_json.h>

namespace cdp {

namespace {

nlohmann::json value_json(const StatValue& v) {
  return std::visit([](const auto& x) { return nlohmann::json(x); }, v.variant());
}

}  // namespace

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
  for (const auto& [name, v] : s.extra) {
    nlohmann::json* at = &j;
    std::size_t start = 0;
    for (std::size_t dot = name.find('.'); dot != std::string::npos; dot = name.find('.', start)) {
      at = &(*at)[name.substr(start, dot - start)];
      start = dot + 1;
    }
    (*at)[name.substr(start)] = value_json(v);
  }
  return j;
}

}  // namespace cdp
