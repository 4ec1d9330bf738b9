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

class SphereTracer;
struct SphereSolution;

class TracedSource {
 public:
  explicit TracedSource(const SceneSpec& scene);
  ~TracedSource();

  const SceneSpec& scene() const { return scene_; }
  int shifts() const { return shifts_; }

  // Mean irradiance S0 (W/m²) over a photodiode centred at `p` (port-centred plane coordinates,
  // mm) on the plane L_o below the port, from shift `shift`, or from all shifts pooled (−1).
  double photodiode_irradiance(const Point2& p, double L_o, int shift = -1) const;

  // The port film: degree of polarization and axis (degrees, scene frame).
  double degree_of_polarization() const { return scene_.port.polarizer.degree_of_polarization(); }
  double polarizer_axis_deg() const { return scene_.port.polarizer.axis_deg; }

  // Rays traced by the sphere solve, and its time (for speed reports).
  long long solve_rays() const;
  double solve_seconds() const;

 private:
  // The sphere is solved on first use, once, whichever thread asks first.
  const SphereSolution& solution() const;

  SceneSpec scene_;
  int shifts_ = 8;
  std::unique_ptr<SphereTracer> tracer_;
  mutable std::unique_ptr<SphereSolution> solution_;
  mutable double L_ref_ = 0;  // mean radiance seen through the port: the control variate
  mutable std::once_flag solved_;
};

}  // namespace polrig
