#include "polrig/io/measured.h"
#include "polrig/quoted.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include <fmt/format.h>

#include "polrig/io/rig_yaml.h"

namespace polrig {
namespace fs = std::filesystem;

namespace {
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

CsvFile CsvFile::read(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    throw DataError(fmt::format("{}: cannot read the file: {}", path.string(),
                                fs::exists(path, ec) ? "not a regular file" : "no such file"));
  std::ifstream in(path, std::ios::binary);
  std::stringstream buf;
  buf << in.rdbuf();
  return parse(buf.str(), path.string());
}

CsvFile CsvFile::parse(std::string_view content, std::string_view origin) {
  std::istringstream in{std::string(content)};
  CsvFile f;
  f.origin = std::string(origin);
  std::string text;
  int n = 0;
  while (std::getline(in, text)) {
    ++n;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    if (text.find_first_not_of(" \t") == std::string::npos) continue;  // blank line
    if (!text.empty() && text[0] == '#') continue;                       // comment
    if (f.header.empty()) {
      f.header = split_fields(text);
      f.header_line = n;
      continue;
    }
    std::vector<std::string> fields = split_fields(text);
    if (fields.size() != f.header.size())
      throw DataError(fmt::format("{}:{}: expected {} fields as in the header, got {}", f.origin,
                                  n, f.header.size(), fields.size()));
    f.rows.push_back(std::move(fields));
    f.line.push_back(n);
  }
  if (f.header.empty())
    throw DataError(fmt::format("{}: the file is empty; expected a header line such as "
                                "theta_R_deg,V1,V2,V3", f.origin));
  return f;
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
  MeasuredData data = stops_of(CsvFile::read(csv), need_angle);
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
  return stops_of(CsvFile::parse(text, origin), need_angle);
}

}  // namespace polrig
