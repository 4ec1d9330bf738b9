#pragma once
// A measured log's start state, its dataset's start.yaml (docs/formats.md §6.17): the INS's
// position, velocity (ENU) and attitude at t = 0 and their standard deviations for the filter's P0,
// in one block, in place of the rig's start (sky.*, trajectory.*, navigation.*_sigma*).
#include <string>
#include <string_view>

#include "polrig/ins/mechanization.h"
#include "polrig/study/navigation.h"

namespace polrig {

struct StatedStart {
  InsState state;  // t_s = 0
  StartSigma sigma;
};

// Parses start.yaml's text (`file` names it in messages). Throws DataError "FILE:LINE: key 'K':
// …" for a syntax error, a duplicate, unknown or missing key, a value that is not a finite number,
// or one outside its range: lat_deg within the INS's ±89°, lon_deg [−180, 360] (wrapped to ±180°),
// h_m [−500, 20000], each velocity component within ±300 m/s, roll (−180, 180], pitch [−90, 90],
// heading [−360, 360] (degrees), the standard deviations positive and at most 30°, 100 m/s, 10⁶ m.
StatedStart parse_start_yaml(const std::string& text, std::string_view file);

}  // namespace polrig
