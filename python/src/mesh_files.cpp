// read_mesh and write_mesh: the library's readers and writers (PLY float64, OBJ and OFF with
// round-trip decimals, STL), so that a mesh written from Python reads back bit for bit and files
// are refused with the same messages as in the programs.
#include "bindings.h"

#include <cdp/core/errors.h>
#include <cdp/io/mesh_io.h>

#include <pybind11/stl/filesystem.h>

#include <filesystem>

namespace cdp::python {

void bind_mesh_files(py::module_& m) {
  m.def(
      "read_mesh",
      [](const std::filesystem::path& path, bool return_normals) {
        Mesh mesh;
        {
          py::gil_scoped_release release;
          mesh = read_mesh(path);
        }
        py::array_t<double> vertices = to_array(mesh.positions);
        py::array_t<std::int32_t> faces = to_array(mesh.triangles);
        if (!return_normals) return py::make_tuple(vertices, faces);
        py::object normals = mesh.normals.size() == mesh.positions.size() && !mesh.normals.empty()
                                 ? py::object(to_array(mesh.normals))
                                 : py::object(py::none());
        return py::make_tuple(vertices, faces, normals);
      },
      py::arg("path"), py::kw_only(), py::arg("return_normals") = false,
      "Reads a PLY, OBJ, OFF or STL file: (vertices (N, 3) float64, faces (M, 3) int32), or with return_normals=True "
      "(vertices, faces, normals or None when the file has none). Polygons become fans. A file that cannot be opened "
      "raises OSError (FileNotFoundError, IsADirectoryError, ...); a malformed one ValueError naming the problem.");
  m.def(
      "write_mesh",
      [](const std::filesystem::path& path, py::handle vertices, py::handle faces, py::handle normals, bool binary,
         py::handle scalars) {
        Mesh mesh = mesh_from(vertices, faces, normals);
        if (!scalars.is_none()) {
          if (!py::isinstance<py::dict>(scalars))
            throw InvalidInputError("scalars: expected a dict {name: (N,) array}, found " +
                                    std::string(py::str(py::type::handle_of(scalars).attr("__name__"))));
          for (auto [key, value] : scalars.cast<py::dict>()) {
            const std::string name = py::str(key);
            auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
            if (!a || a.ndim() != 1 || a.shape(0) != static_cast<py::ssize_t>(mesh.positions.size()))
              throw InvalidInputError("scalars: \"" + name + "\" must be an array of shape (" +
                                      std::to_string(mesh.positions.size()) + ",), one number per vertex");
            mesh.vertex_scalars[name].assign(a.data(), a.data() + a.shape(0));
          }
        }
        py::gil_scoped_release release;
        write_mesh(mesh, path, binary);
      },
      py::arg("path"), py::arg("vertices"), py::arg("faces"), py::arg("normals") = py::none(), py::kw_only(),
      py::arg("binary") = true, py::arg("scalars") = py::none(),
      "Writes a mesh, the format by extension: PLY (binary little-endian float64; ASCII with binary=False; default "
      "True), OBJ, OFF (shortest round-trip decimals) or STL (float32). normals (default None: none written) an (N, "
      "3) array of vertex normals, written by PLY, OBJ and OFF (NOFF), not STL. scalars (default None) {name: (N,) array} become PLY vertex properties "
      "(build/bin/render --color NAME draws them); the other formats have no place for them. Written through a temporary file and a rename, so a failure "
      "leaves no file; one that cannot be written raises OSError with the system's reason.");
}

}  // namespace cdp::python
