#pragma once
// What `polrig orient` writes (issue 12 §4): per sky frame and method, the sun in the camera frame,
// the heading and its error where the true heading is known (docs/formats.md "orientation.csv").
#include <array>
#include <filesystem>
#include <optional>
#include <vector>

#include "polrig/io/manifest.h"
#include "polrig/nav/orientation.h"

namespace polrig {

// One frame's three estimates (nav/orientation.h: orient_frame) and its true heading, if known.
struct FrameOrientation {
  int frame = 0;
  std::array<OrientationEstimate, 3> estimates{};
  std::optional<double> true_heading_deg;
};

// DIR/orientation.csv: one row per frame and method, columns frame, method, sun_az_deg,
// sun_el_deg, heading_deg, heading_error_deg, status; `nan` where a value is not defined (no
// solution, a comparator's elevation, no true heading). With plots (and gnuplot),
// DIR/heading_error.png: the heading error per frame of the three methods. Throws
// std::runtime_error naming the frame and column if a defined value is not finite (nothing is
// written then).
std::vector<DatasetFile> report_orientation(const std::filesystem::path& dir,
                                            const std::vector<FrameOrientation>& frames, bool plots);

}  // namespace polrig
