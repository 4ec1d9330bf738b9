#include "polrig/io/csv.h"

#include <cmath>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

namespace polrig {

CsvTable::CsvTable(std::vector<std::string> header)
    : header_(std::move(header)), may_be_nan_(header_.size(), false) {}

CsvTable& CsvTable::allow_undefined(std::string_view column) {
  for (std::size_t c = 0; c < header_.size(); ++c)
    if (header_[c] == column) may_be_nan_[c] = true;
  return *this;
}

void CsvTable::add_row(const std::vector<double>& values) {
  if (values.size() != header_.size())
    throw std::logic_error(fmt::format("CSV row has {} values for {} columns", values.size(),
                                       header_.size()));
  for (std::size_t c = 0; c < values.size(); ++c)
    if (!std::isfinite(values[c]) && !(std::isnan(values[c]) && may_be_nan_[c]))
      throw std::runtime_error(fmt::format(
          "a result is not finite: column '{}' of row {} ({} = {}) is {}; the inputs are beyond "
          "what the model can represent, and nothing was written",
          header_[c], rows_ + 1, header_[0], values[0], values[c]));
  for (std::size_t c = 0; c < values.size(); ++c)
    fmt::format_to(std::back_inserter(body_), "{}{}", c ? "," : "", values[c]);
  body_ += '\n';
  ++rows_;
}

std::string CsvTable::text() const {
  std::string out;
  for (std::size_t c = 0; c < header_.size(); ++c) out += (c ? "," : "") + header_[c];
  out += '\n';
  return out + body_;
}

void write_text_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  out.close();
  if (!out) throw std::runtime_error(fmt::format("{}: cannot write the file", path.string()));
}

}  // namespace polrig
