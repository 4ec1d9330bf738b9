#pragma once
// What `polrig calibrate --method unit-array` writes (docs/formats.md §6.19): calibration.yaml (each
// unit's mounting errors, their standard errors, the fit's end, the sun-elevation error before and
// after), installation.csv (the same per unit, Z21 Table 2's before → after) and installation.png;
// and the reader navigate --calibration uses.
#include <filesystem>
#include <vector>

#include "polrig/io/manifest.h"
#include "polrig/study/installation.h"

namespace polrig {

std::vector<DatasetFile> report_installation(const std::filesystem::path& dir, const InstallationRun& run, bool plots);

// The calibrated frames from a calibration.yaml, for the units of `nominal` (the dataset's layout):
// installed_frame(nominal_i, δ_i), or nominal_i for a unit whose fit did not converge. Throws
// DataError naming the file, the line and the key: a missing or extra unit, a `converged` that is
// not true or false, a converged unit's δ that is not three numbers within ±10°.
std::vector<UnitMount> read_installation(const std::filesystem::path& file, const std::vector<UnitMount>& nominal);

}  // namespace polrig
