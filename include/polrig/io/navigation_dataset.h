#pragma once
// A unit-array navigation dataset's files (docs/formats.md §6.17): imu.csv, units.csv and, when
// simulated, truth.csv and truth.yaml; the rig beside them (rig.yaml) gives the start (sky.* and
// trajectory.*), the layout (device.units.*) and the filter's settings. A measured dataset is the
// same files without the truth, and may state its own start in start.yaml (io/start_yaml.h).
#include <filesystem>
#include <string>
#include <vector>

#include "polrig/io/dataset_folder.h"
#include "polrig/io/manifest.h"
#include "polrig/study/navigation.h"

namespace polrig {

// Writes DIR/imu.csv, DIR/units.csv and, with a truth, DIR/truth.csv and DIR/truth.yaml; returns
// the files for the manifest. Numbers in their shortest exact form: a dataset reads back to the
// same doubles (angles are written in degrees: within an ulp of the radians they came from).
std::vector<DatasetFile> write_navigation_dataset(const std::filesystem::path& dir, const NavigationDataset& data);

// Reads DIR's imu.csv and units.csv (and truth.csv when present) for the rig (DIR/rig.yaml, loaded by
// the caller): the start from DIR/start.yaml when it has one, else from the rig (study/navigation.h's
// initial_state), the units' nominal
// frames from its layout. Throws DataError naming the file, the line, the column and the value:
// a missing file or column, a value that is not a finite number (a unit's aop_deg and dop may be
// nan or empty: no reading), an IMU interval other than 1/imu.rate_hz within 10 % (a gap, time going
// backwards), a rate beyond a gyro's 2000°/s or a specific force beyond an accelerometer's 50 g, a
// reading's time not after the previous one, a unit index outside the layout, a reading without every
// unit, a DoP outside [0, 1], an AoP beyond ±360°; a truth.csv without a row at every reading's time.
NavigationDataset read_navigation_dataset(const std::filesystem::path& dir, const Rig& rig);
// The same from a folder already open (io/dataset_folder.h): every file from the one dataset, even
// while another process replaces it (a reader of the rig's rig.yaml opens the folder first).
NavigationDataset read_navigation_dataset(const DatasetFolder& folder, const Rig& rig);

}  // namespace polrig
