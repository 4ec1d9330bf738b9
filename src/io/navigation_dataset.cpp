#include "polrig/io/navigation_dataset.h"

#include <cmath>
#include <limits>
#include <map>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/dataset_folder.h"
#include "polrig/io/measured.h"
#include "polrig/io/start_yaml.h"
#include "polrig/units.h"
#include "yaml_load.h"

namespace polrig {

namespace {

constexpr std::string_view kSection = "Navigation dataset";

// A number, or nan for a unit without a reading (docs/formats.md §5).
std::string optional_cell(double v) { return std::isfinite(v) ? fmt::format("{}", v) : std::string("nan"); }

std::string imu_csv(const std::vector<ImuSample>& imu) {
  std::string out = "t_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps\n";
  for (const ImuSample& s : imu)
    out += fmt::format("{},{},{},{},{},{},{}\n", s.t_s, s.dtheta.x(), s.dtheta.y(), s.dtheta.z(), s.dv.x(), s.dv.y(),
                       s.dv.z());
  return out;
}

std::string units_csv(const std::vector<CompassEpoch>& compass, bool simulated) {
  std::string out = simulated ? "t_s,unit,aop_deg,dop,V1,V2,V3,true_aop_deg,true_dop\n" : "t_s,unit,aop_deg,dop\n";
  for (const CompassEpoch& e : compass)
    for (std::size_t i = 0; i < e.units.size(); ++i) {
      out += fmt::format("{},{},{},{}", e.t_s, i + 1, optional_cell(rad2deg(e.units[i].aop_rad)), optional_cell(e.units[i].dop));
      if (simulated) {
        const UnitSample& u = e.samples[i];
        out += fmt::format(",{},{},{},{},{}", u.V[0], u.V[1], u.V[2], rad2deg(u.true_aop_rad), u.true_dop);
      }
      out += '\n';
    }
  return out;
}

std::string truth_csv(const std::vector<TruthSample>& truth) {
  std::string out = "t_s,lat_deg,lon_deg,h_m,roll_deg,pitch_deg,yaw_deg,v_e,v_n,v_u\n";
  for (const TruthSample& t : truth)
    out += fmt::format("{},{},{},{},{},{},{},{},{},{}\n", t.t_s, rad2deg(t.lat_rad), rad2deg(t.lon_rad), t.h_m,
                       rad2deg(t.euler.roll_rad), rad2deg(t.euler.pitch_rad), rad2deg(t.euler.yaw_rad), t.v_n.x(),
                       t.v_n.y(), t.v_n.z());
  return out;
}

std::string triple(const Eigen::Vector3d& v, double scale) {
  return fmt::format("[{}, {}, {}]", v.x() * scale, v.y() * scale, v.z() * scale);
}

std::string truth_yaml(const NavigationTruth& t) {
  const double deg_h = rad2deg(1.0) * 3600, ug = 1e6 / kStandardGravity;
  std::string out = "# The truth of a simulated navigation run (docs/formats.md §6.17).\n";
  out += "units:  # each unit's mounting error δ about its own X, Y, Z (deg), and its nominal placement\n";
  for (std::size_t i = 0; i < t.units.placements.size(); ++i) {
    const UnitPlacement& p = t.units.placements[i];
    const auto& d = t.units.mount_error_deg[i];
    out += fmt::format("  - {{unit: {}, tilt_deg: {}, azimuth_deg: {}, roll_deg: {}, mount_error_deg: [{}, {}, {}]}}\n",
                       i + 1, p.tilt_deg, p.azimuth_deg, p.roll_deg, d[0], d[1], d[2]);
  }
  const auto& m = t.units.misalignment_deg;
  out += fmt::format("misalignment_deg: [{}, {}, {}]  # the compass to the body, about X_b, Y_b, Z_b\n", m[0], m[1], m[2]);
  out += "imu:  # the constant errors this seed drew (bias + turn-on bias; scale factor and misalignment: (I + S + M))\n";
  out += fmt::format("  gyro_bias_deg_h: {}\n", triple(t.imu.gyro_bias, deg_h));
  out += fmt::format("  accel_bias_ug: {}\n", triple(t.imu.accel_bias, ug));
  for (const auto& [name, M] : {std::pair{"gyro_scale_misalignment", &t.imu.gyro_scale_misalignment},
                                {"accel_scale_misalignment", &t.imu.accel_scale_misalignment}})
    out += fmt::format("  {}: [{}, {}, {}]\n", name, triple(M->row(0).transpose(), 1), triple(M->row(1).transpose(), 1),
                       triple(M->row(2).transpose(), 1));
  return out;
}

// The cell of a column that may say "no reading" (nan, or empty), else a finite number.
double optional_number(const CsvFile& f, std::size_t row, std::size_t column) {
  const std::string& c = f.rows[row][column];
  return c.empty() || c == "nan" ? kNaN : f.number(row, column);
}

[[noreturn]] void refuse_cell(const CsvFile& f, std::size_t row, std::string_view column, const std::string& problem) {
  throw DataError(fmt::format("{}:{}: column '{}': {}", f.origin, f.line[row], column, problem));
}

// The sensor's range [C]: a gyro's 2000°/s and an accelerometer's 50 g bound what strapdown IMUs
// measure (tactical and MEMS grades alike); beyond them a sample is not an IMU's.
constexpr double kMaxRate_rad_s = 2000.0 * 3.14159265358979323846 / 180.0;
constexpr double kMaxSpecificForce_mps2 = 50 * kStandardGravity;

constexpr std::string_view kImuHeader = "t_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps";
constexpr std::string_view kUnitsHeader = "t_s,unit,aop_deg,dop";
constexpr std::string_view kTruthHeader = "t_s,lat_deg,lon_deg,h_m,roll_deg,pitch_deg,yaw_deg,v_e,v_n,v_u";

// imu.csv, units.csv and truth.csv are read a row at a time (CsvRows): a long log's memory is its
// samples', not its text's cells.
std::vector<ImuSample> read_imu(const DatasetFolder& folder, double rate_hz) {
  CsvRows rows(folder, "imu.csv", kImuHeader);
  const CsvFile& f = rows.file();
  const std::size_t t = f.column("t_s", kSection);
  const std::array<const char*, 6> names{"dtheta_x_rad", "dtheta_y_rad", "dtheta_z_rad", "dv_x_mps", "dv_y_mps", "dv_z_mps"};
  std::array<std::size_t, 6> c{};
  for (std::size_t i = 0; i < 6; ++i) c[i] = f.column(names[i], kSection);
  const double period = 1 / rate_hz;
  std::vector<ImuSample> out;
  while (rows.next()) {
    constexpr std::size_t r = 0;  // the current row
    ImuSample s;
    s.t_s = f.number(r, t);
    const double dt = s.t_s - (out.empty() ? 0.0 : out.back().t_s);
    // Every interval one IMU period (imu.rate_hz) within 10 %: a gap or a doubled sample is refused.
    if (!(std::abs(dt - period) <= 0.1 * period))
      refuse_cell(f, r, "t_s", out.empty() ? fmt::format("the first sample ends at {} s: expected one IMU period after "
                                                    "the start (t = 0), {} s (imu.rate_hz {} Hz)", s.t_s, period, rate_hz)
                                      : fmt::format("time {} s is {} s after the previous sample's: expected one IMU "
                                                    "period, {} s (imu.rate_hz {} Hz), within 10 %", s.t_s, dt, period,
                                                    rate_hz));
    for (std::size_t i = 0; i < 3; ++i) {
      s.dtheta[static_cast<int>(i)] = f.number(r, c[i]);
      s.dv[static_cast<int>(i)] = f.number(r, c[i + 3]);
    }
    for (std::size_t i = 0; i < 3; ++i) {
      const double w = s.dtheta[static_cast<int>(i)] / dt, a = s.dv[static_cast<int>(i)] / dt;
      if (std::abs(w) > kMaxRate_rad_s)
        refuse_cell(f, r, names[i], fmt::format("{} rad over {} s is {:.4g}°/s, beyond a gyro's 2000°/s", s.dtheta[static_cast<int>(i)],
                                           dt, w * 180 / 3.14159265358979323846));
      if (std::abs(a) > kMaxSpecificForce_mps2)
        refuse_cell(f, r, names[i + 3], fmt::format("{} m/s over {} s is {:.4g} m/s², beyond an accelerometer's 50 g",
                                               s.dv[static_cast<int>(i)], dt, a));
    }
    out.push_back(s);
  }
  if (out.empty()) throw DataError(fmt::format("{}: no IMU samples", f.origin));
  return out;
}

// Every reading must fall on an IMU sample (within 1 ms): the INS's state exists only there.
std::vector<CompassEpoch> read_units_csv(const DatasetFolder& folder, std::size_t units, const std::vector<ImuSample>& imu) {
  CsvRows rows(folder, "units.csv", kUnitsHeader);
  const CsvFile& f = rows.file();
  const std::string path = f.origin;
  std::size_t j = 0;  // the IMU sample the latest reading falls on
  const std::size_t t = f.column("t_s", kSection), u = f.column("unit", kSection), a = f.column("aop_deg", kSection),
                    d = f.column("dop", kSection);
  std::vector<CompassEpoch> out;
  while (rows.next()) {
    constexpr std::size_t r = 0;  // the current row
    const double t_s = f.number(r, t);
    if (out.empty() || t_s != out.back().t_s) {
      if (!out.empty() && !(t_s > out.back().t_s))
        refuse_cell(f, r, "t_s", fmt::format("time {} s is not after the previous reading's {} s", t_s, out.back().t_s));
      if (!out.empty() && out.back().units.size() != units)
        refuse_cell(f, r, "unit", fmt::format("the reading at {} s has {} units, expected {} (device.units.*)", out.back().t_s,
                                         out.back().units.size(), units));
      while (j < imu.size() && imu[j].t_s < t_s - 1e-3) ++j;
      if (j == imu.size() || std::abs(imu[j].t_s - t_s) > 1e-3)
        refuse_cell(f, r, "t_s", fmt::format("the reading at {} s falls on no IMU sample of imu.csv within 1 ms ({})", t_s,
                                         j == imu.size() ? fmt::format("its samples end at {} s", imu.back().t_s)
                                                         : fmt::format("the nearest after it is at {} s", imu[j].t_s)));
      out.push_back({t_s, {}, {}});
    }
    const int index = csv_whole_number(f.rows[r][u], f.origin, f.line[r], "unit", 1, static_cast<int>(units));
    if (static_cast<std::size_t>(index) != out.back().units.size() + 1)
      refuse_cell(f, r, "unit", fmt::format("expected unit {} next (units 1 to {} in order at each time), got {}",
                                       out.back().units.size() + 1, units, index));
    const double aop = optional_number(f, r, a), dop = optional_number(f, r, d);
    if (std::isfinite(dop) && (dop < 0 || dop > 1)) refuse_cell(f, r, "dop", fmt::format("expected a DoP in [0, 1], got {}", dop));
    if (std::isfinite(aop) && std::abs(aop) > 360) refuse_cell(f, r, "aop_deg", fmt::format("expected an angle within ±360°, got {}", aop));
    out.back().units.push_back({deg2rad(aop), dop});
  }
  if (out.empty()) return out;  // a header alone: an IMU log without compass readings (SINS only)
  if (out.back().units.size() != units)
    throw DataError(fmt::format("{}: the last reading at {} s has {} units, expected {}", path, out.back().t_s,
                                out.back().units.size(), units));
  return out;
}

// The truth's physical ranges [C]: a longitude within ±360° (wrapped to [−180°, 180°]); a height
// from the deepest ocean floor to the edge of space; attitude angles within ±360°; a speed below
// orbital (8 km/s). A truth beyond them is not a vehicle's.
constexpr double kMinHeight_m = -11000, kMaxHeight_m = 100000, kMaxSpeed_mps = 8000;

std::vector<TruthSample> read_truth(const DatasetFolder& folder) {
  CsvRows rows(folder, "truth.csv", kTruthHeader);
  const CsvFile& f = rows.file();
  std::array<std::size_t, 10> c{};
  const std::array<const char*, 10> names{"t_s", "lat_deg", "lon_deg", "h_m", "roll_deg", "pitch_deg", "yaw_deg", "v_e", "v_n", "v_u"};
  for (std::size_t i = 0; i < c.size(); ++i) c[i] = f.column(names[i], kSection);
  std::vector<TruthSample> out;
  while (rows.next()) {
    constexpr std::size_t r = 0;  // the current row
    std::array<double, 10> v{};
    for (std::size_t i = 0; i < c.size(); ++i) v[i] = f.number(r, c[i]);
    if (std::abs(v[1]) > 90) refuse_cell(f, r, "lat_deg", fmt::format("expected a latitude in [-90, 90], got {}", v[1]));
    if (std::abs(v[2]) > 360) refuse_cell(f, r, "lon_deg", fmt::format("expected a longitude within ±360°, got {}", v[2]));
    if (!(v[3] >= kMinHeight_m && v[3] <= kMaxHeight_m))
      refuse_cell(f, r, "h_m", fmt::format("expected a height in [{}, {}] m, got {}", kMinHeight_m, kMaxHeight_m, v[3]));
    for (std::size_t i = 4; i < 7; ++i)
      if (std::abs(v[i]) > 360) refuse_cell(f, r, names[i], fmt::format("expected an angle within ±360°, got {}", v[i]));
    for (std::size_t i = 7; i < 10; ++i)
      if (std::abs(v[i]) > kMaxSpeed_mps)
        refuse_cell(f, r, names[i], fmt::format("expected a velocity within ±{} m/s, got {}", kMaxSpeed_mps, v[i]));
    if (!out.empty() && !(v[0] > out.back().t_s))
      refuse_cell(f, r, "t_s", fmt::format("time {} s is not after the previous row's {} s", v[0], out.back().t_s));
    TruthSample s;
    s.t_s = v[0];
    s.lat_rad = deg2rad(v[1]);
    s.lon_rad = deg2rad(std::remainder(v[2], 360.0));
    s.h_m = v[3];
    s.euler = {deg2rad(v[4]), deg2rad(v[5]), deg2rad(v[6])};
    s.C_bn = C_bn_from_euler(s.euler);
    s.v_n = {v[7], v[8], v[9]};
    out.push_back(s);
  }
  return out;
}

}  // namespace

std::vector<DatasetFile> write_navigation_dataset(const std::filesystem::path& dir, const NavigationDataset& data) {
  const bool simulated = data.truth.has_value();
  write_text_file(dir / "imu.csv", imu_csv(data.imu));
  write_text_file(dir / "units.csv", units_csv(data.compass, simulated));
  std::vector<DatasetFile> files{
      {"imu.csv", 1, "IMU increments over (previous t_s, t_s]: angle (rad) and velocity (m/s) about and along X_b, Y_b, Z_b"},
      {"units.csv", 1, simulated ? "every unit's AoP (its own frame, spec sense) and DoP per compass reading; the pair "
                                   "voltages and the true AoP and DoP"
                                 : "every unit's AoP and DoP per compass reading"}};
  if (simulated) {
    write_text_file(dir / "truth.csv", truth_csv(data.truth->trajectory));
    write_text_file(dir / "truth.yaml", truth_yaml(*data.truth));
    files.push_back({"truth.csv", 1, "the true position, attitude and velocity at every IMU sample (t = 0 first)"});
    files.push_back({"truth.yaml", 1, "the units' mounting errors and the IMU's drawn constant errors"});
  }
  return files;
}

NavigationDataset read_navigation_dataset(const std::filesystem::path& dir, const Rig& rig) {
  return read_navigation_dataset(DatasetFolder(dir), rig);
}

NavigationDataset read_navigation_dataset(const DatasetFolder& folder, const Rig& rig) {
  NavigationDataset d;
  d.start = rig.source.sky.resolved_sky().first_stop;
  // A dataset with a truth (simulated) starts as simulate's did, with the drawn start errors of
  // navigation.initial_errors; a measured log where its rig says.
  d.initial = initial_state(rig, folder.has("truth.csv") ? StartErrors::DrawnFromP0 : StartErrors::Stated);
  // A start.yaml states the start and its P0 blocks itself (io/start_yaml.h): it replaces the rig's.
  if (folder.has("start.yaml")) {
    const StatedStart stated = parse_start_yaml(folder.read("start.yaml", kMaxYamlBytes), folder.path("start.yaml").string());
    d.initial = stated.state;
    d.stated_start = stated.sigma;
  }
  const UnitArrayTruth layout = unit_array_truth(rig.units, rig.seed);
  for (const Axes3& C : layout.nominal) d.mounts.push_back({C});
  d.imu = read_imu(folder, rig.imu.rate_hz);
  // Without units.csv (or with its header alone) an IMU log: navigate runs SINS only.
  if (folder.has("units.csv")) d.compass = read_units_csv(folder, d.mounts.size(), d.imu);
  if (folder.has("truth.csv")) {
    NavigationTruth truth;
    truth.trajectory = read_truth(folder);
    for (const CompassEpoch& e : d.compass)
      if (!find_truth(truth, e.t_s))
        throw DataError(fmt::format("{}: no row at t = {} s (the truth must hold every compass reading's time; a "
                                    "measured dataset has no truth.csv)", folder.path("truth.csv").string(), e.t_s));
    d.truth = std::move(truth);
  }
  return d;
}

}  // namespace polrig
