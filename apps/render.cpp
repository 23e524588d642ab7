// build/bin/render MESH -o OUT.png [options]
// A picture of a mesh ray cast with Embree: shading, wireframe, colour maps of vertex scalars,
// principal-direction glyphs of a field. Prints one JSON line describing what it drew (the
// colour map and range, so a script can draw a matching colour bar).
#include "support/app_support.h"
#include "support/command_line.h"

#include <cdp/render/mesh_render.h>
#include <cdp/render/png_image.h>

#include <cdp/core/errors.h>
#include <cdp/io/atomic_write.h>
#include <cdp/io/field_factory.h>
#include <cdp/io/mesh_io.h>
#include <cdp/raytrace/phong_normal.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  cdp::app::install_signal_handling();
  cdp::app::keep_freed_memory();
  try {
    CLI::App app{"A picture of MESH (Embree ray casting): shading, wireframe, colour maps of vertex properties,\n"
                 "principal directions of a field. Prints one JSON line saying what it drew.\n",
                 "render"};
    cdp::app::configure(app);
    std::string mesh_path, out_path, field_path, color = "none", range, up = "y", focus;
    cdp::RenderOptions options;
    app.add_option("MESH", mesh_path, "the mesh: .ply, .obj, .off or .stl")->required()->type_name("")->check(cdp::app::path_name());
    app.add_option("-o", out_path, "the picture (PNG)")->required()->type_name("OUT.png")->check(cdp::app::path_name());
    app.add_option("--width", options.view.width, "picture width in pixels, in [1, 8192]")
        ->capture_default_str()
        ->type_name("W")
        ->transform(cdp::app::integer_in(1, 8192));
    app.add_option("--height", options.view.height, "picture height in pixels, in [1, 8192]")
        ->capture_default_str()
        ->type_name("H")
        ->transform(cdp::app::integer_in(1, 8192));
    app.add_option("--azimuth", options.view.azimuth_deg, "turn of the camera around the up axis, in degrees")
        ->capture_default_str()
        ->type_name("DEG")
        ->transform(cdp::app::number());
    app.add_option("--elevation", options.view.elevation_deg, "lift of the camera towards the up axis, in [-90, 90] degrees")
        ->capture_default_str()
        ->type_name("DEG")
        ->transform(cdp::app::number_in(-90, 90));
    app.add_option("--up", up, "the model's up axis: x, y or z")
        ->capture_default_str()
        ->type_name("AXIS")
        ->check(CLI::IsMember({"x", "y", "z"}));
    app.add_option("--zoom", options.view.zoom, "1 shows the whole mesh, 3 a third of it")
        ->capture_default_str()
        ->type_name("Z")
        ->transform(cdp::app::positive_number());
    app.add_option("--focus", focus, "the point at the picture's centre (default: the centre of the mesh's box)")
        ->type_name("x,y,z")
        ->check(cdp::app::numbers(3, "x,y,z"));
    app.add_option("--samples", options.samples, "N x N rays per pixel, N in [1, 8]")
        ->capture_default_str()
        ->type_name("N")
        ->transform(cdp::app::integer_in(1, 8));
    app.add_flag("--wireframe", options.wireframe, "draw the edges");
    app.add_option("--line-width", options.line_width_px, "width of the edges in pixels")
        ->capture_default_str()
        ->type_name("PX")
        ->transform(cdp::app::positive_number());
    app.add_option("--color", color, "colour by a vertex property: mac, shape_index or any other, or none")
        ->capture_default_str()
        ->type_name("PROPERTY")
        ->check(cdp::app::non_empty("a property name or none"));
    app.add_option("--range", range, "the colour map's range (default: 2nd to 98th percentile)")
        ->type_name("LO,HI")
        ->check(cdp::app::numbers(2, "LO,HI"));
    app.add_option("--field", field_path, "the field, for mac and shape_index of meshes without them, for --directions and for each side's "
                   "normal at vertices on creases")
        ->type_name("FIELD.json")
        ->check(cdp::app::path_name());
    app.add_flag("--directions", options.directions, "draw the principal directions (needs --field)");
    app.add_option("--spacing", options.glyph_spacing_px, "pixels between principal-direction glyphs, at least 2")
        ->capture_default_str()
        ->type_name("PX")
        ->transform(cdp::app::number());
    if (const auto status = cdp::app::parse(app, argc, argv)) return *status;
    options.view.up = cdp::parse_up_axis(up);
    if (!focus.empty()) {
      const std::vector<double> f = cdp::app::split_numbers(focus);
      options.view.focus = cdp::Vec3(f[0], f[1], f[2]);
    }
    std::vector<std::filesystem::path> inputs{mesh_path};
    if (!field_path.empty()) inputs.push_back(field_path);
    cdp::app::check_output_paths({{"-o", out_path}}, inputs);
    if (std::filesystem::path(out_path).extension() != ".png")
      throw cdp::InvalidInputError(out_path + ": the output must be a .png file");
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
        const auto r = cdp::app::split_numbers(range);
        cdp::ColorMapping m = cdp::default_color_mapping(color, mesh.vertex_scalars.at(color));
        m.lo = r[0];
        m.hi = r[1];
        options.mapping = m;
      }
    }
    options.field = field.get();
    // With the field, a vertex on a crease of a min/max/abs field is shaded with each side's
    // normal rather than their blend (the file's vertex normals cannot hold two).
    if (field) {
      if (mesh.normals.size() != mesh.positions.size()) mesh.normals = cdp::area_weighted_normals(mesh);
      mesh.corner_normals = cdp::field_corner_normals(*field, mesh, mesh.normals);
    }
    const cdp::RenderResult result = cdp::render_mesh(mesh, options);
    // A picture of the background alone is a camera pointed away from the mesh, not a picture
    // of it: written with exit 0 it would pass for one.
    if (result.coverage == 0)
      throw cdp::InvalidInputError(mesh_path + ": no pixel of the picture shows the mesh: the camera looks away from it "
                                   "(see --focus, --zoom, --azimuth, --elevation)");
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
