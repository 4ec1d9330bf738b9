#pragma once
// The settings of the sky source (source.model: sky), as the rig's `sky.*` keys write them:
// where and when (the sky), how the sun and the sky are modelled, and how the sensor is mounted
// under it (spec sky-and-compasses.md §1.3–1.4; docs/physics.md §10).
#include <string>

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
  SkyMount mount;

  // `sky` with the text forms applied, and the mount with its field. Throws
  // std::invalid_argument naming the value for text no key would accept.
  Sky resolved_sky() const;
  SkyMount resolved_mount() const;
};

}  // namespace polrig
