#include "polrig/source/scene.h"

#include <fmt/format.h>

namespace polrig {

std::optional<std::string> set_trace_photons(TraceSettings& trace, std::optional<long long> photons) {
  if (photons) {
    if (*photons < 1000 || *photons > 100000000000LL)
      return fmt::format("expected a photon count in [1000, 1e11], got {}", *photons);
    if (*photons < 100LL * trace.batches)
      return fmt::format("expected at least 100 per batch ({} for {} batches)", 100LL * trace.batches,
                         trace.batches);
    trace.photons = *photons;
  }
  trace.photons -= trace.photons % trace.batches;  // whole batches, as traced
  return std::nullopt;
}

}  // namespace polrig
