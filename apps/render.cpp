// build/bin/render MESH -o OUT.png [options]
// A picture of a mesh ray cast with Embree: shading, wireframe, colour maps of vertex scalars,
// principal-direction glyphs of a field. Prints one JSON line describing what it drew (the
// colour map and range, so a script can draw a matching colour bar).
#include "support/app_support.h"

#include <raytrace/mesh_render.h>
#include <raytrace/png_image.h>

#include <polygonizer/atomic_write.h>
#include <polygonizer/errors.h>
#include <polygonizer/field_factory.h>
#include <polygonizer/mesh_io.h>

#include <nlohmann/json.hpp>


#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

constexpr const char* kUsage =
    "usage: render MESH -o OUT.png [--width W] [--height H] [--azimuth DEG] [--elevation DEG] [--up x|y|z] "
    "[--zoom Z] [--focus x,y,z] [--samples N] [--wireframe] [--line-width PX] "
    "[--color none|mac|shape_index|PROPERTY] [--range LO,HI] [--field FIELD.json] [--directions] [--spacing PX]";

std::vector<double> parse_numbers(const std::string& option, const std::string& text, std::size_t count) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  bool ok = !text.empty() && text.back() != ',';
  while (ok && std::getline(in, item, ',')) {
    std::size_t used = 0;
    try {
      values.push_back(std::stod(item, &used));
    } catch (const std::exception&) {
      ok = false;
    }
    ok = ok && used == item.size() && std::isfinite(values.back());
  }
  if (!ok || values.size() != count)
    throw cdp::InvalidInputError(option + " expects " +
                                 (count == 1 ? std::string("a number") : std::to_string(count) + " comma-separated numbers") +
                                 ", found \"" + text + "\"");
  return values;
}

int parse_int(const std::string& option, const std::string& text) {
  const double v = parse_numbers(option, text, 1)[0];
  if (v != std::floor(v) || std::abs(v) > 1e9) throw cdp::InvalidInputError(option + " expects an integer, found \"" + text + "\"");
  return static_cast<int>(v);
}

}  // namespace

int main(int argc, char** argv) {
  cdp::app::install_signal_handling();
  try {
    std::string mesh_path, out_path, field_path, color = "none", range;
    cdp::RenderOptions options;
    std::set<std::string> seen;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      const bool has_value = i + 1 < argc;
      auto value = [&]() -> std::string {
        if (!has_value) throw cdp::InvalidInputError(arg + " needs a value; " + kUsage);
        // Each option once: a second value would silently replace the first.
        if (!seen.insert(arg).second) throw cdp::InvalidInputError(arg + " given twice");
        return argv[++i];
      };
      if (arg == "-h" || arg == "--help") {
        std::cout << kUsage << "\n";
        return 0;
      } else if (arg == "-o") out_path = value();
      else if (arg == "--width") options.view.width = parse_int(arg, value());
      else if (arg == "--height") options.view.height = parse_int(arg, value());
      else if (arg == "--azimuth") options.view.azimuth_deg = parse_numbers(arg, value(), 1)[0];
      else if (arg == "--elevation") options.view.elevation_deg = parse_numbers(arg, value(), 1)[0];
      else if (arg == "--up") options.view.up = cdp::parse_up_axis(value());
      else if (arg == "--zoom") options.view.zoom = parse_numbers(arg, value(), 1)[0];
      else if (arg == "--focus") {
        const auto f = parse_numbers(arg, value(), 3);
        options.view.focus = cdp::Vec3(f[0], f[1], f[2]);
      } else if (arg == "--samples") options.samples = parse_int(arg, value());
      else if (arg == "--wireframe") options.wireframe = true;
      else if (arg == "--line-width") options.line_width_px = parse_numbers(arg, value(), 1)[0];
      else if (arg == "--color") color = value();
      else if (arg == "--range") range = value();
      else if (arg == "--field") field_path = value();
      else if (arg == "--directions") options.directions = true;
      else if (arg == "--spacing") options.glyph_spacing_px = parse_numbers(arg, value(), 1)[0];
      else if (!arg.empty() && arg[0] != '-' && mesh_path.empty()) mesh_path = arg;
      else throw cdp::InvalidInputError("unexpected argument \"" + arg + "\"; " + kUsage);
    }
    if (mesh_path.empty() || out_path.empty()) throw cdp::InvalidInputError(kUsage);
    std::vector<std::filesystem::path> inputs{mesh_path};
    if (!field_path.empty()) inputs.push_back(field_path);
    cdp::app::check_output_paths({{"-o", out_path}}, inputs);
    if (std::filesystem::path(out_path).extension() != ".png")
      throw cdp::InvalidInputError(out_path + ": the output must be a .png file");
    if (color.empty()) throw cdp::InvalidInputError("--color needs a property name or none");
    if (options.directions && field_path.empty())
      throw cdp::InvalidInputError("--directions needs --field FIELD.json (the curvature comes from the field)");
    if (!range.empty() && color == "none") throw cdp::InvalidInputError("--range needs --color");

    cdp::Mesh mesh = cdp::read_mesh(mesh_path);
    if (mesh.triangles.empty()) throw cdp::InvalidInputError(mesh_path + ": the mesh has no triangles");
    std::unique_ptr<cdp::Field> field;
    if (!field_path.empty()) field = cdp::load_field(field_path);
    if (color != "none") {
      options.color = color;
      if (!mesh.vertex_scalars.count(color)) {
        if (field && (color == "mac" || color == "shape_index")) cdp::add_curvature_scalars(*field, mesh);
        else
          throw cdp::InvalidInputError(mesh_path + ": no vertex property \"" + color + "\"" +
                                       (color == "mac" || color == "shape_index" ? " (give --field FIELD.json to compute it)" : ""));
      }
      if (!range.empty()) {
        const auto r = parse_numbers("--range", range, 2);
        cdp::ColorMapping m = cdp::default_color_mapping(color, mesh.vertex_scalars.at(color));
        m.lo = r[0];
        m.hi = r[1];
        options.mapping = m;
      }
    }
    options.field = field.get();
    const cdp::RenderResult result = cdp::render_mesh(mesh, options);
    {
      const std::vector<std::uint8_t> png = cdp::encode_png(result.image);
      cdp::write_file_atomically(out_path, std::string_view(reinterpret_cast<const char*>(png.data()), png.size()),
                                 "the picture");
    }

    nlohmann::json summary{{"output", out_path},
                           {"width", result.image.width},
                           {"height", result.image.height},
                           {"triangles", mesh.num_triangles()},
                           {"coverage", result.coverage}};
    if (result.mapping)
      summary["color"] = {{"property", color},
                          {"map", cdp::to_string(result.mapping->kind)},
                          {"scale", cdp::to_string(result.mapping->scale)},
                          {"range", {result.mapping->lo, result.mapping->hi}}};
    if (options.directions) summary["glyphs"] = result.glyphs;
    std::cout << summary.dump() << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "render: %s\n", e.what());
    return 1;
  }
}
