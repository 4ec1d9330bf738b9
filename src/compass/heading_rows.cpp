#include "polrig/compass/heading_rows.h"

#include <stdexcept>
#include <string>

namespace polrig {

InputRange heading_query_range(std::string_view field) {
  if (field == "roll_deg") return {-180, 180, "degrees, right side down positive"};
  if (field == "pitch_deg") return {-90, 90, "degrees, nose up positive"};
  if (field == "aop_deg") return {-360, 360, "θ_b in degrees, anticlockwise from X_b seen from above"};
  if (field == "prior_deg") return {-360, 360, "degrees clockwise from north; empty for none"};
  if (field == "lat_deg" || field == "lon_deg") return sky_query_range(field);
  throw std::invalid_argument("heading_query_range: no input '" + std::string(field) + "'");
}

std::vector<HeadingSample> headings_along(std::span<const HeadingQuery> queries,
                                          const SunSettings& sun_settings,
                                          const HeadingSettings& settings,
                                          const Progress& progress) {
  std::vector<SunRow> at(queries.size());
  for (std::size_t r = 0; r < queries.size(); ++r) at[r] = queries[r].at;
  const std::vector<SunPosition> suns = sun_positions(at, sun_settings, progress);
  std::vector<HeadingSample> out(queries.size());
  for (std::size_t r = 0; r < queries.size(); ++r) {
    const HeadingQuery& q = queries[r];
    out[r] = {suns[r], solve_heading(sun_direction_enu(suns[r]), q.aop_deg, q.tilt, q.prior_deg,
                                     settings)};
  }
  return out;
}

}  // namespace polrig
