#include "polrig/rig/rig.h"

#include <fmt/format.h>

#include "polrig/rig/error.h"

namespace polrig {

std::optional<Sky> rig_sky(const Rig& rig) {
  if (!rig.light->has(Source::kTimeDependent)) return std::nullopt;
  return rig.source.sky.resolved_sky();
}

std::string no_sky_message(const Rig& rig, std::string_view origin) {
  return fmt::format("{}: source.model {} has no sky (expected source.model sky)", origin,
                     rig.source.model);
}

std::optional<std::string> instrument_problem(const Rig& rig, Instrument::Flag needs,
                                              std::string_view what, std::string_view origin) {
  if (rig.instrument().has(needs)) return std::nullopt;
  std::string_view text = "?";
  for (const InstrumentFlagInfo& f : instrument_flags())
    if (f.flag == needs) text = f.text;
  return fmt::format("{}{}{} needs {} (device.kind {}); device.kind {} has none", origin,
                     origin.empty() ? "" : ": ", what, text, kinds_with(needs),
                     rig.instrument().kind());
}

void require_instrument(const Rig& rig, Instrument::Flag needs, std::string_view what,
                        std::string_view origin) {
  if (auto problem = instrument_problem(rig, needs, what, origin)) throw RigError(*problem);
}

}  // namespace polrig
