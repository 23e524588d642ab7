// The `cdp` Python module: see python/README.md.
#include "bindings.h"

PYBIND11_MODULE(cdp, m) {
  m.doc() =
      "Curvature-dependent polygonization of implicit surfaces (de Araujo & Jorge 2004): fields, the adaptive "
      "polygonizer, Marching Cubes and Tetrahedra, curvature, Newton projection, exact ray-cast evaluation and mesh "
      "files, on numpy arrays. See python/README.md.";
  cdp::python::bind_errors(m);
  cdp::python::bind_fields(m);
  cdp::python::bind_meshing(m);
  cdp::python::bind_analysis(m);
  cdp::python::bind_mesh_files(m);
}
