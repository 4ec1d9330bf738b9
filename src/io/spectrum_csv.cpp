#include "polrig/io/spectrum_csv.h"

#include <fmt/format.h>

#include "polrig/io/measured.h"

namespace polrig {

namespace {

std::size_t column_of(const CsvFile& f, std::string_view name) {
  if (auto c = f.find_column(name)) return *c;
  throw DataError(fmt::format("{}:{}: missing column '{}' (see docs/formats.md, \"Spectra\")",
                              f.origin, f.header_line, name));
}

Spectrum spectrum_of(const CsvFile& f, std::string_view column, double max_value) {
  const std::size_t x = column_of(f, "wavelength_nm"), y = column_of(f, column);
  if (f.rows.size() < 2)
    throw DataError(fmt::format("{}: {} data row(s); a spectrum needs at least two", f.origin,
                                f.rows.size()));
  std::vector<double> nm, value;
  for (std::size_t r = 0; r < f.rows.size(); ++r) {
    nm.push_back(f.number(r, x));
    value.push_back(f.number(r, y));
    if (value.back() > max_value)
      throw DataError(fmt::format("{}:{}: column '{}': {} exceeds {}", f.origin, f.line[r],
                                  column, value.back(), max_value));
  }
  try {
    return Spectrum(std::move(nm), std::move(value), fmt::format("{}:{}", f.origin, column));
  } catch (const SpectrumError& e) {
    // name the line and column instead of the sample index
    const std::size_t r = e.sample;
    if (r == SpectrumError::npos) throw DataError(e.what());
    const double w = f.number(r, x), v = f.number(r, y);
    if (!(w > 0))
      throw DataError(fmt::format("{}:{}: column 'wavelength_nm': {}; expected a wavelength > 0",
                                  f.origin, f.line[r], w));
    if (v < 0)
      throw DataError(fmt::format("{}:{}: column '{}': {}; expected a value >= 0", f.origin,
                                  f.line[r], column, v));
    throw DataError(fmt::format("{}:{}: column 'wavelength_nm': {} {} the previous row's {}; "
                                "wavelengths must increase strictly", f.origin, f.line[r], w,
                                w == f.number(r - 1, x) ? "repeats" : "is below",
                                f.number(r - 1, x)));
  }
}

}  // namespace

Spectrum read_spectrum_csv(const std::filesystem::path& path, std::string_view column,
                           double max_value) {
  return spectrum_of(CsvFile::read(path), column, max_value);
}

FilmSpectra read_film_csv(const std::filesystem::path& path) {
  const CsvFile f = CsvFile::read(path);
  FilmSpectra film{spectrum_of(f, "tau_M", 1.0), spectrum_of(f, "tau_m", 1.0)};
  for (std::size_t r = 0; r < f.rows.size(); ++r)
    if (film.tau_m.value()[r] > film.tau_M.value()[r])
      throw DataError(fmt::format("{}:{}: column 'tau_m': {} exceeds tau_M = {}; the leakage "
                                  "cannot exceed the pass transmittance", f.origin, f.line[r],
                                  film.tau_m.value()[r], film.tau_M.value()[r]));
  return film;
}

}  // namespace polrig
