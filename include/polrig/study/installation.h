#pragma once
// Z21's installation calibration of a unit-array dataset (Z21 §3.2.2, Table 2, Fig. 15; spec
// sky-and-compasses.md §4.6 item 5; docs/physics.md §20.1): every unit's mounting errors δ fitted
// (compass/unit_installation.h) to its readings against the ephemeris sun over the dataset, with the
// attitude of the truth (a simulation) or of the SINS (a measured, static dataset), then the sun's
// elevation from the two highest-DoP units before (nominal frames) and after (calibrated frames).
#include <string>
#include <vector>

#include "polrig/compass/unit_installation.h"
#include "polrig/study/navigation.h"

namespace polrig {

struct InstallationRun {
  std::vector<UnitInstallation> units;
  std::vector<UnitMount> nominal;  // the layout fitted (the dataset's nominal frames), recorded in calibration.yaml
  std::string attitude_from;      // "truth" or "sins"
  int epochs = 0;                 // compass readings used
  // H^n from the two highest-DoP units minus the ephemeris' H at the vehicle, over the readings
  // with a sun: the mean and the mean |error| with the nominal and with the calibrated frames (deg).
  double elevation_mean_before_deg = 0, elevation_mean_after_deg = 0;
  double elevation_mae_before_deg = 0, elevation_mae_after_deg = 0;
  int elevation_epochs = 0;
  // The calibrated frames as navigate takes them (NavigationOptions::mounts).
  std::vector<UnitMount> mounts() const;
};

// Throws std::invalid_argument as navigate does for a malformed dataset.
InstallationRun calibrate_unit_array(const NavigationDataset& data, const Rig& rig,
                                     const UnitInstallationSettings& settings = {});

}  // namespace polrig
