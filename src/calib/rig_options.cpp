#include "polrig/calib/rig_options.h"

#include <cmath>

#include <fmt/format.h>

#include "polrig/rig/error.h"

namespace polrig {

std::optional<std::string> noncontinuous_rule_problem(const NoncontinuousRule& rule) {
  const double t = rule.min_relative_slope;
  if (!std::isfinite(t) || t < kNcThresholdMin || t > kNcThresholdMax)
    return fmt::format("nc_threshold={}: expected a finite number in [{}, {}]", t, kNcThresholdMin,
                       kNcThresholdMax);
  if (rule.min_points < kNcMinPointsMin || rule.min_points > kNcMinPointsMax)
    return fmt::format("nc_min_points={}: expected a whole number in [{}, {}]", rule.min_points,
                       kNcMinPointsMin, kNcMinPointsMax);
  return std::nullopt;
}

CalibrationOptions calibration_options(const Rig& rig, std::optional<double> d_a,
                                       const NoncontinuousRule& rule) {
  require_instrument(rig, Instrument::kPairVoltages, "an Eq. 15 calibration");
  if (const auto problem = noncontinuous_rule_problem(rule)) throw RigError(*problem);
  CalibrationOptions o;
  o.d_a = d_a;
  o.film_axis_deg = rig.device.film_axis_deg;
  o.volts_per_decade = rig.electronics.volts_per_decade;
  o.noncontinuous = rule;
  return o;
}

}  // namespace polrig
