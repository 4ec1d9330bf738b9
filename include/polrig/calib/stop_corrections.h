#pragma once
// The sun-drift corrections of an outdoor calibration (spec sky-and-compasses.md §1.4) from what
// the run recorded: each stop's UTC, or a sky rig's sky.first_stop_utc plus each stop's t_s; the
// observer as given, else the sky rig's site. sky/drift.h computes the corrections from times and
// a site; this part finds those and says where they came from, for params.yaml. `polrig
// calibrate --drift` and polrig.calibrate(drift=...) both call it.
#include <optional>
#include <string>
#include <vector>

#include "polrig/calib/pipeline.h"
#include "polrig/rig/rig.h"
#include "polrig/sky/drift.h"
#include "polrig/sky/sun.h"

namespace polrig {

struct DriftRequest {
  DriftMode mode = DriftMode::None;
  std::vector<UtcTime> utc;  // each stop's time (a `utc` column); empty: none
  std::vector<double> t_s;   // each stop's seconds since the first (a sky rig's stops.csv); empty: none
  std::string origin;        // the data, for messages
  // How the caller spells its settings in messages: the drift ("--drift per-stop"), the site
  // ("--site LAT,LON"), and what is missing without stop times.
  std::string drift_option, site_option, times_missing;
};

// The stops' times: `utc`, else (a time-dependent source's rig, the sky) its sky.first_stop_utc
// plus `t_s`; and where they came from, for params.yaml. Throws std::invalid_argument
// ("<drift_option>: <times_missing>") when there are none.
struct StopTimes {
  std::vector<UtcTime> utc;
  std::string from;  // "the utc column", "the rig's sky.first_stop_utc + t_s"
};
StopTimes drift_stop_times(const DriftRequest& request, const Rig& rig);

// Per-stop corrections at those times for the sun seen from `site` (`site_from` says how it was
// given, for params.yaml), else from the sky rig's site. A sky rig also supplies its
// P_max(h_s) table and its sun settings; any other rig the geometric sun and a constant P_max.
// Empty for DriftMode::None. Throws std::invalid_argument with the message for the user when
// the site is missing or the sun cannot give the corrections (sky/drift.h).
StopCorrections sun_drift_corrections(const DriftRequest& request, const StopTimes& times,
                                      const std::optional<Site>& site,
                                      const std::string& site_from, const Rig& rig);
// Both steps.
StopCorrections sun_drift_corrections(const DriftRequest& request, const std::optional<Site>& site,
                                      const std::string& site_from, const Rig& rig);

}  // namespace polrig
