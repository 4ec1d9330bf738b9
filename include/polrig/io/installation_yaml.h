#pragma once
// The reader of a unit-array installation calibration (calibration.yaml of `polrig calibrate
// --method unit-array`, docs/formats.md §6.19), what navigate --calibration applies.
#include <filesystem>
#include <vector>

#include "polrig/compass/unit_array.h"

namespace polrig {

// The calibrated frames for the units of `nominal` (the dataset's layout): installed_frame(nominal_i,
// δ_i), or nominal_i for a unit whose fit did not converge. Each entry is taken by its `unit:`
// number, not its place in the list, and its `nominal_axes_b` (the layout the fit was made for)
// must be the dataset's unit's nominal frame. Throws DataError naming the file, the line and the
// key: not a regular file, a YAML error, a key given twice, an unknown key, a unit number missing,
// repeated or outside 1…N, a unit count other than the layout's, a unit fitted for another layout
// (or a file without the record, from before it was written), a `converged` that is not true or
// false, a converged unit's δ that is not three numbers within ±10°.
std::vector<UnitMount> read_installation(const std::filesystem::path& file, const std::vector<UnitMount>& nominal);

}  // namespace polrig
