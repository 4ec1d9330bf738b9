#include "polrig/study/installation.h"

#include <cmath>

#include "polrig/sky/sun.h"
#include "polrig/units.h"

namespace polrig {

namespace {


struct Epoch {
  Axes3 C_bn;
  double sun_elevation_deg = 0;
  Vec3 sun_enu{};
};

// Each reading's attitude and ephemeris sun: at the truth when the dataset has one, else the
// SINS's attitude at the start's site (a static run).
std::vector<Epoch> epochs_of(const NavigationDataset& data, const Rig& rig, std::string& attitude_from) {
  const Sky sky = rig.source.sky.resolved_sky();
  std::vector<Epoch> out;
  std::vector<NavigationFix> sins;
  if (!data.truth) {
    NavigationOptions o;
    o.modes = {NavigationMode::Sins};
    sins = navigate(data, rig, o).fixes[0];
  }
  attitude_from = data.truth ? "truth" : "sins";
  for (std::size_t k = 0; k < data.compass.size(); ++k) {
    const double t = data.compass[k].t_s;
    Epoch e;
    Site site{rad2deg(data.initial.lat_rad), rad2deg(data.initial.lon_rad), data.initial.h_m};
    if (data.truth) {
      const TruthSample& s = truth_at(*data.truth, t);
      e.C_bn = axes_of(s.C_bn);
      site = {rad2deg(s.lat_rad), rad2deg(s.lon_rad), s.h_m};
    } else {
      e.C_bn = axes_of(C_bn_from_euler(sins[k].attitude));
    }
    const SunPosition sun = sun_position(data.start.plus_seconds(t), site, sky.sun);
    e.sun_elevation_deg = sun.elevation_deg;
    e.sun_enu = sun_direction_enu(sun);
    out.push_back(e);
  }
  return out;
}

}  // namespace

std::vector<UnitMount> InstallationRun::mounts() const {
  std::vector<UnitMount> out;
  for (const UnitInstallation& u : units) out.push_back({u.C_mb});
  return out;
}

InstallationRun calibrate_unit_array(const NavigationDataset& data, const Rig& rig,
                                     const UnitInstallationSettings& settings) {
  if (data.compass.empty())
    throw std::invalid_argument("no compass readings (units.csv): the installation is fitted to the units' readings");
  InstallationRun run;
  const std::vector<Epoch> epochs = epochs_of(data, rig, run.attitude_from);
  std::vector<InstallationEpoch> fit;
  for (std::size_t k = 0; k < epochs.size(); ++k) fit.push_back({epochs[k].C_bn, epochs[k].sun_enu, data.compass[k].units});
  run.units = calibrate_installation(data.mounts, fit, settings);
  run.nominal = data.mounts;
  run.epochs = static_cast<int>(fit.size());
  // A mounting error beyond 10° is no mounting error (the rig keys' range): the sequence did not
  // determine the unit (one attitude confounds its tilt and roll errors); said, not used.
  for (std::size_t i = 0; i < run.units.size(); ++i) {
    UnitInstallation& u = run.units[i];
    if (std::abs(u.error_deg[0]) > 10 || std::abs(u.error_deg[1]) > 10 || std::abs(u.error_deg[2]) > 10) {
      u.converged = false;
      u.termination = "beyond-10-deg";
      u.C_mb = data.mounts[i].C_mb;  // mounts() keeps the nominal frame
    }
  }
  const std::vector<UnitMount> after = run.mounts();
  double sum_b = 0, sum_a = 0, abs_b = 0, abs_a = 0;
  for (std::size_t k = 0; k < epochs.size(); ++k) {
    const UnitSun b = sun_from_units(data.compass[k].units, data.mounts), a = sun_from_units(data.compass[k].units, after);
    if (b.status != UnitSunStatus::Ok || a.status != UnitSunStatus::Ok) continue;
    const double eb = rad2deg(sun_in_nav(b.s_b, epochs[k].C_bn).elevation_rad) - epochs[k].sun_elevation_deg;
    const double ea = rad2deg(sun_in_nav(a.s_b, epochs[k].C_bn).elevation_rad) - epochs[k].sun_elevation_deg;
    sum_b += eb, sum_a += ea, abs_b += std::abs(eb), abs_a += std::abs(ea);
    ++run.elevation_epochs;
  }
  if (run.elevation_epochs > 0) {
    const double n = run.elevation_epochs;
    run.elevation_mean_before_deg = sum_b / n, run.elevation_mean_after_deg = sum_a / n;
    run.elevation_mae_before_deg = abs_b / n, run.elevation_mae_after_deg = abs_a / n;
  }
  return run;
}

}  // namespace polrig
