#pragma once
// The heading for many rows of (time, site, attitude, E-vector angle): `polrig heading`'s table.
// Values only; reading and writing the files is the CLI's and io/'s.
#include <optional>
#include <string_view>
#include <span>
#include <vector>

#include "polrig/compass/heading.h"
#include "polrig/progress.h"
#include "polrig/sky/sun_rows.h"

namespace polrig {

struct HeadingQuery {
  SunRow at;                        // UTC and site
  Tilt tilt;                        // roll and pitch, degrees (heading.h's senses)
  double aop_deg = 0;               // θ_b, degrees, anticlockwise from X_b seen from above
  std::optional<double> prior_deg;  // clockwise from north; empty: the root with the sun in front
};

// The ranges of `polrig heading`'s inputs (its CSV columns, polrig.heading's arguments): roll_deg,
// pitch_deg, aop_deg, prior_deg, lat_deg, lon_deg; std::invalid_argument for another name.
InputRange heading_query_range(std::string_view field);

struct HeadingSample {
  SunPosition sun;
  HeadingSolution solution;
};

// The sun of every row (sun_positions: SunRowError naming the first row the ephemeris refuses),
// then solve_heading on its ENU direction, in the rows' order; the same for any thread count.
std::vector<HeadingSample> headings_along(std::span<const HeadingQuery> queries,
                                          const SunSettings& sun_settings = {},
                                          const HeadingSettings& settings = {},
                                          const Progress& progress = {});

}  // namespace polrig
