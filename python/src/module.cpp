// The compiled module `cdp._cdp`, which the package `cdp` (python/cdp/__init__.py) re-exports: see
// python/README.md.
#include "bindings.h"

PYBIND11_MODULE(_cdp, m) {
  m.doc() =
      "Curvature-dependent polygonization of implicit surfaces (de Araujo & Jorge 2004): fields, the adaptive "
      "polygonizer, Marching Cubes and Tetrahedra, curvature, Newton projection, exact ray-cast evaluation and mesh "
      "files, on numpy arrays. See python/README.md.";
  // Bound under the package's name, which re-exports everything: classes and functions are
  // cdp.Field, cdp.polygonize (in reprs and the signatures of docstrings), not cdp._cdp.Field.
  const pybind11::object own_name = m.attr("__name__");
  m.attr("__name__") = "cdp";
  cdp::python::bind_errors(m);
  cdp::python::bind_fields(m);
  cdp::python::bind_volume(m);
  cdp::python::bind_meshing(m);
  cdp::python::bind_analysis(m);
  cdp::python::bind_mesh_files(m);
  m.attr("__name__") = own_name;
}
