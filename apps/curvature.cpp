// build/bin/curvature FIELD.json --at x,y,z
// Projects the point onto the surface and prints the curvature measures there as one JSON object.
#include "support/app_support.h"
#include "support/command_line.h"

#include <cdp/core/curvature.h>
#include <cdp/core/errors.h>
#include <cdp/core/newton_projection.h>
#include <cdp/io/field_factory.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

namespace {

nlohmann::json vec(const cdp::Vec3& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

int main(int argc, char** argv) {
  cdp::app::install_signal_handling();
  cdp::app::keep_freed_memory();
  try {
    CLI::App app{"Projects a point onto the surface of FIELD.json (Newton's method) and prints the curvature\n"
                 "measures there as one JSON object.\n",
                 "curvature"};
    cdp::app::configure(app);
    std::string field_path, at;
    app.add_option("FIELD.json", field_path, "the field file")->required()->type_name("")->check(cdp::app::path_name());
    app.add_option("--at", at, "the point to project")->required()->type_name("x,y,z")->check(cdp::app::numbers(3, "x,y,z"));
    if (const auto status = cdp::app::parse(app, argc, argv)) return *status;
    const std::vector<double> xyz = cdp::app::split_numbers(at);
    const cdp::Vec3 start(xyz[0], xyz[1], xyz[2]);
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
