#include <cdp/baselines/marching_options.h>

#include <cdp/core/errors.h>

#include <cmath>
#include <string>

namespace cdp {

double precision_scale(int precision) {
  static constexpr double scale[6] = {1.0, 0.7, 0.6, 0.5, 0.4, 0.3};
  if (precision < 0 || precision > 5)
    throw InvalidInputError("marching: precision must be an integer from 0 to 5, not " + std::to_string(precision));
  return scale[precision];
}

double resolve_cell_size(const Field& field, const MarchingOptions& options) {
  const bool has_cell = options.cell_size != 0;
  const bool has_precision = options.precision >= 0;
  if (has_cell && has_precision) throw InvalidInputError("marching: give either a cell size or a precision, not both");
  if (has_cell) {
    if (!(std::isfinite(options.cell_size) && options.cell_size > 0))
      throw InvalidInputError("marching: the cell size must be a positive number, not " +
                              std::to_string(options.cell_size));
    return options.cell_size;
  }
  if (has_precision) {
    const double scale = precision_scale(options.precision);
    const std::optional<double> spacing = field.constraint_spacing();
    if (!spacing)
      throw InvalidInputError("marching: --precision needs a variational (data-driven) model with constraint points; "
                              "the \"" + field.type_name() + "\" field has none, give a cell size instead");
    if (!(std::isfinite(*spacing) && *spacing > 0))
      throw InvalidInputError("marching: the model's constraint spacing is not a positive number");
    return *spacing * scale;
  }
  const Box& box = field.bounds();
  if (!box.valid()) throw NoSurfaceError("marching: the field has no valid bounding box");
  return box.size().maxCoeff() / 64;
}

MarchingLattice make_marching_lattice(const Field& field, double cell_size) {
  const Box& box = field.bounds();
  if (!box.valid()) throw NoSurfaceError("marching: the field has no valid bounding box");
  constexpr long max_cells_per_axis = 1L << 19;
  MarchingLattice lattice;
  lattice.origin = box.min;
  lattice.h = cell_size;
  for (int a = 0; a < 3; ++a) {
    const double n = std::ceil(box.size()[a] / cell_size - 1e-9);
    if (!(n <= static_cast<double>(max_cells_per_axis)))
      throw InvalidInputError("marching: the cell size " + std::to_string(cell_size) + " needs more than 2^19 cells " +
                              "along a side of the box");
    lattice.cells[a] = std::max(1L, static_cast<long>(n));
  }
  return lattice;
}

const char* to_string(Traversal traversal) { return traversal == Traversal::Grid ? "grid" : "continuation"; }

const char* to_string(FaceAmbiguity rule) {
  switch (rule) {
    case FaceAmbiguity::AsymptoticDecider: return "asymptotic_decider";
    case FaceAmbiguity::JoinInside: return "join_inside";
    case FaceAmbiguity::SeparateInside: return "separate_inside";
  }
  return "?";
}

}  // namespace cdp
