#pragma once
// The three pairs' colours and line style in the simulation's and the sweep's plots.
#include <string>

#include <fmt/format.h>

namespace polrig {

inline constexpr const char* kPairColour[3] = {"#1f77b4", "#d62728", "#2ca02c"};

inline std::string line_style(int pair, const char* extra = "") {
  return fmt::format("lines lw 2 lc rgb '{}' {}", kPairColour[pair], extra);
}

}  // namespace polrig
