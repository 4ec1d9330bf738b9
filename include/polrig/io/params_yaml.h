#pragma once
// params.yaml: calibrated parameters (Eq. 15, decoupled with d_a), their standard errors and fit
// statistics, as `polrig calibrate` writes them. The keys alpha_deg, k_mV, kv, kd are those of a
// rig's device.truth, so a rig can load them back (device.truth_from: params.yaml).
#include <filesystem>
#include <string>
#include <string_view>

#include "polrig/calib/pipeline.h"

namespace polrig {

std::string params_to_yaml(const CalibrationResult& result, double volts_per_decade);

struct LoadedParams {
  CalibrationParams params;
  double d_a = 0;
  double volts_per_decade = 0.5;
};

// Throws DataError naming the file, the line and the key.
LoadedParams read_params_yaml(const std::filesystem::path& path);
// The same from the file's text; `origin` names it in error messages.
LoadedParams parse_params_yaml(std::string_view text, std::string_view origin);

}  // namespace polrig
