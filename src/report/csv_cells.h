#pragma once
// The cells of the calibration reports' CSV files (DoFP, four cameras): a number in its shortest
// round trip, empty for NaN (a quantity that does not exist, e.g. the DoP of a fit without the DoP
// residual), never "nan" or "inf"; a text quoted as CSV quotes it.
#include <cmath>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

namespace polrig {

inline std::string csv_number(double v) {
  if (std::isnan(v)) return "";
  if (!std::isfinite(v)) throw std::runtime_error("calibration report: a non-finite value");
  return fmt::format("{}", v);
}

inline std::string csv_quoted(const std::string& s) {
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

}  // namespace polrig
