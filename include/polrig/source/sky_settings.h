#pragma once
// The settings of the sky source (source.model: sky), as the rig's `sky.*` keys write them:
// where and when (the sky), how the sun and the sky are modelled, and how the sensor is mounted
// under it (spec sky-and-compasses.md §1.3–1.4; docs/physics.md §10).
#include <string>
#include <vector>

#include "polrig/sky/sensor_view.h"
#include "polrig/sky/sky.h"

namespace polrig {

struct SkySettings {
  Sky sky;  // site, sun settings (refraction, UT1 − UTC), model (constant P_max, radiance)
  // The rig keys' text forms, read into `sky` by resolved():
  std::string first_stop_utc = "2018-11-16T08:09:40Z";  // W19 Outdoor1's first stop
  std::string radiance = "uniform";                      // uniform | rayleigh | cie-clear
  std::string refraction = "off";                        // off | on
  std::string field = "point";                           // point | cone (the lens's field)
  // P_max(h_s) as a table (replaces sky.p_max when given): the sun's elevations (rising) and the
  // P_max at each, interpolated linearly and held beyond the ends (sky/rayleigh.h MaxDegree).
  std::vector<double> p_max_table_elevation_deg;
  std::vector<double> p_max_table;
  SkyMount mount;

  // `sky` with the text forms and the P_max table applied, and the mount with its field. Throws
  // std::invalid_argument naming the value for text no key would accept, table columns of
  // different lengths or a table check_sky_model refuses.
  Sky resolved_sky() const;
  SkyMount resolved_mount() const;
};

}  // namespace polrig
