#include "failure_message.h"

#include "stage_checks.h"

#include <cdp/core/crease_curves.h>
#include <cdp/core/errors.h>

#include <cmath>
#include <exception>
#include <numbers>
#include <optional>
#include <sstream>
#include <utility>

namespace cdp::adaptive {
namespace {

// The most crease points traced to name the sharpest crease in a message: the gyroid ball's
// creases are 2,415 points (0.04 s), but fogleman/sdf's knurling example's (48 twisted boxes) are
// 24,159, about 1.5 ms each, and a run across them that failed spent 36 s naming one.
constexpr std::size_t kAdviceCreasePoints = 4000;

// The sharpest crease of a traced layout, as the angle at which its two faces meet (180 degrees
// less the angle between the two pieces' outward normals, as Tracker::acute_crease_between
// measures it) at the traced point where it is smallest, and that point.
std::optional<std::pair<double, Vec3>> sharpest_crease(const Field& field, const CreaseTracingResult& traced) {
  std::optional<std::pair<double, Vec3>> best;
  for (const CreaseCurve& c : traced.curves)
    for (const Vec3& p : c.points) {
      const Vec3 na = field.piece(p, c.pieces[0]).gradient, nb = field.piece(p, c.pieces[1]).gradient;
      if (!(na.squaredNorm() > 0 && nb.squaredNorm() > 0)) continue;
      const double degrees = 180.0 - std::atan2(na.cross(nb).norm(), na.dot(nb)) * 180.0 / std::numbers::pi;
      if (!best || degrees < best->first) best = std::pair(degrees, p);
    }
  return best;
}

// Meshed across its creases by choice (CreaseHandling::Ignore, or the paper variant, which has
// no crease handling): the fronts meet a crease as curvature without bound, and do not always
// close across a sharp one (the box less a ball, the gyroid ball, the spheres on a bar at
// factors 8 and 9 fail so, with errors that named a stuck front or the neighbour searches'
// bound and advised another min_edge). The message says that the field has creases, names the
// sharpest and the way that meshes them, unless the tracker has already named the crease
// where its front stalled.
std::string across_creases_advice(const Field& field, const AdaptiveOptions& options, const std::string& message) {
  const bool across_by_choice = options.creases == CreaseHandling::Ignore || options.variant == Variant::Paper;
  if (!across_by_choice || !field.has_pieces() || message.find(kAlongCreaseAdvice) != std::string::npos) return "";
  const std::string across = "; the field has creases, which this run meshed across as if they were curvature";
  const std::string along = "the improved variant with creases: follow (the defaults) meshes along them";
  try {
    CreaseTracingOptions co;
    co.resolution = options.seed_resolution;
    co.max_points = kAdviceCreasePoints;
    if (const auto sharpest = sharpest_crease(field, trace_creases(field, co))) {
      std::ostringstream crease;
      crease << across << " (the sharpest: faces meeting at " << std::lround(sharpest->first) << " degrees near "
             << describe_point(sharpest->second) << "); " << along;
      return crease.str();
    }
  } catch (const CancelledError&) {
    throw;
  } catch (const LimitExceededError&) {
    // Too many creases to trace for a message: that they are there (has_pieces) is enough.
    return across + "; " + along;
  } catch (const std::exception&) {
    // no layout to name (a field that fails there): the message as it is
  }
  return "";
}

}  // namespace

bool kink_in_black_box(const Field& field, const Bend& tightest) {
  const std::optional<double> step = field.derivative_step();
  return step && tightest.first < *step;
}

bool noise_in_volume(const Field& field, const Settings& resolved, const Bend& tightest) {
  const std::optional<double> spacing = field.sample_spacing();
  return spacing && tightest.first < resolved.sizing.min_edge && tightest.first < kBelowSamples * *spacing;
}

std::string explain_failure(const Field& field, const AdaptiveOptions& options, const Settings& resolved,
                            std::string message, const Bend& tightest, const std::string& crease_fallback) {
  if (kink_in_black_box(field, tightest)) {
    // The cause first: the tracker's own advice (a smaller min_edge) does not help here.
    std::ostringstream kink;
    kink << "adaptive: the normal turns within " << tightest.first << " near " << describe_point(tightest.second)
         << ", less than the step of the central differences that give this field's derivatives ("
         << *field.derivative_step() << "): a crease or corner of the function (a min, max, abs or branch in "
         << "it) that the field does not describe, which no mesh of it follows; a field that names its min, max "
         << "and abs (an expression, or from Python a cdp.sdf model or a numpy function cdp.trace can follow) is "
         << "meshed along its creases, and exact gradient and Hessian functions resolve a smooth bend this tight";
    // creases: follow stops at the first kink (BlackBoxKinkError); meshing across is the caller's choice.
    if (resolved.stop_at_kink)
      kink << "; creases: ignore meshes across such creases as if they were curvature (stats "
           << "creases.across_black_box), with edges as short as min_edge along them, and may fail or take long";
    kink << ". Where the run stopped: " << message;
    message = kink.str();
  } else if (noise_in_volume(field, resolved, tightest)) {
    // The cause first too: lowering min_edge, the tracker's advice, only follows the noise further.
    std::ostringstream noise;
    noise << "adaptive: the surface bends with a radius of curvature of " << tightest.first << " near "
          << describe_point(tightest.second) << ", under a tenth of the volume's sample spacing ("
          << *field.sample_spacing() << ") and under min_edge (" << resolved.sizing.min_edge
          << "): not detail of the data but the noise of its samples (the interpolant bends that tightly only "
             "where the level passes a hair from one of its saddles), which shorter edges only follow further; "
             "smoothing the samples before meshing, with a Gaussian of a voxel or two as examples/mesh_volume.py "
             "does, removes it. Where the run stopped: "
          << message;
    message = noise.str();
  } else if (tightest.first < resolved.sizing.min_edge) {
    std::ostringstream bend;
    bend << "; the surface bends with a radius of curvature of " << tightest.first << " near "
         << describe_point(tightest.second) << ", below min_edge (" << resolved.sizing.min_edge
         << "), detail finer than the mesh's shortest edge";
    // A scan's detail that fine is its noise, which the sampled volume interpolates as surface.
    if (field.type_name() == "volume")
      bend << " (in a scanned volume usually its noise: smoothing the samples before meshing, with a Gaussian of a "
              "voxel or two as examples/mesh_volume.py does, removes it)";
    message += bend.str();
  }
  message += across_creases_advice(field, options, message);
  return crease_fallback.empty() ? message
                                 : message + " (meshed as smooth after crease-aware meshing failed: " + crease_fallback + ")";
}

}  // namespace cdp::adaptive
