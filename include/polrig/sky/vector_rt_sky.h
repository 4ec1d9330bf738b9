#pragma once
// The vector radiative-transfer sky as a rig sees it (spec skies.md §2; docs/physics.md §21): the
// exact diffuse sky (solve_vector_rt) at a grid of the sun's elevations and the views' zenith
// angles, interpolated between them, so that a sun that moves over a run costs a few solves, not
// one per sample. Every sun's field is the same function of its elevation whichever thread asks
// first (the solves are deterministic), so results do not depend on the thread count.
#include <Eigen/Core>
#include <array>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include "polrig/sky/vector_rt.h"

namespace polrig {

// The diffuse sky under one sun: (I, Q, U) in polrig's view frame (χ = ½·atan2(U, Q) from e_θ
// towards e_φ), as L/E₀ (sr⁻¹), for a view at cosine of zenith angle mu ∈ [0, 1] and relative
// math azimuth phi (the view's less the sun's).
class SunField {
 public:
  Eigen::Vector3d stokes(double mu, double phi) const;
  // The same from cos φ and sin φ (no trigonometry: what SunSky calls per ray).
  Eigen::Vector3d stokes(double mu, double cos_phi, double sin_phi) const;
  double zenith_radiance() const { return zenith_I_; }

 private:
  friend class VectorRtSky;
  // coefficients[m][k]: the Fourier coefficients of term m at view node k (I, Q as cos mφ; U as sin mφ).
  std::vector<std::vector<Eigen::Vector3d>> coefficients_;
  // With an aerosol: the exact once-scattered sky, added at the view itself (not interpolated).
  std::shared_ptr<const SingleScatteringSky> single_;
  double mu0_ = 1, sun_air_mass_ = 1;
  double zenith_I_ = 0;
};

class VectorRtSky {
 public:
  // The plane-parallel direct beam's air mass 1/μ₀ is 3 % above the real one at 10° (Kasten &
  // Young 1989: 5.60 against 5.76) and 45 % at 2°: below this elevation the plane-parallel sky
  // refuses; the pseudo-spherical one goes to 1° (min_sun_elevation_deg(settings)).
  static constexpr double kMinSunElevationDeg = 2;
  // The interpolation grid: the sun's elevation every kElevationStepDeg from kGridLowestDeg to 90°, the
  // views at kViewNodes nodes uniform in s, θ = (π/2)(1 − s²) (as √μ at the horizon, where the
  // field changes over δμ ~ τ; analytic at the zenith), cubic
  // (4-point Lagrange) in both. Its error against exact solves: docs/validation.md.
  static constexpr double kElevationStepDeg = 1;
  static constexpr double kGridLowestDeg = 1;
  static constexpr int kViewNodes = 48;

  explicit VectorRtSky(const VectorRtSettings& s);  // throws std::invalid_argument (check_vector_rt)
  const VectorRtSettings& settings() const { return settings_; }
  double lowest_sun_elevation_deg() const { return min_sun_elevation_deg(settings_); }

  // Throws std::invalid_argument for an elevation below lowest_sun_elevation_deg() or above 90°.
  SunField for_sun(double sun_elevation_deg) const;

  // The views' nodes, cos zenith (for tests and the validation figures).
  static const std::vector<double>& view_mu();

 private:
  std::shared_ptr<const DiffuseField> node(int k) const;
  VectorRtSettings settings_;
  mutable std::mutex mutex_;
  mutable std::map<int, std::shared_ptr<const DiffuseField>> nodes_;
};

// The process's one VectorRtSky for these settings (made on first use, shared after), so that every
// copy of a rig, every thread and every stop reads the same solves. Throws as VectorRtSky does.
std::shared_ptr<const VectorRtSky> vector_rt_sky(const VectorRtSettings& s);

}  // namespace polrig
