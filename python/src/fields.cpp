// Fields: from JSON (a dict or a file), by keyword for the analytic, blob and expression models
// (all through the JSON factory, so that Python and the field files share one validation and
// one set of messages), and from Python functions.
#include "bindings.h"
#include "python_field.h"

#include <cdp/core/errors.h>
#include <cdp/io/field_factory.h>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace cdp::python {

namespace {

using FieldPtr = std::shared_ptr<Field>;

std::string type_name_of(py::handle h) { return py::str(py::type::handle_of(h).attr("__name__")); }

bool is_path(py::handle h) { return py::isinstance<py::str>(h) || py::hasattr(h, "__fspath__"); }

std::filesystem::path to_path(py::handle h) {
  return py::module_::import("os").attr("fspath")(h).cast<std::string>();
}

// `source` is what messages name the object by, as a file name names a field file.
FieldPtr field_from_dict(py::handle spec, const std::string& source, const std::filesystem::path& base_dir = {}) {
  const nlohmann::json j = to_json(spec, source);
  std::unique_ptr<Field> field;
  {
    // Data-driven models (vis, mpu) fit for seconds.
    py::gil_scoped_release release;
    field = make_field(j, source, base_dir);
  }
  return FieldPtr(std::move(field));
}

FieldPtr field_from_json(py::object spec, py::object base_dir) {
  if (py::isinstance<py::dict>(spec))
    return field_from_dict(spec, "cdp.field_from_json", base_dir.is_none() ? std::filesystem::path() : to_path(base_dir));
  if (is_path(spec)) {
    if (!base_dir.is_none())
      throw InvalidInputError(
          "cdp.field_from_json: base_dir applies to a dict; paths inside a field file resolve against its folder");
    const std::filesystem::path path = to_path(spec);
    std::unique_ptr<Field> field;
    {
      py::gil_scoped_release release;
      field = load_field(path);
    }
    return FieldPtr(std::move(field));
  }
  throw InvalidInputError("cdp.field_from_json: expected a dict or a path to a JSON file, found " + type_name_of(spec));
}

// Keyword constructors: the keys given (None means "the model's default") go to the factory.
py::dict spec(const char* type, std::initializer_list<std::pair<const char*, py::object>> keys) {
  py::dict d;
  d["type"] = type;
  for (const auto& [k, v] : keys)
    if (!v.is_none()) d[k] = v;
  return d;
}

double positive_or_default(const std::optional<double>& v, const char* what) {
  if (!v) return 0;
  if (!(std::isfinite(*v) && *v > 0))
    throw InvalidInputError(std::string("cdp.callable_field: ") + what + " must be a positive number, not " +
                            std::string(py::str(py::float_(*v))));
  return *v;
}

std::shared_ptr<PythonField> callable_field(py::object f, py::object bounds, py::object gradient, py::object hessian,
                                            std::optional<double> lipschitz, std::optional<double> gradient_step,
                                            std::optional<double> hessian_step, bool smooth) {
  const auto check_callable = [](const py::object& o, const char* what, bool optional) {
    if (optional && o.is_none()) return;
    if (!PyCallable_Check(o.ptr()))
      throw InvalidInputError(std::string("cdp.callable_field: ") + what + " must be callable, found " + type_name_of(o));
  };
  check_callable(f, "f", false);
  check_callable(gradient, "gradient", true);
  check_callable(hessian, "hessian", true);
  const Box box = box_from(bounds, "cdp.callable_field: bounds");
  if (lipschitz) positive_or_default(lipschitz, "lipschitz");
  return std::make_shared<PythonField>(PythonFieldFunctions{f, gradient, hessian}, box, lipschitz,
                                       positive_or_default(gradient_step, "gradient_step"),
                                       positive_or_default(hessian_step, "hessian_step"), smooth);
}

py::dict counts_dict(const EvaluationCounts& c) {
  py::dict d;
  d["value"] = c.value;
  d["value_gradient"] = c.value_gradient;
  d["gradient_hessian"] = c.gradient_hessian;
  d["total"] = c.total();
  return d;
}

std::string repr(const Field& f) {
  const Box& b = f.bounds();
  return "<cdp.Field " + f.type_name() + " bounds=(" + point_text(b.min) + ", " + point_text(b.max) + ")>";
}

}  // namespace

