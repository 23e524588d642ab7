#include "bindings.h"

#include <cdp/core/errors.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>

namespace cdp::python {

namespace {

static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 arrays are copied as packed doubles");
static_assert(sizeof(std::array<int, 3>) == 3 * sizeof(int), "faces are copied as packed ints");

std::string shape_of(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string type_of(py::handle h) { return py::str(py::type::handle_of(h).attr("__name__")); }

// Deeper than any field file; a self-referencing list would otherwise recurse until the C
// stack runs out.
constexpr int kMaxDepth = 256;

// `source` names the object, `path` the place inside it: "cdp.sphere: center[1]: problem".
nlohmann::json json_at(py::handle h, const std::string& source, const std::string& path, int depth) {
  const auto fail = [&](const std::string& problem) -> InvalidInputError {
    return InvalidInputError(source + ": " + (path.empty() ? "" : path + ": ") + problem);
  };
  if (depth > kMaxDepth) throw fail("nested too deeply");
  if (h.is_none()) return nullptr;
  if (py::isinstance<py::bool_>(h)) return h.cast<bool>();
  if (PyLong_Check(h.ptr())) {
    int overflow = 0;
    const long long v = PyLong_AsLongLongAndOverflow(h.ptr(), &overflow);
    if (overflow != 0) throw fail("the integer " + std::string(py::str(h)) + " is too large");
    return v;
  }
  if (PyFloat_Check(h.ptr())) {
    const double v = PyFloat_AsDouble(h.ptr());
    if (!std::isfinite(v)) throw fail(std::string(py::str(h)) + " is not a finite number (JSON has none)");
    return v;
  }
  if (py::isinstance<py::str>(h)) return h.cast<std::string>();
  if (py::isinstance<py::dict>(h)) {
    nlohmann::json object = nlohmann::json::object();
    for (auto [key, value] : h.cast<py::dict>()) {
      if (!py::isinstance<py::str>(key)) throw fail("keys must be strings, found " + type_of(key) + " " + std::string(py::repr(key)));
      const std::string k = key.cast<std::string>();
      object[k] = json_at(value, source, path.empty() ? k : path + "." + k, depth + 1);
    }
    return object;
  }
  if (py::isinstance<py::list>(h) || py::isinstance<py::tuple>(h)) {
    nlohmann::json array = nlohmann::json::array();
    std::size_t i = 0;
    for (auto item : h) array.push_back(json_at(item, source, path + "[" + std::to_string(i++) + "]", depth + 1));
    return array;
  }
  // numpy arrays and scalars (np.float64 is a float already, np.int64 and np.bool_ are not).
  const py::module_ numpy = py::module_::import("numpy");
  if (py::isinstance(h, numpy.attr("ndarray")) || py::isinstance(h, numpy.attr("generic")))
    return json_at(h.attr("tolist")(), source, path, depth + 1);
  if (py::hasattr(h, "__fspath__")) return json_at(py::module_::import("os").attr("fspath")(h), source, path, depth + 1);
  throw fail("a " + type_of(h) + " cannot be written as JSON");
}

}  // namespace

nlohmann::json to_json(py::handle object, const std::string& where) { return json_at(object, where, "", 0); }

std::string point_text(const Vec3& p) {
  const auto shortest = [](double v) {
    char buf[32];
    return std::string(buf, std::to_chars(buf, buf + sizeof(buf), v).ptr);
  };
  return "(" + shortest(p.x()) + ", " + shortest(p.y()) + ", " + shortest(p.z()) + ")";
}

py::object from_json(const nlohmann::json& j) {
  switch (j.type()) {
    case nlohmann::json::value_t::null: return py::none();
    case nlohmann::json::value_t::boolean: return py::bool_(j.get<bool>());
    case nlohmann::json::value_t::number_integer: return py::int_(j.get<long long>());
    case nlohmann::json::value_t::number_unsigned: return py::int_(j.get<unsigned long long>());
    case nlohmann::json::value_t::number_float: {
      // As in the files the programs write (nlohmann writes null), and as raytrace/README.md
      // documents: a mean over no samples is None, not NaN.
      const double v = j.get<double>();
      return std::isfinite(v) ? py::object(py::float_(v)) : py::object(py::none());
    }
    case nlohmann::json::value_t::string: return py::str(j.get<std::string>());
    case nlohmann::json::value_t::array: {
      py::list list;
      for (const auto& item : j) list.append(from_json(item));
      return list;
    }
    case nlohmann::json::value_t::object: {
      py::dict dict;
      for (const auto& [k, v] : j.items()) dict[py::str(k)] = from_json(v);
      return dict;
    }
    default: return py::none();  // binary and discarded values never occur here
  }
}

std::vector<Vec3> points_from(py::handle object, const std::string& what) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(object);
  if (!a) throw InvalidInputError(what + ": expected an array of shape (N, 3) of numbers, found " + type_of(object));
  if (a.ndim() != 2 || a.shape(1) != 3)
    throw InvalidInputError(what + ": expected an array of shape (N, 3), found shape " + shape_of(a));
  std::vector<Vec3> points(static_cast<std::size_t>(a.shape(0)));
  const double* d = a.data();
  for (std::size_t i = 0; i < points.size(); ++i) points[i] = Vec3(d[3 * i], d[3 * i + 1], d[3 * i + 2]);
  return points;
}

std::vector<std::array<int, 3>> faces_from(py::handle object, std::size_t vertices, const std::string& what) {
  const py::array raw = py::array::ensure(object);
  if (!raw) throw InvalidInputError(what + ": expected an array of shape (M, 3) of integers, found " + type_of(object));
  // Floats would be truncated silently by a cast; an index is an integer or a mistake.
  const char kind = raw.dtype().kind();
  if (kind != 'i' && kind != 'u' && !(raw.size() == 0 && kind == 'f'))
    throw InvalidInputError(what + ": expected integer vertex indices, found dtype " + std::string(py::str(raw.dtype())));
  auto a = py::array_t<long long, py::array::c_style | py::array::forcecast>::ensure(raw);
  if (!a || a.ndim() != 2 || a.shape(1) != 3)
    throw InvalidInputError(what + ": expected an array of shape (M, 3), found shape " + shape_of(raw));
  std::vector<std::array<int, 3>> faces(static_cast<std::size_t>(a.shape(0)));
  const long long* data = a.data();
  const auto nv = static_cast<long long>(vertices);
  for (std::size_t f = 0; f < faces.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const long long v = data[3 * f + k];
      // The same wording as the mesh readers' check.
      if (v < 0 || v >= nv)
        throw InvalidInputError(what + ": face " + std::to_string(f) + " refers to vertex " + std::to_string(v) + " of " +
                                std::to_string(nv));
      faces[f][k] = static_cast<int>(v);
    }
  return faces;
}

Mesh mesh_from(py::handle vertices, py::handle faces, py::handle normals) {
  Mesh mesh;
  mesh.positions = points_from(vertices, "vertices");
  if (mesh.positions.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw InvalidInputError("vertices: more than 2^31 - 1 vertices");
  mesh.triangles = faces_from(faces, mesh.positions.size(), "faces");
  if (!normals.is_none()) {
    mesh.normals = points_from(normals, "normals");
    if (mesh.normals.size() != mesh.positions.size())
      throw InvalidInputError("normals: " + std::to_string(mesh.normals.size()) + " normals for " +
                              std::to_string(mesh.positions.size()) + " vertices");
  }
  for (std::size_t i = 0; i < mesh.positions.size(); ++i)
    if (!mesh.positions[i].allFinite())
      throw InvalidInputError("vertices: vertex " + std::to_string(i) + " has a coordinate that is not a finite number");
  for (std::size_t i = 0; i < mesh.normals.size(); ++i)
    if (!mesh.normals[i].allFinite())
      throw InvalidInputError("normals: vertex " + std::to_string(i) + " has a normal that is not a finite number");
  if (mesh.triangles.empty()) throw InvalidInputError("faces: the mesh has no triangles");
  return mesh;
}

Box box_from(py::handle object, const std::string& what) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(object);
  const std::string expected = what + ": expected ((xmin, ymin, zmin), (xmax, ymax, zmax))";
  if (!a) throw InvalidInputError(expected + ", found " + type_of(object));
  if (a.ndim() != 2 || a.shape(0) != 2 || a.shape(1) != 3) throw InvalidInputError(expected + ", found shape " + shape_of(a));
  Box box;
  for (int k = 0; k < 3; ++k) {
    box.min[k] = a.at(0, k);
    box.max[k] = a.at(1, k);
  }
  if (!box.valid()) throw InvalidInputError(what + ": every min must be below its max, and all finite");
  return box;
}

py::array_t<double> to_array(const std::vector<Vec3>& points) {
  py::array_t<double> a({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  if (!points.empty()) std::memcpy(a.mutable_data(), points.data(), points.size() * sizeof(Vec3));
  return a;
}

py::array_t<double> to_array(const std::vector<double>& values) {
  py::array_t<double> a(static_cast<py::ssize_t>(values.size()));
  if (!values.empty()) std::memcpy(a.mutable_data(), values.data(), values.size() * sizeof(double));
  return a;
}

py::array_t<std::int32_t> to_array(const std::vector<std::array<int, 3>>& faces) {
  py::array_t<std::int32_t> a({static_cast<py::ssize_t>(faces.size()), py::ssize_t{3}});
  if (!faces.empty()) std::memcpy(a.mutable_data(), faces.data(), faces.size() * sizeof(std::array<int, 3>));
  return a;
}

py::array_t<double> to_array(const Box& box) { return to_array(std::vector<Vec3>{box.min, box.max}); }

}  // namespace cdp::python
