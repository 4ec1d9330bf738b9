#include "polrig/nav/heading_rows.h"

namespace polrig {

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
