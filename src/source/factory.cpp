// The only place that names the source models: each kind is one entry here.
#include <array>

#include "polrig/source/cos4_port.h"
#include "polrig/source/sky_source.h"
#include "polrig/source/source.h"
#include "polrig/source/traced_source.h"

namespace polrig {

namespace {
constexpr std::array<std::string_view, 3> kSourceModels{"cos4", "traced", "sky"};
}  // namespace

std::span<const std::string_view> source_kinds() { return kSourceModels; }

std::shared_ptr<const Source> cos4_source() {
  static const std::shared_ptr<const Source> source = std::make_shared<const Cos4PortSource>();
  return source;
}

std::shared_ptr<const Source> make_source(const SourceSpec& s, const SceneLoader& load_scene) {
  if (s.model == "cos4") return cos4_source();
  if (s.model == "traced") {
    if (s.scene.empty()) throw SourceSettingError("source.model", "expected source.scene with source.model traced");
    if (!load_scene) throw std::logic_error("make_source: a traced source needs a scene loader");
    return std::make_shared<const TracedSource>(load_scene(s.scene));
  }
  if (s.model == "sky") {
    try {  // the settings the keys cannot check one by one: the first stop, the P_max table
      s.sky.resolved_sky();
      s.sky.resolved_mount();
    } catch (const std::invalid_argument& e) {
      throw SourceSettingError("sky.p_max_table", e.what());
    }
    return std::make_shared<const SkySource>();
  }
  throw SourceSettingError("source.model", "expected one of \"cos4\", \"traced\", \"sky\", got '" + s.model + "'");
}

}  // namespace polrig
