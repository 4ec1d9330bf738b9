#pragma once
// Reading voltages to calibrate: a dataset folder written by `polrig simulate` (its stops.csv and
// rig.yaml), or a researcher's own CSV with the header theta_R_deg,V1,V2,V3 (volts). Both go
// through the same reader, so measured data calibrate exactly like synthetic data.
#include <ext/stdio_filebuf.h>
#include <filesystem>
#include <istream>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/calib/preprocess.h"
#include "polrig/rig/rig.h"
#include "polrig/sky/sun.h"

namespace polrig {

class DatasetFolder;

// Bad data files. what() names the file, the line and the column.
class DataError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A CSV file as text cells; line numbers are 1-based and count the header.
struct CsvFile {
  std::string origin;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::vector<int> line;  // line of each row
  int header_line = 1;

  // A UTF-8 byte-order mark, blank lines and lines starting with '#' are passed over. An empty file
  // is refused, the message giving `expected_header` as the header it lacks.
  static CsvFile read(const std::filesystem::path& path, std::string_view expected_header = {});
  // The same from the file's text; `origin` names it in error messages.
  static CsvFile parse(std::string_view text, std::string_view origin, std::string_view expected_header = {});
  // Index of a column, or DataError naming the file, the missing column and the section of
  // docs/formats.md that describes the file.
  std::size_t column(std::string_view name, std::string_view section = "Measured data") const;
  std::optional<std::size_t> find_column(std::string_view name) const;
  // The cell as a finite number, or DataError naming file:line and the column.
  double number(std::size_t row, std::size_t column) const;

  // Line n (1-based) of the text: the header if there is none yet, else a row appended (true);
  // false for the header, a blank line or a comment. DataError for a row of another width.
  bool take_line(std::string& text, int n);
  // DataError when no header was read (an empty file).
  void require_header(std::string_view expected_header) const;
};

// A CSV file of a dataset read a row at a time, for files too large to hold as cells (a 10⁷-row
// imu.csv is 329 MB of text and was ~3.9 GB as CsvFile's cells): the same rules as CsvFile, the
// header and the current row held as a one-row CsvFile (file().rows[0], file().line[0]), so that
// CsvFile::number and its messages serve both.
class CsvRows {
 public:
  CsvRows(const DatasetFolder& folder, std::string_view name, std::string_view expected_header);
  ~CsvRows();
  CsvRows(const CsvRows&) = delete;
  CsvRows& operator=(const CsvRows&) = delete;
  const CsvFile& file() const { return f_; }
  // The next data row; false at the end of the file.
  bool next();

 private:
  int fd_;
  __gnu_cxx::stdio_filebuf<char> buf_;
  std::istream in_;
  int n_ = 0;
  CsvFile f_;
};

struct MeasuredData {
  std::string origin;               // the CSV read
  std::vector<StopVoltages> stops;  // in file order; labels are "file:line"
  std::vector<UtcTime> utc;         // each stop's time, from an optional `utc` column (ISO 8601,
                                    // Z); empty without the column
  std::vector<double> t_s;          // each stop's time since the first, from an optional `t_s`
                                    // column (a time-dependent source's stops.csv)
  std::optional<Rig> rig;           // the dataset's rig.yaml, when there is one
  std::string rig_origin;           // its path
};

// `input` is a folder (reads stops.csv, and rig.yaml when present) or a CSV file. Requires
// theta_R_deg, V1, V2, V3; an optional `utc` column gives each stop's time (for the sun-drift
// corrections of an outdoor run); other columns are ignored. Throws DataError (or RigError for the
// dataset's rig.yaml). A folder whose rig's instrument gives no pair voltages (a camera's dataset)
// is refused before stops.csv is read: RigError "DIR/rig.yaml: WHAT needs pair voltages …".
MeasuredData read_measured(const std::filesystem::path& input, std::string_view what = "calibrate");

// Voltages only (for `polrig apply`): V1, V2, V3 required, theta_R_deg optional (NaN if absent).
MeasuredData read_voltages(const std::filesystem::path& input, std::string_view what = "apply");

// A CSV's text, as read_measured (need_angle) or read_voltages read it; `origin` names it in
// error messages.
MeasuredData parse_measured_csv(std::string_view text, std::string_view origin, bool need_angle);

}  // namespace polrig
