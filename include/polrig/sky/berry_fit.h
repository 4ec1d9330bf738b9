#pragma once
// Berry's sky as an emulator of the vector-RT sky (spec skies.md §3; docs/physics.md §22.2): its
// two distances fitted, at each sun elevation, to the exact sky's E-vector pattern, and tabulated
// against the elevation per atmosphere, so that `sky.berry.*: fit` costs a few fits per run.
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "polrig/sky/berry.h"
#include "polrig/sky/rayleigh.h"
#include "polrig/sky/vector_rt_sky.h"

namespace polrig {

// How one fit ended (Ceres's Summary in small: failures are data).
struct BerryFitSummary {
  std::string status;    // Eigen's LevenbergMarquardtSpace::Status, e.g. "relative_reduction"
  bool converged = false;  // the solver met a tolerance (not the iteration limit or bad input)
  int iterations = 0;      // Jacobian evaluations
  int views = 0;           // the views the fit and the errors below are over (exact DoP ≥ 0.02)
  // Over those views, unweighted (they are spread uniformly in solid angle above the horizon):
  double aop_rms_deg = 0;         // Berry's AoP less the exact sky's, rms
  double aop_p95_deg = 0;         // its 95th percentile of |ΔAoP|
  double single_aop_rms_deg = 0;  // single scattering's AoP less the exact sky's, rms (the comparison)
  bool usable() const { return converged; }
};

struct BerryFitResult {
  double sun_el_deg = 0;
  BerryDistances distances;
  BerryFitSummary summary;
};

// The fit at one sun elevation to `field` (the exact sky for that sun, SunField): least squares of
// sin(ψ_Berry − ψ_exact) over a grid uniform in solid angle above the horizon, the views where the
// exact DoP is below 0.02 left out (their AoP is not defined to a degree), by Levenberg–Marquardt
// from δ_Ba = δ_Br = 15°, each distance kept in [0°, 89°].
BerryFitResult fit_berry(const SunField& field, double sun_el_deg);

// The fitted distances of one atmosphere against the sun's elevation: a fit at every
// VectorRtSky node elevation (made on first use, shared by threads; the same bits whichever thread
// fits first), linear between nodes.
class BerryFit {
 public:
  explicit BerryFit(std::shared_ptr<const VectorRtSky> sky);
  // Throws std::invalid_argument for an elevation the vector-RT sky refuses, and for a fit that
  // did not converge at a node it needs (naming the node and its status).
  BerryDistances distances(double sun_el_deg) const;
  BerryFitResult at_node(int k) const;
  const VectorRtSky& sky() const { return *sky_; }

 private:
  std::shared_ptr<const VectorRtSky> sky_;
  mutable std::mutex mutex_;
  mutable std::map<int, BerryFitResult> nodes_;
};

// The process's one BerryFit for these settings (as vector_rt_sky()).
std::shared_ptr<const BerryFit> berry_fit(const VectorRtSettings& s);

// A rig's Berry distances at the sun's elevation: each the number given, or the fit's. Throws as
// BerryFit::distances; std::logic_error for a fitted distance without its fit.
BerryDistances berry_distances(const BerrySkySettings& b, double sun_el_deg);

}  // namespace polrig
