#pragma once
// The settings of the sky source (source.model: sky), as the rig's `sky.*` keys write them:
// where and when (the sky), how the sun and the sky are modelled, and how the sensor is mounted
// under it (spec sky-and-compasses.md §1.3–1.4; docs/physics.md §10).
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/sky/sensor_view.h"
#include "polrig/sky/sky.h"
#include "polrig/sky/vector_rt.h"

namespace polrig {

// sky.rt.tau_rayleigh's text: the optical depth, or nothing for "bodhaine". Throws
// std::invalid_argument naming the text for anything else.
std::optional<double> parse_tau_rayleigh(std::string_view text);

// sky.berry.babinet_deg's or sky.berry.brewster_deg's text: a distance in [0°, 90°), or nothing
// for "fit". Throws std::invalid_argument naming the key and the text for anything else.
std::optional<double> parse_berry_distance(std::string_view key, std::string_view text);

struct SkySettings {
  Sky sky;  // site, sun settings (refraction, UT1 − UTC), model (constant P_max, radiance)
  // The rig keys' text forms, read into `sky` by resolved():
  std::string first_stop_utc = "2018-11-16T08:09:40Z";  // W19 Outdoor1's first stop
  std::string radiance = "uniform";                      // uniform | rayleigh | cie-clear
  std::string model = "single-scattering";               // single-scattering | vector-rt | berry
  // The vector-RT sky (sky.rt.*; physics.md §21): τ as a number, or "bodhaine" for Bodhaine et
  // al. 1999's at the wavelength and surface pressure below; ρ, A and the streams in `rt`.
  std::string tau_rayleigh = "0.1";
  double wavelength_nm = 550, pressure_hPa = 1013.25;
  VectorRtSettings rt;  // rt.aerosol.tau, .ssa from sky.rt.aerosol.*; its phase from the file below
  // sky.rt.aerosol.phase_matrix: the aerosol's phase-matrix file (docs/formats.md §6.22), absolute
  // once the rig has loaded (relative to the rig file in it).
  std::string aerosol_phase_matrix;
  std::string direct_beam = "plane-parallel";  // sky.rt.direct_beam: plane-parallel | pseudo-spherical
  // Berry's sky (sky.berry.*; physics.md §22): each distance in degrees, or "fit" (to the
  // vector-RT sky of the sky.rt.* settings at the sun's elevation).
  std::string berry_babinet_deg = "fit", berry_brewster_deg = "fit";
  std::string refraction = "off";                        // off | on
  std::string field = "point";                           // point | cone (the lens's field)
  // P_max(h_s) as a table (replaces sky.p_max when given): the sun's elevations (rising) and the
  // P_max at each, interpolated linearly and held beyond the ends (sky/rayleigh.h MaxDegree).
  std::vector<double> p_max_table_elevation_deg;
  std::vector<double> p_max_table;
  SkyMount mount;

  // `sky` with the text forms and the P_max table applied, and the mount with its field. Throws
  // std::invalid_argument naming the value for text no key would accept, table columns of
  // different lengths or a table check_sky_model refuses. Under sky.model vector-rt the solved
  // sky is the process's shared one for these settings (vector_rt_sky()); under berry a fitted
  // distance reads the process's shared fit (berry_fit()) to the sky.rt.* settings' sky.
  Sky resolved_sky() const;
  // m's kind and what it needs (the solved vector-RT sky, Berry's distances or their fit) from
  // sky.model, sky.rt.* and sky.berry.*; throws as resolved_sky().
  void resolve_kind(SkyModel& m) const;
  // The vector-RT settings with τ resolved (a number, or Bodhaine's) and the aerosol's phase
  // matrix read (once per file in a process); throws as resolved_sky(), and SourceSettingError
  // naming sky.rt.aerosol.phase_matrix for a file that cannot be read or is missing, or
  // sky.rt.streams for streams too few for it.
  VectorRtSettings resolved_rt() const;
  SkyMount resolved_mount() const;
};

}  // namespace polrig
