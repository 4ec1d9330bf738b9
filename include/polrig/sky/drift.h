#pragma once
// Sun-drift corrections for an outdoor turntable calibration (spec sky-and-compasses.md §1.4):
// during a turn the zenith E-vector follows the sun's azimuth and the zenith degree of
// polarization follows its elevation. calib/ takes the result as per-stop vectors.
//
// Sign (docs/physics.md §1, §10): polrig's sensor frame measures θ anticlockwise seen from above
// and the table turns the sensor clockwise seen from above, so θ = θ_R + const for a fixed
// light. The zenith E-vector lies at geographic azimuth A_s ± 90°, which turns clockwise seen
// from above as A_s rises, so in the sensor frame θ(t) = θ_0 + θ_R(t) − [A_s(t) − A_s(t_0)].
// (In the spec's sense, clockwise from above, θ' = −θ = θ'_0 − θ_R + ΔA_s: s_R = −1 and the drift
// enters with +, spec §1.4.)
#include <optional>
#include <string_view>
#include <vector>

#include "polrig/sky/rayleigh.h"
#include "polrig/sky/sun.h"

namespace polrig {

enum class DriftMode {
  None,     // the reference is the table angle only (Table 2's Outdoor columns)
  Angle,    // + the azimuth drift from the ephemeris, per stop (W19's compensation: Sun columns)
  PerStop,  // the angle as `Angle`, and the fit's d scaled by d(t_k)/d(t_0) from the sky model
  Linear    // as PerStop from the first and last stop only, both interpolated linearly in time
            // (W19 §6: "start and end compensated, medial points by linear inserting")
};
std::string_view drift_mode_name(DriftMode m);  // "none", "angle", "per-stop", "linear"
std::optional<DriftMode> parse_drift_mode(std::string_view name);

// Per-stop corrections: dtheta_deg[k] is added to stop k's table angle (sensor frame), d_ratio[k]
// multiplies the fitted d. Both are empty for DriftMode::None.
struct SkyDrift {
  std::vector<double> dtheta_deg;
  std::vector<double> d_ratio;
};

// The zenith's degree of polarization for the sun at zenith angle θ_s (spec §1.2 with γ = θ_s):
// P_max(h_s)·sin²θ_s/(1 + cos²θ_s).
double zenith_dop(const SunPosition& sun, const MaxDegree& P_max);

// The corrections at each stop from its time t_s[k] (seconds, any origin), the sun's azimuth
// A_s and the zenith's degree of polarization there. The first stop is the earliest, the last the
// latest (stops in any order). Throws std::invalid_argument when the sizes differ, a value is
// not finite, or (per-stop) the zenith is unpolarized at the first stop.
SkyDrift drift_from_sun(const std::vector<double>& t_s, const std::vector<double>& azimuth_deg,
                        const std::vector<double>& zenith_dop, DriftMode mode);

// The same with the sun from the ephemeris at each stop's time (a sensor looking at the zenith).
SkyDrift drift_corrections(const std::vector<UtcTime>& times, const Site& site,
                           const SunSettings& settings, const MaxDegree& P_max, DriftMode mode);

}  // namespace polrig
