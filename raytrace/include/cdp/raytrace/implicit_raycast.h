// Exact ray casting of an implicit surface F = 0: the ground truth of the accuracy metrics.
//
// Sphere tracing steps |F| / L with a Lipschitz bound L, at least `min_step`, inside the ray's
// part within the field's box. A sign change between consecutive samples brackets the first
// crossing, which Newton's method guarded by bisection refines to machine precision. Where the
// sampled values have a local minimum small enough for F to reach zero between samples (a ray
// grazing the surface), a golden-section search finds the minimum along the ray: a minimum <= 0
// gives a crossing (flag Grazing), a minimum within `tangent_tolerance` a touch (flag Tangent).
// Features thinner than `min_step` along a ray that do not leave a sampled local minimum can be
// missed; that is the price of a bounded step count.
#pragma once

#include <cdp/raytrace/camera.h>

#include <cdp/core/field.h>

#include <cstdint>
#include <vector>

namespace cdp {

struct RaycastOptions {
  // > 0: use this Lipschitz bound. Otherwise Field::lipschitz_bound() when the model has one,
  // else an estimate: max |grad F| over a lipschitz_grid^3 grid of the box times lipschitz_safety.
  double lipschitz = 0.0;
  int lipschitz_grid = 32;
  double lipschitz_safety = 2.0;
  // Smallest step, as a fraction of the box diagonal: sphere tracing cannot stall near the surface.
  double min_step = 1e-4;
  // A touch without crossing counts when min F along the ray, divided by |grad F| there, is below
  // this fraction of the box diagonal.
  double tangent_tolerance = 1e-10;
  int max_steps = 100000;             // per ray; a ray that hits it gets status StepLimit
  int max_refine_iterations = 200;    // root refinement and minimum search, per bracket
};

enum class RayStatus : std::uint8_t {
  Miss = 0,          // no surface along the ray inside the box
  Hit = 1,           // first intersection at t
  StartsInside = 2,  // F <= 0 where the ray enters the box: the surface leaves the box
  StepLimit = 3,     // max_steps reached before leaving the box
  NotFinite = 4,     // F was NaN or infinite along the ray
};
// \return "miss", "hit", "starts_inside", "step_limit" or "not_finite" ("unknown" outside the enum).
const char* to_string(RayStatus status);

// Bits of SurfaceHit::flags.
enum RayFlag : std::uint8_t {
  kRayGrazing = 1,   // the crossing was found between samples by the minimum search
  kRayTangent = 2,   // a touch without crossing (to tangent_tolerance), reported as the hit
  kRayNearMiss = 4,  // passed within a step's reach of the surface without touching it
};

struct SurfaceHit {
  RayStatus status = RayStatus::Miss;
  std::uint8_t flags = 0;
  std::int32_t steps = 0;          // field samples along the ray (marching only)
  double t = 0.0;                  // distance along the ray (Hit only)
  Vec3 normal = Vec3::Zero();      // unit field gradient at the hit (Hit only)
  bool hit() const { return status == RayStatus::Hit; }
};

// What ray casting needs from a field besides the field itself.
struct RaycastSetup {
  Box box;
  double lipschitz = 0.0;
  bool lipschitz_from_model = false;  // false: user-given or estimated
  double min_step = 0.0;              // absolute
  double tangent_tolerance = 0.0;     // absolute distance
};

// Throws InvalidInputError on bad options, NoSurfaceError when the field's box is invalid or the
// gradient is not finite on the estimation grid.
// \pre where it estimates the bound (options.lipschitz 0 and no bound from the model), the field can
//      be evaluated from several threads at once (Field::thread_safe is not consulted).
// \throw InvalidInputError for lipschitz negative or not finite, lipschitz_grid outside [2, 1024],
//        lipschitz_safety below 1, min_step or tangent_tolerance outside (0, 1), or max_steps or
//        max_refine_iterations below 1.
// \throw NoSurfaceError when field.bounds() is not valid, or the gradient is not finite at a point
//        of the estimation grid.
// \throw what the field's evaluations throw, unchanged.
RaycastSetup make_raycast_setup(const Field& field, const RaycastOptions& options);

// max |grad F| over a grid x grid x grid lattice of the box (corners included), in parallel.
// \pre the field can be evaluated from several threads at once (Field::thread_safe is not consulted).
// \return the maximum, or the first norm in lattice order that is not finite; a grid below 2 counts
//         as 2.
// \throw what the field's evaluations throw, unchanged.
double max_gradient_norm(const Field& field, const Box& box, int grid);

// \pre setup is make_raycast_setup(field, options); ray.direction has unit length.
// \return the ray's first crossing of the surface inside setup.box (status, flags, t and normal).
// \throw what the field's evaluations throw, unchanged.
SurfaceHit cast_ray(const Field& field, const Ray& ray, const RaycastSetup& setup, const RaycastOptions& options);

struct GroundTruthCounts {
  std::size_t hits = 0, misses = 0, starts_inside = 0, step_limit = 0, not_finite = 0;
  std::size_t grazing = 0, tangent = 0, near_miss = 0;
};

struct GroundTruth {
  std::vector<Ray> rays;
  std::vector<SurfaceHit> hits;  // one per ray
  RaycastSetup setup;
  // \return the number of hits of each status and of each flag.
  GroundTruthCounts counts() const;
};

// Casts every ray in parallel (TBB); each ray is independent, so the result does not depend on
// the number of threads.
// \pre every ray's direction has unit length; the field can be evaluated from several threads at
//      once (Field::thread_safe is not consulted).
// \return the rays, one hit per ray, and the setup.
// \throw as make_raycast_setup; what the field's evaluations throw, unchanged.
GroundTruth compute_ground_truth(const Field& field, std::vector<Ray> rays, const RaycastOptions& options = {});

}  // namespace cdp
