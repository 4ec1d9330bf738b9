#include "polrig/source/sky_settings.h"

#include "polrig/sky/berry_fit.h"
#include "polrig/sky/vector_rt_sky.h"
#include "polrig/source/source.h"

#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string_view>

namespace polrig {

Sky SkySettings::resolved_sky() const {
  Sky s = sky;
  s.first_stop = parse_utc(first_stop_utc);
  const std::optional<SkyRadiance> radiance_model = parse_sky_radiance(radiance);
  if (!radiance_model)
    throw std::invalid_argument("sky.radiance: expected uniform, rayleigh or cie-clear, got '" + radiance + "'");
  s.model.radiance = *radiance_model;
  if (refraction != "off" && refraction != "on")
    throw std::invalid_argument("sky.refraction: expected off or on, got '" + refraction + "'");
  s.sun.refraction = refraction == "on";
  if (p_max_table_elevation_deg.size() != p_max_table.size())
    throw std::invalid_argument("sky.p_max_table: " + std::to_string(p_max_table.size()) +
                                " values for " + std::to_string(p_max_table_elevation_deg.size()) +
                                " elevations in sky.p_max_table_elevation_deg");
  s.model.P_max.table.clear();
  for (std::size_t i = 0; i < p_max_table.size(); ++i)
    s.model.P_max.table.emplace_back(p_max_table_elevation_deg[i], p_max_table[i]);
  check_sky_model(s.model);
  resolve_kind(s.model);
  return s;
}

void SkySettings::resolve_kind(SkyModel& m) const {
  const std::optional<SkyKind> kind = parse_sky_kind(model);
  if (!kind)
    throw std::invalid_argument("sky.model: expected single-scattering, vector-rt or berry, got '" + model + "'");
  m.kind = *kind;
  m.vector_rt = *kind == SkyKind::VectorRt ? vector_rt_sky(resolved_rt()) : nullptr;
  m.berry = {};
  if (*kind == SkyKind::Berry) {
    m.berry.babinet_deg = parse_berry_distance("sky.berry.babinet_deg", berry_babinet_deg);
    m.berry.brewster_deg = parse_berry_distance("sky.berry.brewster_deg", berry_brewster_deg);
    if (!m.berry.babinet_deg || !m.berry.brewster_deg) m.berry.fit = berry_fit(resolved_rt());
  }
}

std::optional<double> parse_berry_distance(std::string_view key, std::string_view text) {
  if (text == "fit") return std::nullopt;
  std::size_t used = 0;
  double d = 0;
  try {
    d = std::stod(std::string(text), &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !(d >= 0 && d < 90))
    throw std::invalid_argument(std::string(key) + ": expected a distance in [0, 90) degrees or fit, got '" +
                                std::string(text) + "'");
  return d;
}

std::optional<double> parse_tau_rayleigh(std::string_view text) {
  if (text == "bodhaine") return std::nullopt;
  std::size_t used = 0;
  double tau = 0;
  try {
    tau = std::stod(std::string(text), &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !(tau >= 0 && tau <= 100))
    throw std::invalid_argument("sky.rt.tau_rayleigh: expected an optical depth in [0, 100] or bodhaine, got '" +
                                std::string(text) + "'");
  return tau;
}

namespace {

// The process's one table per phase-matrix file, so that every copy of a rig shares one sky
// (vector_rt_sky() keys on the table).
std::shared_ptr<const PhaseMatrixTable> shared_phase_matrix(const std::string& path) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const PhaseMatrixTable>> tables;
  std::lock_guard<std::mutex> lock(mutex);
  auto& t = tables[path];
  if (!t) t = std::make_shared<const PhaseMatrixTable>(read_phase_matrix(path));
  return t;
}

}  // namespace

VectorRtSettings SkySettings::resolved_rt() const {
  VectorRtSettings s = rt;
  const std::optional<double> tau = parse_tau_rayleigh(tau_rayleigh);
  s.tau_rayleigh = tau ? *tau : rayleigh_optical_depth_bodhaine(wavelength_nm, pressure_hPa, s.depolarization);
  if (direct_beam != "plane-parallel" && direct_beam != "pseudo-spherical")
    throw SourceSettingError("sky.rt.direct_beam",
                             "expected plane-parallel or pseudo-spherical, got '" + direct_beam + "'");
  s.pseudo_spherical = direct_beam == "pseudo-spherical";
  if (s.tau_rayleigh == 0 && !(s.aerosol.tau > 0))
    throw SourceSettingError("sky.rt.tau_rayleigh",
                             "expected an optical depth > 0 (0 only under an aerosol, sky.rt.aerosol.tau > 0)");
  if (s.aerosol.tau > 0 && aerosol_phase_matrix.empty())
    throw SourceSettingError("sky.rt.aerosol.phase_matrix",
                             "expected the aerosol's phase-matrix file with sky.rt.aerosol.tau > 0");
  if (s.aerosol.tau > 0) {
    try {
      s.aerosol.phase = shared_phase_matrix(aerosol_phase_matrix);
    } catch (const PhaseMatrixError& e) {
      throw SourceSettingError("sky.rt.aerosol.phase_matrix", std::string("cannot read the phase matrix: ") + e.what());
    }
  }
  try {
    check_vector_rt(s);
  } catch (const std::invalid_argument& e) {
    // The keys have checked every value on its own; what is left under an aerosol is the streams.
    if (s.aerosol.tau > 0) throw SourceSettingError("sky.rt.streams", e.what());
    throw;
  }
  return s;
}

SkyMount SkySettings::resolved_mount() const {
  if (field != "point" && field != "cone")
    throw std::invalid_argument("sky.field: expected point or cone, got '" + field + "'");
  SkyMount m = mount;
  m.cone = field == "cone";
  return m;
}

}  // namespace polrig
