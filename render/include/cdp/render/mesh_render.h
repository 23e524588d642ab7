// Pictures of meshes for the paper's figures, ray cast with Embree (EmbreeScene): Blinn-Phong
// shading of the vertex normals blended at each hit, an optional wireframe drawn from the hit's
// barycentric coordinates, colour maps of per-vertex scalars, and glyphs of a field's principal
// directions. Orthographic projection, white background, deterministic pixels.
#pragma once

#include <cdp/render/color_map.h>
#include <cdp/render/png_image.h>

#include <cdp/core/field.h>
#include <cdp/core/mesh.h>

#include <optional>
#include <string>

namespace cdp {

enum class UpAxis { X, Y, Z };
// Throws InvalidInputError on anything but "x", "y" or "z".
UpAxis parse_up_axis(const std::string& name);

// The camera. At azimuth 0 and elevation 0 it looks at the focus from the axis that follows the
// up axis cyclically (up y: from +z; up z: from +x; up x: from +y), with the up axis pointing up
// in the picture. Azimuth turns the camera around the up axis (right-hand rule), elevation lifts
// it towards the up axis.
struct ViewOptions {
  int width = 800, height = 800;  // pixels, each in [1, 8192]
  double azimuth_deg = 0.0;       // any finite value, taken modulo 360
  double elevation_deg = 0.0;     // in [-90, 90]
  UpAxis up = UpAxis::Y;
  // The picture's shorter side spans the mesh's bounding sphere (half the box diagonal) divided
  // by zoom: zoom 1 shows the whole mesh from any direction, zoom 4 a quarter of it.
  double zoom = 1.0;
  // The point at the centre of the picture; empty: the centre of the mesh's box.
  std::optional<Vec3> focus;
};

struct RenderOptions {
  ViewOptions view;
  // Rays per pixel along each side (samples^2 per pixel, averaged), in [1, 8]; anti-aliases
  // silhouettes and wireframe lines.
  int samples = 2;
  // Darkens the points nearer than line_width_px / 2 pixels (on screen) to an edge of their
  // triangle: the screen distance to edge i is the barycentric b_i times the projected
  // triangle's altitude from vertex i (exact under the orthographic projection), so lines are
  // line_width_px wide at any mesh density.
  bool wireframe = false;
  double line_width_px = 1.0;
  // Name of a per-vertex scalar of the mesh to colour by ("" for none); values are blended at
  // the hit, then mapped. Default mapping: default_color_mapping(name, values).
  std::string color;
  std::optional<ColorMapping> mapping;
  // Principal-direction glyphs: on a grid of glyph_spacing_px, where a pixel centre hits the
  // mesh, curvature_at(*field, hit point) gives the directions of k1 (max, red) and k2 (min,
  // blue), drawn as short segments centred there (foreshortened as the directions project).
  // Points where |k1 - k2| < 5% of max(|k1|, |k2|) (near umbilics, directions undefined) and
  // points where the gradient vanishes get none.
  const Field* field = nullptr;
  bool directions = false;
  double glyph_spacing_px = 14.0;
};

struct RenderResult {
  Image image;
  double coverage = 0.0;                 // share of pixel samples that hit the mesh
  std::optional<ColorMapping> mapping;   // the mapping used, when colouring
  int glyphs = 0;                        // glyph centres drawn (each has two segments)
};

// Throws InvalidInputError on bad options, a mesh without triangles, a missing colour property
// (or one whose size is not the vertex count), directions without a field, or a camera that
// float ray casting cannot draw (the mesh under a pixel; pixels finer than 1e-6 of the rays'
// distance from the mesh's centre, from too large a zoom or too far a focus).
RenderResult render_mesh(const Mesh& mesh, const RenderOptions& options);

// Sets mesh.vertex_scalars "mac" and "shape_index" from curvature_at(field, vertex) (in
// parallel; NaN where the gradient vanishes), for meshes written without them.
void add_curvature_scalars(const Field& field, Mesh& mesh);

}  // namespace cdp
