#pragma once
// Reading voltages to calibrate: a dataset folder written by `polrig simulate` (its stops.csv and
// rig.yaml), or a researcher's own CSV with the header theta_R_deg,V1,V2,V3 (volts). Both go
// through the same reader, so measured data calibrate exactly like synthetic data.
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/calib/preprocess.h"
#include "polrig/rig/rig.h"
#include "polrig/sky/sun.h"

namespace polrig {

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

  static CsvFile read(const std::filesystem::path& path);
  // The same from the file's text; `origin` names it in error messages.
  static CsvFile parse(std::string_view text, std::string_view origin);
  // Index of a column, or DataError naming the file, the missing column and the section of
  // docs/formats.md that describes the file.
  std::size_t column(std::string_view name, std::string_view section = "Measured data") const;
  std::optional<std::size_t> find_column(std::string_view name) const;
  // The cell as a finite number, or DataError naming file:line and the column.
  double number(std::size_t row, std::size_t column) const;
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
