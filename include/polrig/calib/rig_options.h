#pragma once
// The calibration settings a rig's sensor implies, shared by `polrig calibrate`, `polrig study
// calibration` and Python (polrig.calibrate, Rig.study_calibration): the film axes of the
// nominal start, the amplifier's volts per decade, d_a and the noncontinuous rule, and the
// range that rule's settings must lie in.
#include <optional>
#include <string>

#include "polrig/calib/pipeline.h"
#include "polrig/calib/preprocess.h"
#include "polrig/rig/rig.h"

namespace polrig {

// The ranges of the noncontinuous rule's settings (`--nc-threshold`, `--nc-min-points`).
inline constexpr double kNcThresholdMin = 0.0;
inline constexpr double kNcThresholdMax = 1.0;
inline constexpr int kNcMinPointsMin = 6;  // the fit's 6 films need at least 6 points
inline constexpr int kNcMinPointsMax = 100000;

// What is wrong with `rule`, naming the setting and its value as Python names them
// ("nc_threshold=2: expected a finite number in [0, 1]"); nullopt when it is valid.
std::optional<std::string> noncontinuous_rule_problem(const NoncontinuousRule& rule);

// CalibrationOptions for the rig's sensor: its film axes (the fit's nominal start), its
// amplifier's volts per decade, `d_a` (the stated degree of polarization to decouple with; nullopt:
// none, the fit's best film ideal) and the noncontinuous `rule`. The method is left at the
// default and d_a_source at "given": the caller says where d_a came from. Throws RigError when
// `rule` is out of range (noncontinuous_rule_problem).
CalibrationOptions calibration_options(const Rig& rig, std::optional<double> d_a,
                                       const NoncontinuousRule& rule);

}  // namespace polrig
