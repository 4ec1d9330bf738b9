#include "polrig/io/measured.h"
#include "polrig/quoted.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include <fmt/format.h>

#include "polrig/io/dataset_folder.h"
#include "polrig/io/rig_yaml.h"

namespace polrig {
namespace fs = std::filesystem;

namespace {
constexpr std::string_view kStopsHeader = "theta_R_deg,V1,V2,V3";

std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> out;
  std::string field;
  std::stringstream ss(line);
  while (std::getline(ss, field, ',')) {
    const auto b = field.find_first_not_of(" \t");
    const auto e = field.find_last_not_of(" \t\r");
    out.push_back(b == std::string::npos ? "" : field.substr(b, e - b + 1));
  }
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}
}  // namespace

CsvFile CsvFile::read(const fs::path& path, std::string_view expected_header) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    throw DataError(fmt::format("{}: cannot read the file: {}", path.string(),
                                fs::exists(path, ec) ? "not a regular file" : "no such file"));
  std::ifstream in(path, std::ios::binary);
  std::stringstream buf;
  buf << in.rdbuf();
  return parse(buf.str(), path.string(), expected_header);
}

bool CsvFile::take_line(std::string& text, int n) {
  if (n == 1 && text.starts_with("\xEF\xBB\xBF")) text.erase(0, 3);  // a UTF-8 byte-order mark
  if (!text.empty() && text.back() == '\r') text.pop_back();
  if (text.find_first_not_of(" \t") == std::string::npos) return false;  // blank line
  if (!text.empty() && text[0] == '#') return false;                       // comment
  if (header.empty()) {
    header = split_fields(text);
    header_line = n;
    return false;
  }
  std::vector<std::string> fields = split_fields(text);
  if (fields.size() != header.size())
    throw DataError(fmt::format("{}:{}: expected {} fields as in the header, got {}", origin, n, header.size(),
                                fields.size()));
  rows.push_back(std::move(fields));
  line.push_back(n);
  return true;
}

void CsvFile::require_header(std::string_view expected_header) const {
  if (header.empty())
    throw DataError(fmt::format("{}: the file is empty; expected a header line{}", origin,
                                expected_header.empty() ? std::string() : fmt::format(" such as {}", expected_header)));
}

CsvFile CsvFile::parse(std::string_view content, std::string_view origin, std::string_view expected_header) {
  std::istringstream in{std::string(content)};
  CsvFile f;
  f.origin = std::string(origin);
  std::string text;
  int n = 0;
  while (std::getline(in, text)) f.take_line(text, ++n);
  f.require_header(expected_header);
  return f;
}

CsvRows::CsvRows(const DatasetFolder& folder, std::string_view name, std::string_view expected_header)
    : fd_(folder.open(name)), buf_(fd_, std::ios::in), in_(&buf_) {
  f_.origin = folder.path(name).string();
  std::string text;
  while (f_.header.empty() && std::getline(in_, text)) f_.take_line(text, ++n_);
  f_.require_header(expected_header);
}

CsvRows::~CsvRows() = default;  // the filebuf closes the descriptor

bool CsvRows::next() {
  f_.rows.clear(), f_.line.clear();
  std::string text;
  while (std::getline(in_, text))
    if (f_.take_line(text, ++n_)) return true;
  if (in_.bad()) throw DataError(fmt::format("{}: cannot read the file", f_.origin));
  return false;
}

std::optional<std::size_t> CsvFile::find_column(std::string_view name) const {
  for (std::size_t c = 0; c < header.size(); ++c)
    if (header[c] == name) return c;
  return std::nullopt;
}

std::size_t CsvFile::column(std::string_view name, std::string_view section) const {
  if (auto c = find_column(name)) return *c;
  throw DataError(fmt::format("{}:{}: missing column '{}' (see docs/formats.md, \"{}\")", origin,
                              header_line, name, section));
}

double CsvFile::number(std::size_t row, std::size_t col) const {
  const std::string& s = rows[row][col];
  double v = 0;
  const char* b = s.data();
  const char* e = s.data() + s.size();
  if (b != e && *b == '+') ++b;
  auto [end, err] = std::from_chars(b, e, v);
  if (s.empty() || err != std::errc() || end != e || !std::isfinite(v))
    throw DataError(fmt::format("{}:{}: column '{}': expected a finite number, got '{}'", origin,
                                line[row], header[col], quoted_value(s)));
  return v;
}

namespace {

MeasuredData stops_of(const CsvFile& f, bool need_angle) {
  MeasuredData data;
  data.origin = f.origin;
  const std::optional<std::size_t> angle =
      need_angle ? std::optional<std::size_t>(f.column("theta_R_deg")) : f.find_column("theta_R_deg");
  const std::size_t v[3] = {f.column("V1"), f.column("V2"), f.column("V3")};
  const std::optional<std::size_t> utc = f.find_column("utc");
  const std::optional<std::size_t> t_s = f.find_column("t_s");
  if (f.rows.empty())
    throw DataError(fmt::format("{}: no data rows after the header", f.origin));
  for (std::size_t r = 0; r < f.rows.size(); ++r) {
    StopVoltages s;
    s.theta_R_deg = angle ? f.number(r, *angle) : std::numeric_limits<double>::quiet_NaN();
    for (int i = 0; i < 3; ++i) s.V[i] = f.number(r, v[i]);
    s.label = fmt::format("{}:{}", f.origin, f.line[r]);
    data.stops.push_back(s);
    if (t_s) data.t_s.push_back(f.number(r, *t_s));
    if (utc) {
      try {
        data.utc.push_back(parse_utc(f.rows[r][*utc]));
      } catch (const std::invalid_argument& e) {
        throw DataError(fmt::format("{}:{}: column 'utc': expected an ISO 8601 UTC time such as "
                                    "2018-11-16T08:09:40Z, got '{}' ({})", f.origin, f.line[r],
                                    quoted_value(f.rows[r][*utc]), e.what()));
      }
    }
  }
  return data;
}

MeasuredData read_stops(const fs::path& input, bool need_angle, std::string_view what) {
  std::error_code ec;
  fs::path csv = input;
  std::optional<Rig> rig;
  std::string rig_origin;
  if (fs::is_directory(input, ec)) {
    csv = input / "stops.csv";
    if (fs::exists(input / "rig.yaml", ec)) {
      rig = load_rig(input / "rig.yaml").rig;
      rig_origin = (input / "rig.yaml").string();
      require_instrument(*rig, Instrument::kPairVoltages, what, rig_origin);
    }
  }
  MeasuredData data = stops_of(CsvFile::read(csv, kStopsHeader), need_angle);
  data.rig = std::move(rig);
  data.rig_origin = std::move(rig_origin);
  return data;
}

}  // namespace

MeasuredData read_measured(const fs::path& input, std::string_view what) {
  return read_stops(input, true, what);
}
MeasuredData read_voltages(const fs::path& input, std::string_view what) {
  return read_stops(input, false, what);
}

MeasuredData parse_measured_csv(std::string_view text, std::string_view origin, bool need_angle) {
  return stops_of(CsvFile::parse(text, origin, kStopsHeader), need_angle);
}

}  // namespace polrig
