#pragma once
// The cells of the calibration reports' CSV files (DoFP, four cameras): a number in its shortest
// round trip, empty for NaN (a quantity that does not exist, e.g. the DoP of a fit without the DoP
// residual), never "nan" or "inf"; a text quoted as CSV quotes it.
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

namespace polrig {

inline std::string csv_number(double v) {
  if (std::isnan(v)) return "";
  if (!std::isfinite(v)) throw std::runtime_error("calibration report: a non-finite value");
  return fmt::format("{}", v);
}

// A number for the studies' CSV cells: finite, or NaN where `undefined_ok` (formats.md: `nan`); else
// std::runtime_error naming the column and the row, before anything is written.
inline std::string checked_cell(double v, const char* column, std::size_t row, bool undefined_ok = false) {
  if (!std::isfinite(v) && !(std::isnan(v) && undefined_ok))
    throw std::runtime_error(fmt::format("a result is not finite: column '{}' of row {} is {}; "
                                         "nothing was written", column, row, v));
  return fmt::format("{}", v);
}

inline std::string csv_quoted(const std::string& s) {
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

}  // namespace polrig
