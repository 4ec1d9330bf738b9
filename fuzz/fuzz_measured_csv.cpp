// Measured voltages (theta_R_deg,V1,V2,V3): any text ends as stops or a DataError, read both as
// `calibrate` (angle required) and as `apply` (angle optional) read it; anything else is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "polrig/io/measured.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  for (bool need_angle : {true, false}) {
    try {
      const polrig::MeasuredData m = polrig::parse_measured_csv(text, "fuzz/stops.csv", need_angle);
      for (const polrig::StopVoltages& s : m.stops)
        for (double v : s.V)
          if (!std::isfinite(v)) std::abort();  // the reader promises finite voltages
    } catch (const polrig::DataError&) {
    }
  }
  return 0;
}