void bind_fields(py::module_& m) {
  py::class_<Field, FieldPtr>(m, "Field", py::dynamic_attr(),
                              "An implicit field F: negative inside, positive outside, zero on the surface. Made by "
                              "field_from_json, the model functions (sphere, torus, ...) or callable_field.")
      .def_property_readonly("type", &Field::type_name, "The model's type name as written in JSON.")
      .def_property_readonly(
          "bounds", [](const Field& f) { return to_array(f.bounds()); },
          "The box that contains the surface, as a (2, 3) array: min row, max row.")
      .def_property_readonly(
          "lipschitz_bound",
          [](const Field& f) -> py::object {
            const auto b = f.lipschitz_bound();
            return b ? py::object(py::float_(*b)) : py::object(py::none());
          },
          "A bound on |F(a) - F(b)| / |a - b| inside the box when the model knows one, else None.")
      .def_property_readonly("smooth", &Field::smooth,
                             "Whether the model promises a regular zero set, without creases, cusps or nodes (VIS, "
                             "MPU, blobs, analytic models, the compiled tanglecube and double torus; a callable_field "
                             "made with smooth=True; never an expression).")
      .def(
          "values",
          [](const Field& f, py::handle points) {
            const std::vector<Vec3> p = points_from(points, "points");
            std::vector<double> out(p.size());
            {
              py::gil_scoped_release release;
              f.values(p.data(), out.data(), p.size());
            }
            return to_array(out);
          },
          py::arg("points"), "F at each row of an (N, 3) array: an (N,) array (one batched evaluation).")
      .def(
          "gradients",
          [](const Field& f, py::handle points) {
            const std::vector<Vec3> p = points_from(points, "points");
            std::vector<Vec3> out(p.size());
            {
              py::gil_scoped_release release;
              std::vector<double> values(p.size());
              for (std::size_t s = 0; s < p.size(); s += kBindingBatch)
                f.values_gradients(&p[s], &values[s], &out[s], std::min(kBindingBatch, p.size() - s));
            }
            return to_array(out);
          },
          py::arg("points"), "grad F at each row of an (N, 3) array: (N, 3) (one value_gradient per point, batched).")
      .def(
          "hessians",
          [](const Field& f, py::handle points) {
            const std::vector<Vec3> p = points_from(points, "points");
            std::vector<Mat3> h(p.size());
            {
              py::gil_scoped_release release;
              std::vector<double> values(p.size());
              std::vector<Vec3> g(p.size());
              for (std::size_t s = 0; s < p.size(); s += kBindingBatch)
                f.gradients_hessians(&p[s], &values[s], &g[s], &h[s], std::min(kBindingBatch, p.size() - s));
            }
            py::array_t<double> out({static_cast<py::ssize_t>(p.size()), py::ssize_t{3}, py::ssize_t{3}});
            double* d = out.mutable_data();
            for (std::size_t i = 0; i < p.size(); ++i)
              for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) d[9 * i + 3 * r + c] = h[i](r, c);
            return out;
          },
          py::arg("points"), "The Hessian of F at each row of an (N, 3) array: (N, 3, 3) (one gradient_hessian per point, batched).")
      .def(
          "counts", [](const Field& f) { return counts_dict(f.counts()); },
          "Evaluations so far by kind: value (single or batched points), value_gradient, gradient_hessian, total.")
      .def("reset_counts", &Field::reset_counts)
      .def("__repr__", &repr);

  py::class_<PythonField, Field, std::shared_ptr<PythonField>>(
      m, "CallableField", "A field whose value (and optionally gradient and Hessian) are Python functions; see callable_field.")
      .def_property_readonly("python_calls", &PythonField::python_calls, "Calls into the Python functions so far.")
      .def("reset_python_calls", &PythonField::reset_python_calls)
      .def_property_readonly("gradient_step", &PythonField::gradient_step,
                             "The central-difference step of first derivatives (of F, or of the given gradient).")
      .def_property_readonly("hessian_step", &PythonField::hessian_step,
                             "The step of the second differences of F (used when neither gradient nor hessian is given).");

  m.def("field_from_json", &field_from_json, py::arg("spec"), py::arg("base_dir") = py::none(),
        "A field from a JSON object (a dict, checked by the same factory as field files; relative file names in it "
        "resolve against base_dir, else the working directory) or from a field file (str or os.PathLike).");
  m.def("field_types", &registered_field_types, "The model type names field_from_json knows.");

  m.def(
      "sphere",
      [](py::object radius, py::object center, py::object bounds) {
        return field_from_dict(spec("sphere", {{"radius", radius}, {"center", center}, {"bounds", bounds}}), "cdp.sphere");
      },
      py::arg("radius"), py::arg("center") = py::none(), py::arg("bounds") = py::none(),
      "{\"type\": \"sphere\"}: the signed distance to a sphere of the given radius around center (default None: the "
      "origin). bounds ((xmin, ymin, zmin), (xmax, ymax, zmax)), default None: the sphere's box grown by 10% of the "
      "radius.");
  m.def(
      "ellipsoid",
      [](py::object radii, py::object center, py::object bounds) {
        return field_from_dict(spec("ellipsoid", {{"radii", radii}, {"center", center}, {"bounds", bounds}}), "cdp.ellipsoid");
      },
      py::arg("radii"), py::arg("center") = py::none(), py::arg("bounds") = py::none(),
      "{\"type\": \"ellipsoid\"}: the axis-aligned ellipsoid with radii (rx, ry, rz) around center (default None: the "
      "origin); bounds (default None: its box grown by 10% of each radius) as for sphere.");
  m.def(
      "torus",
      [](py::object major_radius, py::object minor_radius, py::object center, py::object bounds) {
        return field_from_dict(spec("torus", {{"major_radius", major_radius},
                                              {"minor_radius", minor_radius},
                                              {"center", center},
                                              {"bounds", bounds}}),
                               "cdp.torus");
      },
      py::arg("major_radius"), py::arg("minor_radius"), py::arg("center") = py::none(), py::arg("bounds") = py::none(),
      "{\"type\": \"torus\"}: the signed distance to a ring torus around the z axis through center (default None: "
      "the origin), 0 < minor_radius < major_radius; bounds (default None: its box grown by 10% of minor_radius) as "
      "for sphere.");
  m.def(
      "blobs",
      [](py::object blobs, py::object threshold, py::object kernel, py::object bounds) {
        // (center, radius) and (center, radius, strength) tuples are spelled out as the JSON's
        // objects; anything else goes to the factory as it is, to be refused there by name.
        py::object items = blobs;
        if (py::isinstance<py::list>(blobs) || py::isinstance<py::tuple>(blobs)) {
          py::list list;
          for (auto b : blobs) {
            if ((py::isinstance<py::tuple>(b) || py::isinstance<py::list>(b)) && (py::len(b) == 2 || py::len(b) == 3)) {
              py::dict d;
              d["center"] = b[py::int_(0)];
              d["radius"] = b[py::int_(1)];
              if (py::len(b) == 3) d["strength"] = b[py::int_(2)];
              list.append(d);
            } else {
              list.append(b);
            }
          }
          items = list;
        }
        return field_from_dict(
            spec("blobs", {{"blobs", items}, {"threshold", threshold}, {"kernel", kernel}, {"bounds", bounds}}), "cdp.blobs");
      },
      py::arg("blobs"), py::arg("threshold"), py::arg("kernel") = py::none(), py::arg("bounds") = py::none(),
      "{\"type\": \"blobs\"}: the surface where the sum of the blobs' kernels reaches threshold. blobs is a list of "
      "{\"center\", \"radius\", \"strength\"} dicts or (center, radius[, strength]) tuples; kernel (default None) "
      "\"wyvill\" (the default) or \"blinn\"; bounds (default None: the box of every blob's reach) as for sphere.");
  m.def(
      "expression",
      [](py::object formula, py::object bounds, py::object params, py::object define) {
        return field_from_dict(
            spec("expression", {{"value", formula}, {"bounds", bounds}, {"params", params}, {"define", define}}),
            "cdp.expression");
      },
      py::arg("formula"), py::arg("bounds"), py::arg("params") = py::none(), py::arg("define") = py::none(),
      "{\"type\": \"expression\"}: a formula in x, y, z with exact derivatives (messages call the formula \"value\", "
      "its JSON key); params names numbers, define names sub-expressions ({\"r\": \"sqrt(x^2+y^2)\"}) the formula "
      "and each other may use.");

  m.def("callable_field", &callable_field, py::arg("f"), py::arg("bounds"), py::arg("gradient") = py::none(),
        py::arg("hessian") = py::none(), py::kw_only(), py::arg("lipschitz") = py::none(),
        py::arg("gradient_step") = py::none(), py::arg("hessian_step") = py::none(), py::arg("smooth") = false,
        "A field from Python functions called on (N, 3) float64 arrays: f -> (N,), gradient -> (N, 3), hessian -> "
        "(N, 3, 3); bounds ((xmin, ymin, zmin), (xmax, ymax, zmax)) holds the surface. Missing derivatives come from "
        "central differences: gradient_step (default None: 1e-5 of the box diagonal) for first derivatives, "
        "hessian_step (default None: 1e-4 of it) for second differences of f. lipschitz (default None: estimated "
        "where an algorithm needs it, as evaluate's ray casting does) bounds |f(a) - f(b)| / |a - b| in the box. "
        "smooth=True (default False) promises a regular zero set (the gradient continuous and nonzero where the surface "
        "passes: no min, max, abs or branch on the coordinates there, no node): the adaptive method's repair then "
        "skips its crease probes, three calls per vertex it touches, and a bend tighter than the differences resolve is meshed across rather than stopping the run as a crease would. See python/README.md for how often the algorithms call them.");
}

}  // namespace cdp::python
