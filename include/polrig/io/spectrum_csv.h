#pragma once
// Spectra from CSV files (docs/formats.md, "Spectra"): a column wavelength_nm and named value
// columns, '#' comment lines allowed.
#include <filesystem>
#include <limits>
#include <string_view>

#include "polrig/spectral/effective_degree.h"
#include "polrig/spectral/spectrum.h"

namespace polrig {

// wavelength_nm and `column` as a Spectrum named "FILE:column". Throws DataError naming the
// file, line, column and value for a missing column, fewer than two rows, a non-number, a
// wavelength not > 0 or not strictly increasing, or a value outside [0, max_value].
Spectrum read_spectrum_csv(const std::filesystem::path& path, std::string_view column,
                           double max_value = std::numeric_limits<double>::infinity());

// Film transmittances: columns tau_M and tau_m, each in [0, 1], and tau_m <= tau_M on every line.
FilmSpectra read_film_csv(const std::filesystem::path& path);

}  // namespace polrig
