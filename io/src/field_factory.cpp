#include <cdp/core/errors.h>
#include <cdp/core/models/analytic.h>
#include <cdp/core/models/blobs.h>
#include <cdp/core/models/expression.h>
#include <cdp/core/models/mpu.h>
#include <cdp/core/models/vis.h>
#include <cdp/core/oriented_points.h>
#include <cdp/io/field_factory.h>
#include <cdp/io/mesh_io.h>
#include <cdp/io/volume_io.h>

#include <map>
#include <mutex>

#include <cdp/core/models/compiled.h>

namespace cdp {

namespace {

struct Registry {
  std::mutex mutex;
  std::map<std::string, FieldBuilder> builders;
};

std::unique_ptr<Field> build_sphere(JsonReader& r) {
  return std::make_unique<Sphere>(r.vec3("center", Vec3::Zero()), r.positive_number("radius"));
}

std::unique_ptr<Field> build_ellipsoid(JsonReader& r) {
  const Vec3 radii = r.vec3("radii");
  if ((radii.array() <= 0).any()) r.fail("radii", "every radius must be positive");
  return std::make_unique<Ellipsoid>(r.vec3("center", Vec3::Zero()), radii);
}

std::unique_ptr<Field> build_torus(JsonReader& r) {
  const Vec3 center = r.vec3("center", Vec3::Zero());
  const double major = r.positive_number("major_radius");
  const double minor = r.positive_number("minor_radius");
  if (minor >= major) r.fail("minor_radius", "must be smaller than major_radius (a ring torus)");
  return std::make_unique<Torus>(center, major, minor);
}

std::unique_ptr<Field> build_blobs(JsonReader& r) {
  const std::string kernel = r.choice("kernel", {"wyvill", "blinn"}, "wyvill");
  const double threshold = r.positive_number("threshold");
  std::vector<Blob> blobs;
  for (auto& b : r.objects("blobs")) {
    Blob blob;
    blob.center = b.vec3("center");
    blob.radius = b.positive_number("radius");
    blob.strength = b.number("strength", 1.0);
    b.finish({"center", "radius", "strength"});
    blobs.push_back(blob);
  }
  if (blobs.empty()) r.fail("blobs", "needs at least one blob");
  return std::make_unique<Blobs>(kernel == "wyvill" ? BlobKernel::Wyvill : BlobKernel::Blinn, threshold,
                                 std::move(blobs));
}

std::unique_ptr<Field> build_expression(JsonReader& r) {
  const std::string formula = r.string("value");
  std::map<std::string, double> params;
  if (r.has("params")) {
    const auto& p = r.raw("params");
    if (!p.is_object()) r.fail("params", "expected an object {\"name\": number, ...}");
    for (const auto& [name, v] : p.items()) {
      if (!v.is_number()) r.fail("params." + name, "expected a number");
      params[name] = v.get<double>();
    }
  }
  std::map<std::string, std::string> definitions;
  if (r.has("define")) {
    const auto& d = r.raw("define");
    if (!d.is_object()) r.fail("define", "expected an object {\"name\": \"formula\", ...}");
    for (const auto& [name, v] : d.items()) {
      if (!v.is_string()) r.fail("define." + name, "expected a formula (a string)");
      definitions[name] = v.get<std::string>();
    }
  }
  if (!r.has("bounds")) r.fail("bounds", "missing required key (an expression has no box of its own)");
  const Box bounds = r.box("bounds");
  try {
    return std::make_unique<Expression>(formula, params, bounds, definitions);
  } catch (const InvalidInputError& e) {
    r.fail("value", e.what());
  }
}

// Data-driven models: "points" names a mesh file relative to the JSON file; errors from reading
// or fitting it are reported under that key, with the mesh file named.
std::unique_ptr<Field> build_vis(JsonReader& r) {
  r.check_keys({"type", "bounds", "points", "constraints", "normal_offset"});
  const std::filesystem::path path = r.file("points");
  VisOptions options;
  const long long constraints = r.integer("constraints", static_cast<long long>(options.constraints));
  if (constraints < 8 || constraints % 2 != 0) r.fail("constraints", "must be even and at least 8 (two per point)");
  options.constraints = static_cast<std::size_t>(constraints);
  options.normal_offset = r.positive_number("normal_offset", options.normal_offset);
  if (!(options.normal_offset < 0.1)) r.fail("normal_offset", "must be below 0.1 (a fraction of the box diagonal)");
  try {
    return make_vis(read_oriented_points(path), options, path.string());
  } catch (const InvalidInputError& e) {
    r.fail("points", e.what());
  }
}

std::unique_ptr<Field> build_mpu(JsonReader& r) {
  r.check_keys({"type", "bounds", "points", "max_error", "support_factor", "min_points", "max_depth"});
  const std::filesystem::path path = r.file("points");
  MpuOptions options;
  options.max_error = r.positive_number("max_error", options.max_error);
  options.support_factor = r.positive_number("support_factor", options.support_factor);
  const long long min_points = r.integer("min_points", options.min_points);
  if (min_points < 10) r.fail("min_points", "must be at least 10 (a general quadric has 10 coefficients)");
  options.min_points = static_cast<int>(std::min<long long>(min_points, 1'000'000));
  const long long max_depth = r.integer("max_depth", options.max_depth);
  if (max_depth < 1 || max_depth > 20) r.fail("max_depth", "must be in 1..20");
  options.max_depth = static_cast<int>(max_depth);
  if (!(options.support_factor > 0.5 && options.support_factor <= 2))
    r.fail("support_factor", "must be in (0.5, 2] (from 0.5 down the supports leave gaps between cells)");
  try {
    return std::make_unique<Mpu>(read_oriented_points(path), options, path.string());
  } catch (const InvalidInputError& e) {
    r.fail("points", e.what());
  }
}

// A sampled volume: "file" (.npy or .nrrd, relative to the JSON file), placed by "bounds" (the
// grid spans the box) or by "origin" and "spacing" (a number or one per axis; an NRRD file's
// own by default, else 0 and 1).
std::unique_ptr<Field> build_volume(JsonReader& r) {
  r.check_keys({"type", "bounds", "file", "level", "inside", "origin", "spacing"});
  const std::filesystem::path path = r.file("file");
  VolumeSamples samples;
  try {
    samples = read_volume(path);
  } catch (const InvalidInputError& e) {
    r.fail("file", e.what());
  }
  if (r.has("bounds")) {
    if (r.has("origin") || r.has("spacing")) r.fail("bounds", "give either bounds or origin and spacing, not both");
    const Box box = r.box("bounds");
    samples.origin = box.min;
    for (int a = 0; a < 3; ++a) samples.spacing[a] = box.size()[a] / static_cast<double>(samples.dims[a] - 1);
  } else {
    samples.origin = r.vec3("origin", samples.origin);
    if (r.has("spacing")) {
      if (r.raw("spacing").is_number()) samples.spacing = Vec3::Constant(r.positive_number("spacing"));
      else samples.spacing = r.vec3("spacing");
    }
  }
  const double level = r.number("level", 0.0);
  const VolumeInside inside = r.choice("inside", {"below", "above"}, "below") == "below" ? VolumeInside::Below : VolumeInside::Above;
  try {
    return std::make_unique<Volume>(std::move(samples), level, inside);
  } catch (const InvalidInputError& e) {
    r.fail("file", e.what());
  }
}

Registry& registry() {
  static Registry* reg = [] {
    auto* r = new Registry;
    r->builders["sphere"] = build_sphere;
    r->builders["ellipsoid"] = build_ellipsoid;
    r->builders["torus"] = build_torus;
    r->builders["blobs"] = build_blobs;
    r->builders["expression"] = build_expression;
    r->builders["vis"] = build_vis;
    r->builders["mpu"] = build_mpu;
    r->builders["volume"] = build_volume;
    for (auto& [name, make] : compiled_models())
      r->builders[name] = [make = std::move(make)](JsonReader&) { return make(); };
    return r;
  }();
  return *reg;
}

}  // namespace

void register_field_type(const std::string& type, FieldBuilder builder) {
  auto& reg = registry();
  std::lock_guard lock(reg.mutex);
  reg.builders[type] = std::move(builder);
}

std::vector<std::string> registered_field_types() {
  auto& reg = registry();
  std::lock_guard lock(reg.mutex);
  std::vector<std::string> names;
  for (const auto& [name, b] : reg.builders) names.push_back(name);
  return names;
}

std::unique_ptr<Field> make_field(JsonReader& reader) {
  const std::string type = reader.string("type");
  FieldBuilder builder;
  {
    auto& reg = registry();
    std::lock_guard lock(reg.mutex);
    auto it = reg.builders.find(type);
    if (it == reg.builders.end()) {
      std::string list;
      for (const auto& [name, b] : reg.builders) list += (list.empty() ? "" : ", ") + name;
      reader.fail("type", "unknown model type \"" + type + "\" (known: " + list + ")");
    }
    builder = it->second;
  }
  std::unique_ptr<Field> field = builder(reader);
  if (reader.has("bounds")) field->set_bounds(reader.box("bounds"));
  reader.finish({"type", "bounds"});
  if (!field->bounds().valid()) reader.fail("the model has no valid bounding box; give \"bounds\"");
  return field;
}

std::unique_ptr<Field> make_field(const nlohmann::json& spec, const std::string& source,
                                  const std::filesystem::path& base_dir) {
  JsonReader reader(spec, source, "", base_dir);
  return make_field(reader);
}

std::unique_ptr<Field> load_field(const std::filesystem::path& path) {
  const nlohmann::json spec = read_json_file(path);
  return make_field(spec, path.string(), path.parent_path());
}

}  // namespace cdp
