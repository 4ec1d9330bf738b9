#pragma once
// The traced source as a rig's light (source.model: traced): the scene's sphere is solved once,
// and the irradiance at a photodiode is the port integral of traced_port.h over the photodiode's
// square (2 × 2 Gauss points). The light's degree and angle of polarization are those of the
// scene's port film (normal-incidence model).
//
// The quasi-random port samples are the same for every photodiode and pose; each of `shifts`
// independent random shifts gives a complete estimate, so studies run once per shift and report
// the spread of the shifts as standard errors.
#include <filesystem>
#include <memory>
#include <mutex>

#include "polrig/rig/geometry.h"
#include "polrig/source/scene.h"

namespace polrig {

// The rig frame is seen from the sensor looking up, the scene frame from above (z up): mirror
// images sharing the x-axis. A rig-plane offset from the port centre in scene coordinates:
inline Point2 to_scene(const Point2& rig) { return {rig.x(), -rig.y()}; }

class SphereTracer;
struct SphereSolution;

class TracedSource {
 public:
  explicit TracedSource(const SceneSpec& scene);
  ~TracedSource();

  const SceneSpec& scene() const { return scene_; }
  int shifts() const { return shifts_; }

  // Mean irradiance S0 (W/m²) on a photodiode whose centre (or, lensed, whose channel axis) is
  // at `p` (port-centred plane coordinates, mm), from shift `shift`, or all shifts pooled (−1).
  // Bare (sensor.geometry: bare): the photodiode lies L_o below the port. Lensed: the channel's
  // film is L_o below the port, then film_to_lens, the plano-convex lens (traced exactly, with
  // Fresnel losses) and lens_to_photodiode; the blue filter scales every channel alike.
  double photodiode_irradiance(const Point2& p, double L_o, int shift = -1) const;

  // The port film: degree of polarization, and its axis in the rig frame (the scene's axis,
  // mirrored: −axis_deg).
  double degree_of_polarization() const { return scene_.port.polarizer.degree_of_polarization(); }
  double polarizer_axis_rig_deg() const { return -scene_.port.polarizer.axis_deg; }

  // Rays traced by the sphere solve, and its time (for speed reports).
  long long solve_rays() const;
  double solve_seconds() const;

 private:
  // The sphere is solved on first use, once, whichever thread asks first.
  const SphereSolution& solution() const;
  double lensed_irradiance(const Point2& p, double top, int shift) const;

  SceneSpec scene_;
  int shifts_ = 8;
  std::unique_ptr<SphereTracer> tracer_;
  mutable std::unique_ptr<SphereSolution> solution_;
  mutable double L_ref_ = 0;  // mean radiance seen through the port: the control variate
  mutable std::once_flag solved_;
};

}  // namespace polrig
