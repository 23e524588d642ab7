// build/bin/curvature FIELD.json --at x,y,z
// Projects the point onto the surface and prints the curvature measures there as one JSON object.
#include "support/app_support.h"

#include <polygonizer/curvature.h>
#include <polygonizer/errors.h>
#include <polygonizer/field_factory.h>
#include <polygonizer/newton_projection.h>

#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>

namespace {

constexpr const char* kUsage = "usage: curvature FIELD.json --at x,y,z";

cdp::Vec3 parse_point(const std::string& text) {
  std::stringstream in(text);
  cdp::Vec3 p;
  char c1 = 0, c2 = 0;
  if (!(in >> p.x() >> c1 >> p.y() >> c2 >> p.z()) || c1 != ',' || c2 != ',' || !(in >> std::ws).eof() ||
      !p.allFinite())
    throw cdp::InvalidInputError("--at expects three numbers x,y,z, found \"" + text + "\"");
  return p;
}

nlohmann::json vec(const cdp::Vec3& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

int main(int argc, char** argv) {
  cdp::app::install_signal_handling();
  try {
    std::string field_path, at;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--at" && i + 1 < argc) {
        if (!at.empty()) throw cdp::InvalidInputError("--at given twice");
        at = argv[++i];
      }
      else if (arg == "-h" || arg == "--help") {
        std::cout << kUsage << "\n";
        return 0;
      } else if (!arg.empty() && arg[0] != '-' && field_path.empty()) field_path = arg;
      else throw cdp::InvalidInputError("unexpected argument \"" + arg + "\"; " + kUsage);
    }
    if (field_path.empty() || at.empty()) throw cdp::InvalidInputError(kUsage);
    const cdp::Vec3 start = parse_point(at);
    const auto field = cdp::load_field(field_path);
    const cdp::ProjectionResult proj = cdp::project_to_surface(*field, start);
    if (!proj.ok())
      throw cdp::NoSurfaceError(field_path + ": cannot project " + at + " onto the surface: " +
                                cdp::to_string(proj.status));
    cdp::Curvature c;
    try {
      c = cdp::curvature_at(*field, proj.point);
    } catch (const cdp::NoSurfaceError& e) {
      // The library's message starts with its own name, which is also this program's.
      std::string why = e.what();
      if (why.rfind("curvature: ", 0) == 0) why.erase(0, 11);
      throw cdp::NoSurfaceError(field_path + ": no curvature at the projected point: " + why);
    }
    nlohmann::json out;
    out["projected"] = vec(proj.point);
    out["normal"] = vec(c.normal);
    out["k1"] = c.k1;
    out["k2"] = c.k2;
    out["dir1"] = vec(c.dir1);
    out["dir2"] = vec(c.dir2);
    out["gaussian"] = c.gaussian;
    out["mean"] = c.mean;
    out["mac"] = c.mac;
    out["min_radius"] = std::isfinite(c.min_radius) ? nlohmann::json(c.min_radius) : nlohmann::json(nullptr);
    out["shape_index"] = c.shape_index;
    out["newton_iterations"] = proj.iterations;
    std::cout << out.dump(2) << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "curvature: %s\n", e.what());
    return 1;
  }
}
