#include "polrig/io/csv.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/compile.h>
#include <fmt/format.h>

#include "polrig/io/measured.h"
#include "polrig/quoted.h"
#include "polrig/sky/sun.h"

namespace polrig {

void append_csv_line(std::string& out, std::span<const double> values) {
  constexpr std::size_t kMaxNumber = 25;  // a double's shortest form is at most 24 characters, then ',' or '\n'
  const std::size_t at = out.size();
  out.resize(at + std::max<std::size_t>(1, values.size()) * kMaxNumber);
  char* p = out.data() + at;
  for (std::size_t c = 0; c < values.size(); ++c) {
    if (c) *p++ = ',';
    p = fmt::format_to(p, FMT_COMPILE("{}"), values[c]);
  }
  *p++ = '\n';
  out.resize(static_cast<std::size_t>(p - out.data()));
}

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
  append_csv_line(body_, values);
  ++rows_;
}

std::string CsvTable::header_line() const {
  std::string out;
  for (std::size_t c = 0; c < header_.size(); ++c) out += (c ? "," : "") + header_[c];
  return out + '\n';
}

std::string CsvTable::text() const { return header_line() + body_; }

std::string CsvTable::take_body() {
  std::string body;
  body.swap(body_);
  return body;
}

TextFileWriter::TextFileWriter(const std::filesystem::path& path) : path_(path) {
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) fail("cannot create the file", errno);
}

TextFileWriter::TextFileWriter(const std::filesystem::path& path, std::uint64_t keep_bytes) : path_(path) {
  // truncate() would pad a file shorter than its checkpoint with zero bytes: refuse it instead.
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) fail("cannot read the file's length", ec.value());
  if (size < keep_bytes)
    throw std::runtime_error(fmt::format("{}: {} bytes, shorter than its last checkpoint ({} bytes): the file "
                                         "was changed after the checkpoint",
                                         path_.string(), size, keep_bytes));
  if (::truncate(path.c_str(), static_cast<off_t>(keep_bytes)) != 0) fail("cannot cut the file to its last checkpoint", errno);
  file_ = std::fopen(path.c_str(), "ab");
  if (!file_) fail("cannot open the file", errno);
}

std::uint64_t TextFileWriter::sync() {
  if (!file_) throw std::logic_error(fmt::format("{}: synced after close", path_.string()));
  errno = 0;
  if (std::fflush(file_) != 0 || ::fsync(::fileno(file_)) != 0) fail("cannot write the file", errno ? errno : EIO);
  const long at = std::ftell(file_);
  if (at < 0) fail("cannot tell the file's length", errno);
  return static_cast<std::uint64_t>(at);
}

void TextFileWriter::start_writeback() {
  if (!file_) throw std::logic_error(fmt::format("{}: written after close", path_.string()));
  errno = 0;
  if (std::fflush(file_) != 0) fail("cannot write the file", errno ? errno : EIO);
  const long at = std::ftell(file_);
  if (at < 0) fail("cannot tell the file's length", errno);
  // Linux: start writing the new pages out without waiting for them (a hint: a failure here is
  // found by the next sync's fsync).
  if (at > writeback_from_)
    ::sync_file_range(::fileno(file_), writeback_from_, at - writeback_from_, SYNC_FILE_RANGE_WRITE);
  writeback_from_ = at;
}

TextFileWriter::~TextFileWriter() {
  if (file_) std::fclose(file_);
}

void TextFileWriter::fail(const char* what, int err) {
  if (file_) std::fclose(file_);
  file_ = nullptr;
  throw std::runtime_error(fmt::format("{}: {}: {}", path_.string(), what, std::strerror(err)));
}

void TextFileWriter::write(std::string_view text) {
  if (!file_) throw std::logic_error(fmt::format("{}: written after close", path_.string()));
  errno = 0;
  if (std::fwrite(text.data(), 1, text.size(), file_) != text.size())
    fail("cannot write the file", errno ? errno : EIO);
}

void TextFileWriter::close() {
  if (!file_) return;
  errno = 0;
  const bool flushed = std::fflush(file_) == 0;
  const int err = errno;
  std::FILE* f = file_;
  file_ = nullptr;
  errno = 0;
  const bool closed = std::fclose(f) == 0;
  if (!flushed || !closed) {
    throw std::runtime_error(fmt::format("{}: cannot write the file: {}", path_.string(),
                                         std::strerror(!flushed && err ? err : errno ? errno : EIO)));
  }
}

void write_text_file(const std::filesystem::path& path, const std::string& text) {
  TextFileWriter out(path);
  out.write(text);
  out.close();
}

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) out.push_back(cell);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

double csv_number(const std::string& text, const std::filesystem::path& file, int line, const char* column) {
  double v = 0;
  const char* end = text.data() + text.size();
  const auto r = std::from_chars(text.data(), end, v);
  if (r.ec != std::errc() || r.ptr != end || !std::isfinite(v))
    throw DataError(fmt::format("{}:{}: column {}: '{}' is not a finite number", file.string(), line, column, quoted_value(text)));
  return v;
}

int csv_whole_number(const std::string& text, const std::filesystem::path& file, int line, const char* column, int lo,
                     int hi) {
  const double v = csv_number(text, file, line, column);
  if (v != std::floor(v) || v < lo || v > hi)
    throw DataError(fmt::format("{}:{}: column {}: {} (expected a whole number in [{}, {}])", file.string(), line, column,
                                quoted_value(text), lo, hi));
  return static_cast<int>(v);
}

bool csv_flag(const std::string& text, const std::filesystem::path& file, int line, const char* column) {
  const double v = csv_number(text, file, line, column);
  if (v != 0 && v != 1)
    throw DataError(fmt::format("{}:{}: column {}: {} (expected 0 or 1)", file.string(), line, column, quoted_value(text)));
  return v == 1;
}

double csv_nonnegative(const std::string& text, const std::filesystem::path& file, int line, const char* column) {
  const double v = csv_number(text, file, line, column);
  if (v < 0)
    throw DataError(fmt::format("{}:{}: column {}: {} (expected a number ≥ 0)", file.string(), line, column,
                                quoted_value(text)));
  return v;
}

std::string csv_utc(const std::string& text, const std::filesystem::path& file, int line, const char* column) {
  if (text.empty()) return text;
  try {
    (void)parse_utc(text);
  } catch (const std::invalid_argument& e) {
    throw DataError(fmt::format("{}:{}: column {}: '{}': {}", file.string(), line, column, quoted_value(text), e.what()));
  }
  return text;
}

}  // namespace polrig
