// cdp.volume_field: a sampled volume (a numpy array) as a field, the model of the JSON type
// "volume" (cdp/core/models/volume.h) built from memory instead of a file.
#include "bindings.h"

#include <cdp/core/errors.h>
#include <cdp/core/models/volume.h>

#include <pybind11/numpy.h>

#include <cmath>
#include <string>

namespace cdp::python {

namespace {

constexpr const char* kWhere = "cdp.volume_field";

// A number or three, each positive and finite: the spacing along x, y and z.
Vec3 spacing_from(py::handle object) {
  const py::array_t<double, py::array::forcecast> a = py::array_t<double, py::array::forcecast>::ensure(object);
  if (!a || !(a.ndim() == 0 || (a.ndim() == 1 && a.size() == 3)))
    throw InvalidInputError(std::string(kWhere) + ": spacing must be a number or three numbers");
  const double* d = a.data();
  const Vec3 s = a.ndim() == 0 ? Vec3::Constant(d[0]) : Vec3(d[0], d[1], d[2]);
  if (!(s.array().isFinite().all() && (s.array() > 0).all()))
    throw InvalidInputError(std::string(kWhere) + ": spacing must be positive and finite");
  return s;
}

std::shared_ptr<Field> volume_field(py::handle values, py::handle bounds, py::handle spacing, py::handle origin,
                                    double level, const std::string& inside) {
  // The shape before the copy to float64: a grid beyond the model's limit is refused before
  // gigabytes are allocated for it.
  const py::array any = py::array::ensure(values);
  if (!any) throw InvalidInputError(std::string(kWhere) + ": values must be a 3-D array of numbers");
  if (any.ndim() == 3) {
    std::size_t total = 1;
    for (int a = 0; a < 3; ++a) {
      const auto n = static_cast<std::size_t>(any.shape(a));
      if (n != 0 && total > Volume::kMaxSamples / n)
        throw InvalidInputError(std::string(kWhere) + ": more than " + std::to_string(Volume::kMaxSamples) + " samples");
      total *= n;
    }
  }
  const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(any);
  if (!array) throw InvalidInputError(std::string(kWhere) + ": values must be a 3-D array of numbers");
  if (array.ndim() != 3)
    throw InvalidInputError(std::string(kWhere) + ": values must be a 3-D array, not " + std::to_string(array.ndim()) + "-D");
  if (inside != "below" && inside != "above")
    throw InvalidInputError(std::string(kWhere) + ": inside must be \"below\" or \"above\", not \"" + inside + "\"");
  VolumeSamples samples;
  for (int a = 0; a < 3; ++a) samples.dims[a] = static_cast<std::size_t>(array.shape(a));
  if (!bounds.is_none()) {
    if (!spacing.is_none() || !origin.is_none())
      throw InvalidInputError(std::string(kWhere) + ": give either bounds or spacing and origin, not both");
    const Box box = box_from(bounds, std::string(kWhere) + ": bounds");
    samples.origin = box.min;
    for (int a = 0; a < 3; ++a)
      samples.spacing[a] = box.size()[a] / std::max(1.0, static_cast<double>(samples.dims[a]) - 1.0);
  } else {
    if (!spacing.is_none()) samples.spacing = spacing_from(spacing);
    if (!origin.is_none()) {
      const auto o = py::array_t<double, py::array::forcecast>::ensure(origin);
      if (!o || o.ndim() != 1 || o.size() != 3)
        throw InvalidInputError(std::string(kWhere) + ": origin must be one point (x, y, z)");
      samples.origin = Vec3(o.data()[0], o.data()[1], o.data()[2]);
    }
  }
  samples.values.assign(array.data(), array.data() + array.size());
  std::unique_ptr<Field> field;
  {
    py::gil_scoped_release release;  // the prefilter passes over every sample three times
    field = std::make_unique<Volume>(std::move(samples), level, inside == "below" ? VolumeInside::Below : VolumeInside::Above);
  }
  return std::shared_ptr<Field>(std::move(field));
}

}  // namespace

void bind_volume(py::module_& m) {
  m.def("volume_field", &volume_field, py::arg("values"), py::arg("bounds") = py::none(), py::kw_only(),
        py::arg("spacing") = py::none(), py::arg("origin") = py::none(), py::arg("level") = 0.0,
        py::arg("inside") = "below",
        R"(A sampled volume as a field: values[i, j, k] is the sample at origin + (i, j, k) * spacing.

values: a 3-D array of numbers (a CT or MRI scan, simulation output, a distance grid), at least 4
samples along each axis. It is interpolated by a tricubic B-spline through the samples: C2, so
gradients, Hessians and curvature are exact for the interpolant, and the surface has no creases.
bounds ((xmin, ymin, zmin), (xmax, ymax, zmax)): the grid spans the box (default None); or
spacing (a number or three, default 1) and origin ((x, y, z), default (0, 0, 0)).
level (default 0.0): the surface is where the interpolant equals it. Give a volume's level here:
polygonize's level= shifts F = S - level (or level - S) after this, with inside="above" the other
way round, and skips the check below.
inside (default "below"): "below" when values below the level are inside (a signed distance),
"above" when values above it are (a density: bone in a CT scan).

The surface must stay inside the grid: the interpolant must be outside on the grid's faces,
checked on the coefficients of the two layers next to each (pad with numpy.pad(values, 5,
constant_values=...) otherwise: they ring next to a steep jump, such as a scan's cut edge); the field's box is the grid's, and beyond it F is its value at
the nearest point of the box plus the distance to the box. A bad argument
is a ValueError naming it. In JSON: {"type": "volume", "file": "scan.npy" or ".nrrd", ...}.)");
}

}  // namespace cdp::python
