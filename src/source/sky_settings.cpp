#include "polrig/source/sky_settings.h"

#include <optional>
#include <stdexcept>

namespace polrig {

Sky SkySettings::resolved_sky() const {
  Sky s = sky;
  s.first_stop = parse_utc(first_stop_utc);
  const std::optional<SkyRadiance> model = parse_sky_radiance(radiance);
  if (!model)
    throw std::invalid_argument("sky.radiance: expected uniform, rayleigh or cie-clear, got '" + radiance + "'");
  s.model.radiance = *model;
  if (refraction != "off" && refraction != "on")
    throw std::invalid_argument("sky.refraction: expected off or on, got '" + refraction + "'");
  s.sun.refraction = refraction == "on";
  if (p_max_table_elevation_deg.size() != p_max_table.size())
    throw std::invalid_argument("sky.p_max_table: " + std::to_string(p_max_table.size()) +
                                " values for " + std::to_string(p_max_table_elevation_deg.size()) +
                                " elevations in sky.p_max_table_elevation_deg");
  s.model.P_max.table.clear();
  for (std::size_t i = 0; i < p_max_table.size(); ++i)
    s.model.P_max.table.emplace_back(p_max_table_elevation_deg[i], p_max_table[i]);
  check_sky_model(s.model);
  return s;
}

SkyMount SkySettings::resolved_mount() const {
  if (field != "point" && field != "cone")
    throw std::invalid_argument("sky.field: expected point or cone, got '" + field + "'");
  SkyMount m = mount;
  m.cone = field == "cone";
  return m;
}

}  // namespace polrig
