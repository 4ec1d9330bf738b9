#include "polrig/rig/rig.h"

#include <fmt/format.h>

namespace polrig {

std::optional<Sky> rig_sky(const Rig& rig) {
  if (!rig.light->has(Source::kTimeDependent)) return std::nullopt;
  return rig.source.sky.resolved_sky();
}

std::string no_sky_message(const Rig& rig, std::string_view origin) {
  return fmt::format("{}: source.model {} has no sky (expected source.model sky)", origin,
                     rig.source.model);
}

}  // namespace polrig
