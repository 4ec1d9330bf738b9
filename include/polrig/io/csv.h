#pragma once
// CSV output. Numbers are written in their shortest exact form ({fmt}'s "{}"), so a CSV reads
// back to the same doubles and is byte-identical for identical results.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace polrig {

// One CSV line of numbers, "v1,v2,…,vn\n", appended to `out`: each in its shortest exact form
// ({fmt}'s "{}", compiled: no format string parsed per number). The one formatter of every CSV
// row polrig writes (CsvTable::add_row, sweep.csv's rows formatted in parallel); no check here.
void append_csv_line(std::string& out, std::span<const double> values);

// Every value must be finite: add_row throws std::runtime_error naming the column and row of a
// NaN or infinity, so that no result leaves as one. A column whose NaN is documented to mean
// "not defined" (a ratio over a zero denominator) is declared with allow_undefined; it may hold
// NaN, never infinity.
class CsvTable {
 public:
  explicit CsvTable(std::vector<std::string> header);
  CsvTable& allow_undefined(std::string_view column);
  void add_row(const std::vector<double>& values);
  std::size_t columns() const { return header_.size(); }
  std::size_t rows() const { return rows_; }
  std::string text() const;
  std::string header_line() const;
  // The rows added so far, then forgets them (for tables written as they are computed).
  std::string take_body();

 private:
  std::vector<std::string> header_;
  std::vector<bool> may_be_nan_;
  std::string body_;
  std::size_t rows_ = 0;
};

// A file written piece by piece. Every failure (a full disk, a missing folder…) throws
// std::runtime_error naming the path and the system's reason (strerror).
class TextFileWriter {
 public:
  explicit TextFileWriter(const std::filesystem::path& path);
  // Continues an existing file after its first `keep_bytes` bytes (the rest is cut off).
  TextFileWriter(const std::filesystem::path& path, std::uint64_t keep_bytes);
  ~TextFileWriter();  // closes without checking: call close() to know the file is whole
  TextFileWriter(const TextFileWriter&) = delete;
  TextFileWriter& operator=(const TextFileWriter&) = delete;
  void write(std::string_view text);
  // Makes what was written durable (fflush, fsync); returns the file's length.
  std::uint64_t sync();
  // Hands what was written to the kernel and starts writing it to the disk without waiting
  // (sync_file_range), so that the next sync() waits for little: a long file written between
  // checkpoints then goes out at the disk's pace beside the work instead of at the checkpoint.
  void start_writeback();
  void close();

 private:
  [[noreturn]] void fail(const char* what, int err);
  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  long writeback_from_ = 0;  // the first byte start_writeback has not handed on
};

// Writes a whole file or throws std::runtime_error naming the path and the reason.
void write_text_file(const std::filesystem::path& path, const std::string& text);

// CSV input of the datasets' plain tables (stops.csv): a line's comma-separated cells (no quoting;
// a trailing comma is an empty last cell), and a cell as a finite number, else std::runtime_error
// "FILE:LINE: column COLUMN: 'TEXT' is not a finite number".
std::vector<std::string> split_csv_line(const std::string& line);
double csv_number(const std::string& text, const std::filesystem::path& file, int line, const char* column);
// The checks the dataset readers (DoFP and four-camera stops.csv) share, each a DataError naming
// file:line and the column: a whole number in [lo, hi]; 0 or 1; a number ≥ 0; an ISO 8601 UTC
// time with Z (returned as written) or empty.
int csv_whole_number(const std::string& text, const std::filesystem::path& file, int line, const char* column, int lo,
                     int hi);
bool csv_flag(const std::string& text, const std::filesystem::path& file, int line, const char* column);
double csv_nonnegative(const std::string& text, const std::filesystem::path& file, int line, const char* column);
std::string csv_utc(const std::string& text, const std::filesystem::path& file, int line, const char* column);

}  // namespace polrig
