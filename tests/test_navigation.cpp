// Z21's system end to end (study/navigation.h; docs/physics.md §20): the rig's trajectory.*, imu.*
// and navigation.* keys, the simulated dataset, its files and the three modes, against references
// written here: the closed-form displacement of a drive on a plane, the Astronomical Almanac's sun
// (tests/almanac_sun.h, not ERFA) and the spec's closed forms (§4.7).
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <fmt/format.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "almanac_sun.h"
#include "polrig/ins/earth.h"
#include "polrig/io/dataset_folder.h"
#include "polrig/io/measured.h"
#include "polrig/io/navigation_dataset.h"
#include "polrig/io/output_dir.h"
#include "polrig/io/plot.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/io/start_yaml.h"
#include "polrig/rig/error.h"
#include "polrig/rig/keys.h"
#include "polrig/study/installation.h"
#include "polrig/study/navigation.h"
#include "polrig/statistics.h"
#include "polrig/units.h"
#include "support.h"

using namespace polrig;
namespace fs = std::filesystem;

namespace {


Rig load(const std::string& name, const std::vector<RigOverride>& sets = {}) {
  return load_rig(std::string(POLRIG_SOURCE_DIR) + "/rigs/" + name, sets).rig;
}

std::string rig_error(const std::string& name, const std::vector<RigOverride>& sets) {
  try {
    load(name, sets);
  } catch (const RigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no RigError";
  return "";
}

// A quiet compass and a perfect IMU: noise-free units (31-bit ADC) read with their own truth, no
// IMU error, the INS started at the truth, `seconds` long.
std::vector<RigOverride> ideal(double seconds) {
  return {{"electronics.noise_sigma_V", "0"}, {"electronics.adc_bits", "31"}, {"schedule.samples_per_stop", "1"},
          {"imu.gyro.turn_on_deg_h", "[0, 0, 0]"}, {"imu.gyro.arw_deg_rt_h", "[0, 0, 0]"},
          {"imu.accel.turn_on_ug", "[0, 0, 0]"}, {"imu.accel.vrw_ug_rt_hz", "[0, 0, 0]"},
          {"trajectory.duration_s", std::to_string(seconds)}, {"navigation.initial_errors", "none"}};
}

}  // namespace

// ---- the rig's keys -------------------------------------------------------------------------

TEST(NavigationRig, TheShippedRigsLoadAndRoundTrip) {
  for (const char* name : {"zhang2021-static.yaml", "zhang2021-vehicle.yaml"}) {
    SCOPED_TRACE(name);
    const Rig rig = load(name);
    EXPECT_EQ(rig.device_kind, "unit-array");
    const Rig back = parse_rig(rig_to_yaml(rig), "back.yaml").rig;
    EXPECT_EQ(rig_to_yaml(back), rig_to_yaml(rig));
    EXPECT_EQ(back.trajectory.segment_s, rig.trajectory.segment_s);
    EXPECT_EQ(back.imu.gyro.white_noise, rig.imu.gyro.white_noise);
  }
  // The defaults are Z21's Table 1 as ins/imu.h's z21_imu_errors reads it (an independent copy).
  const ImuErrorSpec a = imu_error_spec(ImuSettings{}), b = z21_imu_errors();
  EXPECT_NEAR((a.gyro.turn_on_bias_sigma - b.gyro.turn_on_bias_sigma).norm(), 0, 1e-20);
  EXPECT_NEAR((a.gyro.white_noise - b.gyro.white_noise).norm(), 0, 1e-20);
  EXPECT_NEAR((a.accel.turn_on_bias_sigma - b.accel.turn_on_bias_sigma).norm(), 0, 1e-18);
  EXPECT_NEAR((a.accel.white_noise - b.accel.white_noise).norm(), 0, 1e-18);
  // 5°/h is 2.424e-5 rad/s; 0.5°/√h is 1.454e-4 rad/√s; 25 µg/√Hz is 2.452e-4 m/s/√s.
  EXPECT_NEAR(a.gyro.turn_on_bias_sigma.x(), 5 * kPi / 180 / 3600, 1e-18);
  EXPECT_NEAR(a.gyro.white_noise.x(), 0.5 * kPi / 180 / 60, 1e-18);
  EXPECT_NEAR(a.accel.white_noise.x(), 25e-6 * 9.80665, 1e-18);
}

TEST(NavigationRig, ARunThatCannotBeFlownIsRefusedByItsKey) {
  const char* r = "zhang2021-vehicle.yaml";
  EXPECT_HAS(rig_error(r, {{"trajectory.segment_turn_deg_s", "[0, 3]"}}),
             "key 'trajectory.segment_turn_deg_s': expected one value per segment of trajectory.segment_s (8), got 2");
  EXPECT_HAS(rig_error(r, {{"trajectory.segment_turn_deg_s", "[1, 0, 3, 0, -3, 0, 0, 0]"}}),
             "expected one motion per segment");
  EXPECT_HAS(rig_error(r, {{"trajectory.segment_accel_mps2", "[0.5, 0, 0, 0, 0, 0, -1, 0]"}}),
             "expected a speed ≥ 0 throughout, segment 7 ends at -10 m/s");
  EXPECT_HAS(rig_error(r, {{"trajectory.segment_s", "[20, 120, 30, 300, 30, 300, 20, 380.005]"}}),
             "key 'trajectory.segment_s': expected a whole number of IMU intervals");
  EXPECT_HAS(rig_error(r, {{"device.units.rate_hz", "3"}}), "key 'device.units.rate_hz': expected a rate that divides");
  EXPECT_HAS(rig_error(r, {{"imu.rate_hz", "2000"}, {"trajectory.segment_s", "[20, 120, 30, 300, 30, 300, 20, 3800]"}}),
             "expected at most 2e6 IMU samples");
  try {
    parse_rig("device: {kind: unit-array}\n", "units.yaml");
    ADD_FAILURE() << "a unit array under the port's light";
  } catch (const RigError& e) {
    EXPECT_HAS(e.what(), "key 'source.model': expected sky for device.kind unit-array (its units read the sky), got 'cos4'");
  }
  EXPECT_HAS(rig_error(r, {{"imu.gyro.arw_deg_rt_h", "[0.5, -1, 0.5]"}}), "key 'imu.gyro.arw_deg_rt_h'");
  EXPECT_HAS(rig_error(r, {{"trajectory.pitch_deg", "85"}}), "key 'trajectory.pitch_deg'");
  // The rest detector weighs each axis by its white noise: none is no detector.
  EXPECT_HAS(rig_error(r, {{"navigation.zupt", "true"}, {"imu.accel.vrw_ug_rt_hz", "[25, 0, 25]"}}),
             "key 'imu.accel.vrw_ug_rt_hz': expected a positive density on every axis with navigation.zupt true");
  EXPECT_HAS(rig_error(r, {{"trajectory.vibration_mps2", "-0.1"}}), "key 'trajectory.vibration_mps2'");
  EXPECT_HAS(rig_error(r, {{"navigation.zupt_sigma_mps", "0"}}), "key 'navigation.zupt_sigma_mps'");
  EXPECT_HAS(rig_error(r, {{"navigation.integrated_level", "accelerometer"}}),
             "key 'navigation.measurement': expected elevation-z21 with navigation.integrated_level accelerometer");
  EXPECT_HAS(rig_error(r, {{"navigation.measurement", "heading"}}), "key 'navigation.measurement'");
  EXPECT_HAS(rig_error(r, {{"navigation.initial_errors", "some"}}), "key 'navigation.initial_errors'");
  // The third review's finding 2: a start at the pole (inside sky.lat_deg's range) ran with
  // non-finite filter rows; the INS's domain is refused at load.
  EXPECT_HAS(rig_error(r, {{"sky.lat_deg", "90"}}), "key 'sky.lat_deg': expected a latitude within ±89° for device.kind unit-array");
}

// Findings 10 and 11: a trajectory that reaches past ±89° is refused naming the rig's keys (it
// was "sun position: latitude 90.0017° is outside"); one round a parallel across 180° keeps every
// longitude in (−180°, 180°] (it was refused at 360°, and truth.csv carried 190°), and the SINS's
// error across the antimeridian is its drift, not 360°.
TEST(NavigationRig, TrajectoriesNearThePoleAndAcrossTheAntimeridian) {
  Rig rig = load("zhang2021-vehicle.yaml");
  rig.source.sky.sky.site.lat_deg = 88.999, rig.trajectory.heading_deg = 0;
  try {
    navigation_scene(rig);
    ADD_FAILURE() << "a trajectory past 89°";
  } catch (const std::invalid_argument& e) {
    EXPECT_HAS(std::string(e.what()), "the trajectory (sky.lat_deg 88.999°, trajectory.heading_deg 0°");
    EXPECT_HAS(std::string(e.what()), "reaches latitude 89.0000");
  }
  rig = load("zhang2021-vehicle.yaml");
  rig.source.sky.sky.site.lat_deg = 85, rig.source.sky.sky.site.lon_deg = 179.9, rig.trajectory.heading_deg = 90;
  const NavigationDataset d = simulate_navigation(rig);
  double west = 0, east = 0;
  for (const TruthSample& t : d.truth->trajectory) {
    EXPECT_LE(std::abs(t.lon_rad), std::numbers::pi);
    west = std::min(west, t.lon_rad), east = std::max(east, t.lon_rad);
  }
  EXPECT_LT(west, deg2rad(-179));  // it did cross
  EXPECT_GT(east, deg2rad(179.9));
  NavigationOptions o;
  o.modes = {NavigationMode::Sins};
  const NavigationRun run = navigate(d, rig, o);
  for (const NavigationFix& f : run.fixes[0]) {
    EXPECT_LE(std::abs(f.lon_rad), std::numbers::pi);
    EXPECT_LT(std::abs(position_error(f, truth_at(*d.truth, f.t_s)).east_m), 100e3) << f.t_s;
  }
}

// The vehicle rig's drive against its displacement on a plane, written here segment by segment
// (a turn of rate ω at speed u is an arc of radius u/ω): the ellipsoid's curvature over the 7 km
// moves the end by ~d²·tan L/(2R) ≈ 3 m, so 10 m.
TEST(NavigationRig, TheVehicleDriveEndsWhereItsSegmentsSay) {
  const Rig rig = load("zhang2021-vehicle.yaml");
  const Trajectory tr = generate_trajectory(trajectory_spec(rig));
  double E = 0, N = 0, psi = 30 * kPi / 180, u = 0;
  const auto straight = [&](double d) { E += d * std::sin(psi), N += d * std::cos(psi); };
  const auto turn = [&](double dpsi, double rate) {
    const double R = u / std::abs(rate);
    const double s = dpsi > 0 ? 1 : -1;
    E += s * R * (std::cos(psi) - std::cos(psi + dpsi));
    N += s * R * (std::sin(psi + dpsi) - std::sin(psi));
    psi += dpsi;
  };
  straight(0.5 * 0.5 * 20 * 20);
  u = 10;
  straight(1200);
  turn(kPi / 2, 3 * kPi / 180);
  straight(3000);
  turn(-kPi / 2, 3 * kPi / 180);
  straight(3000);
  straight(100);
  const TruthSample& end = tr.truth.back();
  const EarthRadii r = earth_radii(deg2rad(39.979));
  const double north = (end.lat_rad - deg2rad(39.979)) * (r.R_M + 50);
  const double east = (end.lon_rad - deg2rad(116.339)) * (r.R_N + 50) * std::cos(deg2rad(39.979));
  std::printf("drive: end %.1f m north, %.1f m east (plane: %.1f, %.1f)\n", north, east, N, E);
  EXPECT_NEAR(north, N, 10);
  EXPECT_NEAR(east, E, 10);
  EXPECT_NEAR(end.v_n.norm(), 0, 1e-9);
  EXPECT_NEAR(rad2deg(end.euler.yaw_rad), 30, 1e-9);
  EXPECT_EQ(tr.imu.size(), 120000u);
}

// ins/'s attitude (Eigen, C_b^n = Rz(−yaw)·Rx(pitch)·Ry(roll)) and compass/'s (Axes3, body_axes_enu from
// compass/heading.h's body_to_enu) are one convention: the same matrix for the same angles, to rounding.
TEST(NavigationAttitude, InsAndNavGiveTheSameBodyAxes) {
  double worst = 0;
  for (double yaw : {0.0, 30.0, 135.0, 251.0, 359.0})
    for (double pitch : {-40.0, 0.0, 12.5})
      for (double roll : {-170.0, -3.0, 0.0, 25.0}) {
        const Axes3 a = axes_of(C_bn_from_euler({deg2rad(roll), deg2rad(pitch), deg2rad(yaw)}));
        const Axes3 b = body_axes_enu(yaw, roll, pitch);
        for (int c = 0; c < 3; ++c)
          for (int r = 0; r < 3; ++r) worst = std::max(worst, std::abs(a[c][r] - b[c][r]));
      }
  EXPECT_LT(worst, 1e-15);
}

// ---- the dataset ----------------------------------------------------------------------------

// Noise-free, the two highest-DoP units with their nominal frames and the true attitude give the
// sun's true elevation: against the almanac (0.01°) and against the ERFA truth of the dataset.
TEST(NavigationDataset, TheUnitsSeeTheSunsElevation) {
  const Rig rig = load("zhang2021-static.yaml", ideal(60));
  const NavigationDataset d = simulate_navigation(rig);
  ASSERT_EQ(d.compass.size(), 60u);
  ASSERT_TRUE(d.truth);
  const UtcTime start = parse_utc("2019-09-18T08:14:00Z");
  for (std::size_t k = 0; k < d.compass.size(); k += 10) {
    const UnitSun sun = sun_from_units(d.compass[k].units, d.mounts);
    ASSERT_EQ(sun.status, UnitSunStatus::Ok);
    const TruthSample& t = truth_at(*d.truth, d.compass[k].t_s);
    const double H = rad2deg(sun_in_nav(sun.s_b, axes_of(t.C_bn)).elevation_rad);
    const test::AlmanacSun a = test::almanac_sun(start.unix_s + d.compass[k].t_s, 39.979, 116.339);
    EXPECT_NEAR(H, 90 - a.zenith_deg, 0.02) << k;
    EXPECT_NEAR(H, rad2deg(d.truth->sun_elevation_rad[k]), 1e-6) << k;
  }
  // Z21's sun sinks from 22.9° towards 18.4° over 20 min (spec §4.5): here the first minute.
  EXPECT_NEAR(rad2deg(d.truth->sun_elevation_rad.front()), 22.9, 0.05);
}

TEST(NavigationDataset, AScenesRunIsTheRigsRunForAnySeed) {
  // navigation_scene (trajectory and sun) made from one seed and reused for another, as the study
  // reuses it across trials: the same bits as simulate_navigation(rig) of that seed, noise and all.
  const Rig a = load("zhang2021-static.yaml", {{"trajectory.duration_s", "120"}, {"seed", "1"}});
  const Rig b = load("zhang2021-static.yaml", {{"trajectory.duration_s", "120"}, {"seed", "2"}});
  const NavigationScene scene = navigation_scene(a);
  const NavigationDataset direct = simulate_navigation(b), shared = simulate_navigation(b, scene);
  ASSERT_EQ(shared.imu.size(), direct.imu.size());
  ASSERT_EQ(shared.compass.size(), direct.compass.size());
  for (std::size_t i = 0; i < direct.imu.size(); ++i) {
    ASSERT_EQ(shared.imu[i].dtheta, direct.imu[i].dtheta) << i;
    ASSERT_EQ(shared.imu[i].dv, direct.imu[i].dv) << i;
  }
  for (std::size_t k = 0; k < direct.compass.size(); ++k)
    for (std::size_t u = 0; u < direct.mounts.size(); ++u) {
      EXPECT_EQ(shared.compass[k].units[u].aop_rad, direct.compass[k].units[u].aop_rad) << k;
      EXPECT_EQ(shared.compass[k].units[u].dop, direct.compass[k].units[u].dop) << k;
    }
  EXPECT_EQ(shared.truth->sun_elevation_rad, direct.truth->sun_elevation_rad);
  EXPECT_NE(simulate_navigation(a, scene).imu[500].dtheta, shared.imu[500].dtheta);  // the seeds differ
  // A scene of another run length is refused, naming both.
  const Rig longer = load("zhang2021-static.yaml", {{"trajectory.duration_s", "180"}});
  try {
    simulate_navigation(longer, scene);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("12001 samples and 120 compass epochs, the rig's run has 18001 and 180"),
              std::string::npos) << e.what();
  }
}

TEST(NavigationDataset, FilesReadBackToTheSameRun) {
  test::TempDir dir("polrig-nav-files");
  const Rig rig = load("zhang2021-static.yaml", {{"trajectory.duration_s", "120"}});
  const NavigationDataset d = simulate_navigation(rig);
  write_navigation_dataset(dir.path(), d);
  const NavigationDataset back = read_navigation_dataset(dir.path(), rig);
  ASSERT_EQ(back.imu.size(), d.imu.size());
  ASSERT_EQ(back.compass.size(), d.compass.size());
  for (std::size_t i = 0; i < d.imu.size(); i += 997) {
    EXPECT_EQ(back.imu[i].t_s, d.imu[i].t_s);
    EXPECT_EQ(back.imu[i].dtheta, d.imu[i].dtheta);
    EXPECT_EQ(back.imu[i].dv, d.imu[i].dv);
  }
  for (std::size_t k = 0; k < d.compass.size(); ++k)
    for (std::size_t u = 0; u < d.mounts.size(); ++u) {
      EXPECT_NEAR(back.compass[k].units[u].aop_rad, d.compass[k].units[u].aop_rad, 1e-15);
      EXPECT_EQ(back.compass[k].units[u].dop, d.compass[k].units[u].dop);
    }
  EXPECT_EQ(back.initial.q_bn.coeffs(), d.initial.q_bn.coeffs());
  const NavigationRun a = navigate(d, rig), b = navigate(back, rig);
  for (std::size_t m = 0; m < a.modes.size(); ++m)
    for (std::size_t k = 0; k < a.fixes[m].size(); ++k) {
      // Only the aop's ulp from degrees differs.
      if (std::isfinite(a.fixes[m][k].lat_rad)) {
        EXPECT_NEAR(a.fixes[m][k].lat_rad, b.fixes[m][k].lat_rad, 1e-12);
      }
    }
}

// A measured log's start stated in start.yaml (docs/formats.md §6.17): the INS starts there, with
// its velocity in ENU (not along the nose) and its P0 blocks, whatever the rig's start says.
TEST(NavigationDataset, AStartYamlStatesTheStartAndItsP0) {
  test::TempDir dir("polrig-nav-start");
  // A cruise at 10 m/s towards 30° on a perfect IMU, the truth the reference.
  std::vector<RigOverride> cruise = {{"trajectory.speed_mps", "10"}, {"trajectory.segment_s", "[60]"},
                                     {"trajectory.segment_accel_mps2", "[0]"}, {"trajectory.segment_turn_deg_s", "[0]"}};
  for (const RigOverride& o : ideal(60))
    if (o.path != "trajectory.duration_s") cruise.push_back(o);
  const NavigationDataset d = simulate_navigation(load("zhang2021-vehicle.yaml", cruise));
  write_navigation_dataset(dir.path(), d);
  fs::remove(dir.path() / "truth.csv");
  fs::remove(dir.path() / "truth.yaml");
  // The rig the log is read with says something else: at rest, heading 80°.
  std::vector<RigOverride> wrong = cruise;
  wrong[0] = {"trajectory.speed_mps", "0"};
  wrong.push_back({"trajectory.heading_deg", "80"});
  const Rig rig = load("zhang2021-vehicle.yaml", wrong);
  NavigationOptions sins;
  sins.modes = {NavigationMode::Sins};
  const TruthSample& end = d.truth->trajectory.back();
  const auto miss_m = [&](const NavigationDataset& data) {
    const PositionError e = position_error(navigate(data, rig, sins).fixes[0].back(), end);
    return std::hypot(e.north_m, e.east_m);
  };
  EXPECT_GT(miss_m(read_navigation_dataset(dir.path(), rig)), 300.0);  // the rig's start: 600 m of cruise lost

  const TruthSample& t0 = d.truth->trajectory.front();
  test::write_file(dir.path() / "start.yaml",
                   fmt::format("lat_deg: {}\nlon_deg: {}\nh_m: {}\nv_enu_mps: [{}, {}, {}]\nattitude_deg: [0, 0, 30]\n"
                               "sigma:\n  attitude_deg: [0.05, 0.05, 0.5]\n  v_enu_mps: [0.02, 0.02, 0.02]\n"
                               "  position_m: [5000, 3000, 10]\n",
                               rad2deg(t0.lat_rad), rad2deg(t0.lon_rad), t0.h_m, 10 * std::sin(std::numbers::pi / 6),
                               10 * std::cos(std::numbers::pi / 6), 0));
  const NavigationDataset stated = read_navigation_dataset(dir.path(), rig);
  ASSERT_TRUE(stated.stated_start.has_value());
  EXPECT_NEAR((stated.initial.v_n - t0.v_n).norm(), 0, 1e-12);
  const double m = miss_m(stated);
  std::printf("start.yaml: the SINS ends %.3g m from the truth after a minute's cruise\n", m);
  EXPECT_LT(m, 0.01);  // a perfect IMU from the true start (the mechanization's mm: test_ins)
  // P0's position block: north 5000 m, east 3000 m at the start's latitude (a metre of latitude
  // and of longitude from WGS-84's radii of curvature, ins/earth.h).
  const Matrix15 P0 = initial_covariance(rig, stated);
  const EarthRadii r = earth_radii(t0.lat_rad);
  EXPECT_NEAR(std::sqrt(P0(kDLat, kDLat)) * (r.R_M + t0.h_m), 5000, 1e-6);
  EXPECT_NEAR(std::sqrt(P0(kDLon, kDLon)) * (r.R_N + t0.h_m) * std::cos(t0.lat_rad), 3000, 1e-6);
  EXPECT_EQ(P0(kDh, kDh), 0.0);  // held (navigation.hold_height)
  EXPECT_EQ(P0(kGyroBias, kGyroBias), initial_covariance(rig)(kGyroBias, kGyroBias));  // the IMU's blocks stay
  EXPECT_HAS(start_text(stated, rig), "start.yaml");
  EXPECT_HAS(vertical_channel_text(rig, stated), "start.yaml's h_m");
}

// The third review's §4 leftover: a whole-file read from a dataset's folder has a limit, checked
// before anything is read (a 2 MB start.yaml against 1 MiB; rig.yaml's is 32 MiB).
TEST(NavigationDataset, AFolderReadRefusesAFileOverItsLimitNamingIt) {
  test::TempDir dir("polrig-nav-cap");
  test::write_file(dir.path() / "start.yaml", std::string(2'000'000, '#'));
  const DatasetFolder folder(dir.path());
  try {
    folder.read("start.yaml", 1u << 20);
    ADD_FAILURE() << "read";
  } catch (const DataError& e) {
    EXPECT_HAS(std::string(e.what()), "start.yaml: 2000000 bytes, more than the 1048576 bytes its reader takes");
  }
  EXPECT_EQ(folder.read("start.yaml", 2'000'000).size(), 2'000'000u);
}

TEST(NavigationDataset, ABadStartYamlIsNamedWithItsLineAndKey) {
  const std::string good =
      "lat_deg: 40\nlon_deg: 116\nh_m: 50\nv_enu_mps: [0, 0, 0]\nattitude_deg: [0, 0, 30]\n"
      "sigma:\n  attitude_deg: [0.05, 0.05, 0.5]\n  v_enu_mps: [0.02, 0.02, 0.02]\n  position_m: [200, 200, 10]\n";
  EXPECT_NEAR(rad2deg(parse_start_yaml(good, "start.yaml").state.lat_rad), 40, 1e-12);
  const auto error = [](const std::string& text) {
    try {
      parse_start_yaml(text, "D/start.yaml");
    } catch (const DataError& e) {
      return std::string(e.what());
    }
    ADD_FAILURE() << "accepted:\n" << text;
    return std::string();
  };
  const auto with = [&](const std::string& from, const std::string& to) {
    std::string t = good;
    t.replace(t.find(from), from.size(), to);
    return t;
  };
  EXPECT_HAS(error(with("lat_deg: 40", "lat_deg: 89.5")), "D/start.yaml:1: key 'lat_deg': expected [-89, 89]");
  EXPECT_HAS(error(with("lon_deg: 116", "lon_deg: 1000")), "D/start.yaml:2: key 'lon_deg'");
  EXPECT_HAS(error(with("h_m: 50", "h_m: 1e300")), "D/start.yaml:3: key 'h_m'");
  EXPECT_HAS(error(with("h_m: 50", "h_m: nan")), "key 'h_m': expected a number, got 'nan'");
  EXPECT_HAS(error(with("h_m: 50", "h_m: .inf")), "key 'h_m': expected a finite number, got '.inf'");
  EXPECT_HAS(error(with("[0, 0, 0]", "[0, 400, 0]")), "D/start.yaml:4: key 'v_enu_mps[1]'");
  EXPECT_HAS(error(with("[0, 0, 30]", "[0, 0]")), "key 'attitude_deg': expected a list of three");
  EXPECT_HAS(error(with("position_m: [200, 200, 10]", "position_m: [200, 0, 10]")), "D/start.yaml:9: key 'sigma.position_m[1]'");
  EXPECT_HAS(error(with("h_m: 50\n", "")), "key 'h_m': missing");
  EXPECT_HAS(error(good + "speed_mps: 3\n"), "D/start.yaml:10: key 'speed_mps': unknown key");
  EXPECT_HAS(error(good + "h_m: 60\n"), "D/start.yaml:10: key 'h_m': duplicate key (first at line 3)");
  EXPECT_HAS(error("lat_deg: [\n"), "D/start.yaml:");
}

// Same rig and seed, the same bits whatever the thread count (the readings and the PNS fits run
// in parallel; every deviate is counter-based).
TEST(NavigationDataset, BitIdenticalForAnyThreadCount) {
  const Rig rig = load("zhang2021-static.yaml", {{"trajectory.duration_s", "400"}});
  const auto run = [&](int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    const NavigationDataset d = simulate_navigation(rig);
    return std::pair{d, navigate(d, rig)};
  };
  const auto [d1, r1] = run(1);
  const auto [d2, r2] = run(2);
  for (std::size_t k = 0; k < d1.compass.size(); ++k)
    for (std::size_t u = 0; u < d1.mounts.size(); ++u) {
      EXPECT_EQ(std::bit_cast<std::uint64_t>(d1.compass[k].units[u].aop_rad),
                std::bit_cast<std::uint64_t>(d2.compass[k].units[u].aop_rad));
    }
  for (std::size_t m = 0; m < r1.modes.size(); ++m)
    for (std::size_t k = 0; k < r1.fixes[m].size(); ++k) {
      EXPECT_EQ(std::bit_cast<std::uint64_t>(r1.fixes[m][k].lat_rad), std::bit_cast<std::uint64_t>(r2.fixes[m][k].lat_rad));
      EXPECT_EQ(std::bit_cast<std::uint64_t>(r1.fixes[m][k].lon_rad), std::bit_cast<std::uint64_t>(r2.fixes[m][k].lon_rad));
    }
  EXPECT_EQ(r1.fixes[1].back().status, "converged");  // the PNS window (300 s) filled
}

// ---- the three modes ------------------------------------------------------------------------

// A perfect IMU and a noise-free compass: the SINS stays on its start (spec §4.7: pyins's 1e-3 m
// over an hour at rest), the filter's innovations are ~0 and the PNS fix lands on the site.
TEST(Navigation, PerfectSensorsStayOnTheSite) {
  const Rig rig = load("zhang2021-static.yaml", ideal(600));
  const NavigationDataset d = simulate_navigation(rig);
  const NavigationRun run = navigate(d, rig);
  ASSERT_EQ(run.modes.size(), 3u);
  const TruthSample& t = d.truth->trajectory.back();
  const PositionError sins = position_error(run.fixes[0].back(), t);
  const PositionError pns = position_error(run.fixes[1].back(), t);
  const PositionError both = position_error(run.fixes[2].back(), t);
  std::printf("perfect sensors, 600 s: SINS %.2g m, PNS %.3g m, integrated %.2g m; %s\n",
              std::hypot(sins.north_m, sins.east_m), std::hypot(pns.north_m, pns.east_m),
              std::hypot(both.north_m, both.east_m), run.filter_summary.BriefReport().c_str());
  EXPECT_LT(std::hypot(sins.north_m, sins.east_m), 0.01);
  EXPECT_LT(std::hypot(both.north_m, both.east_m), 1.0);
  EXPECT_EQ(run.fixes[1].back().status, "converged");
  EXPECT_LT(std::hypot(pns.north_m, pns.east_m), 50.0);
  EXPECT_EQ(run.filter_summary.updates, 600);
  for (const FilterEpoch& f : run.filter) EXPECT_LT(std::abs(f.update.innovation), 1e-6);
}

// The fixed-interval smoother (ins/smoother.h; its algebra against the batch solution in test_ins)
// on the shipped vehicle rig over Monte-Carlo trials, each started at an error drawn from P0: the
// smoothed position error is consistent with its Pˢ (NEES of 2 dof inside the 99.9 % χ² band over the
// trials) and its mean square no larger than the filter's, mid-run where later readings inform
// earlier epochs. Elevation updates leave most of the drift unobservable, so the gain is small
// (docs/validation.md: rms 1028 → 947 m at reading 300).
TEST(SlowNavigation, TheRtsSmootherIsConsistentAndHelpsMidRun) {
  constexpr int kTrials = 25;
  constexpr double z999 = 3.2905;
  const std::vector<std::size_t> epochs = {300, 500, 1000};
  std::vector<double> nees(epochs.size()), mse_filtered(epochs.size()), mse_smoothed(epochs.size());
  for (int t = 0; t < kTrials; ++t) {
    const Rig rig = load("zhang2021-vehicle.yaml", {{"seed", std::to_string(1000 + t)}, {"navigation.adaptive", "false"}});
    const NavigationDataset d = simulate_navigation(rig);
    NavigationOptions o;
    o.modes = parse_navigation_modes("smoothed,integrated");
    ASSERT_EQ(o.modes, (std::vector<NavigationMode>{NavigationMode::Integrated, NavigationMode::Smoothed}));
    const NavigationRun run = navigate(d, rig, o);
    ASSERT_EQ(run.smoothed_P.size(), run.fixes[1].size());
    EXPECT_EQ(run.fixes[1].back().lat_rad, run.fixes[0].back().lat_rad);  // y_N = 0
    for (std::size_t j = 0; j < epochs.size(); ++j) {
      const std::size_t k = epochs[j];
      const TruthSample& truth = *find_truth(*d.truth, run.fixes[0][k].t_s);
      const PositionError f = position_error(run.fixes[0][k], truth), s = position_error(run.fixes[1][k], truth);
      const EarthRadii r = earth_radii(truth.lat_rad);
      const Eigen::Matrix2d J = Eigen::Vector2d(r.R_M + truth.h_m, (r.R_N + truth.h_m) * std::cos(truth.lat_rad)).asDiagonal();
      const Eigen::Matrix2d P = J * run.smoothed_P[k].block<2, 2>(kDLat, kDLat) * J;
      const Eigen::Vector2d e(s.north_m, s.east_m);
      nees[j] += e.dot(P.ldlt().solve(e)) / kTrials;
      mse_filtered[j] += (f.north_m * f.north_m + f.east_m * f.east_m) / kTrials;
      mse_smoothed[j] += e.squaredNorm() / kTrials;
    }
  }
  const double lo = 2 * chi2_mean_quantile(2.0 * kTrials, -z999), hi = 2 * chi2_mean_quantile(2.0 * kTrials, z999);
  double filtered_sum = 0, smoothed_sum = 0;
  for (std::size_t j = 0; j < epochs.size(); ++j) {
    std::printf("vehicle, reading %zu: smoothed NEES %.2f [%.2f, %.2f]; rms error filtered %.0f m, smoothed %.0f m\n",
                epochs[j], nees[j], lo, hi, std::sqrt(mse_filtered[j]), std::sqrt(mse_smoothed[j]));
    EXPECT_GE(nees[j], lo);
    EXPECT_LE(nees[j], hi);
    filtered_sum += mse_filtered[j];
    smoothed_sum += mse_smoothed[j];
  }
  EXPECT_LT(smoothed_sum, filtered_sum);
  EXPECT_THROW(parse_navigation_modes("all,smooth"), std::invalid_argument);
  EXPECT_EQ(parse_navigation_modes("all,smoothed").size(), 4u);
}

// navigation.zupt on the shipped vehicle rig (its 0.3 m/s² vibration while moving): the IMU's rest
// detector passes at every reading of the final 380 s rest and at none while the truth moves, and
// the rest's zero-velocity updates bring the velocity error to the 1 mm/s they allow (without them
// the INS drifts at dm/s); the drive's error does not grow through the rest.
TEST(SlowNavigation, ZeroVelocityUpdatesComeAtRestOnlyAndHoldTheVelocity) {
  const Rig rig = load("zhang2021-vehicle.yaml", {{"navigation.zupt", "true"}});
  const NavigationDataset d = simulate_navigation(rig);
  NavigationOptions o;
  o.modes = {NavigationMode::Sins, NavigationMode::Integrated};
  const NavigationRun run = navigate(d, rig, o);
  int at_rest = 0, updated_at_rest = 0, updated_moving = 0;
  for (const FilterEpoch& f : run.filter) {
    // At rest over the whole interval (the brake ends at 0 up to rounding).
    const bool rest = find_truth(*d.truth, f.t_s)->v_n.norm() < 1e-9 && find_truth(*d.truth, f.t_s - 1)->v_n.norm() < 1e-9;
    const bool updated = std::isfinite(f.zero_velocity.east.nis);
    EXPECT_TRUE(std::isfinite(f.rest_statistic));
    at_rest += rest ? 1 : 0;
    updated_at_rest += rest && updated ? 1 : 0;
    updated_moving += !rest && updated ? 1 : 0;
  }
  EXPECT_EQ(at_rest, 380);
  EXPECT_EQ(updated_at_rest, 380);
  EXPECT_EQ(updated_moving, 0);
  EXPECT_EQ(run.filter_summary.zero_velocity_updates, 2 * 380);  // east and north: the height is held
  const NavigationFix& end = run.fixes[1].back();
  const NavigationFix& sins = run.fixes[0].back();
  const NavigationFix& rest_start = run.fixes[1][820];
  std::printf("vehicle with ZUPT: |v| at the end %.2e m/s (SINS %.3f m/s); error at the rest's start %.0f m, end %.0f m\n",
              end.v_enu.norm(), sins.v_enu.norm(),
              std::hypot(position_error(rest_start, truth_at(*d.truth, rest_start.t_s)).north_m,
                         position_error(rest_start, truth_at(*d.truth, rest_start.t_s)).east_m),
              std::hypot(position_error(end, truth_at(*d.truth, end.t_s)).north_m,
                         position_error(end, truth_at(*d.truth, end.t_s)).east_m));
  EXPECT_LT(end.v_enu.norm(), 5e-3);
  EXPECT_GT(sins.v_enu.norm(), 0.1);
  EXPECT_EQ(run.filter_summary.status, FilterStatus::Ok) << run.filter_summary.BriefReport();
}

// Spec §4.6 item 3 [SIM-trend] on the shipped rig: the SINS alone drifts by tens of km in 20 min
// (its tilt by ~2° with 5°/h gyros), while SINS/PNS holds the position along the sun's azimuth, the
// one direction an elevation sees (spec §4.3), to a few km; across it the error grows as the SINS's.
// H^n is measured through the INS's attitude: Z21's position-only H leaves that tilt unmodelled and
// the filter's σ along the sun is then too small; with the tilt columns (navigation.measurement elevation)
// the error lies within 4σ. PNS, levelled by the accelerometers, holds the along-sun direction too.
TEST(SlowNavigation, Z21sStaticRunBoundsTheDriftAlongTheSun) {
  const NavigationDataset d = simulate_navigation(load("zhang2021-static.yaml"));
  const TruthSample& t = d.truth->trajectory.back();
  const test::AlmanacSun a = test::almanac_sun(parse_utc("2019-09-18T08:34:00Z").unix_s, 39.979, 116.339);
  const auto along = [&](const PositionError& e) {
    return e.north_m * std::cos(a.azimuth_rad) + e.east_m * std::sin(a.azimuth_rad);
  };
  // σ along the sun from the filter's north and east σ and their correlation.
  const auto sigma_along = [&](const FilterEpoch& f) {
    const double cn = std::cos(a.azimuth_rad) * f.sigma_north_m, ce = std::sin(a.azimuth_rad) * f.sigma_east_m;
    return std::sqrt(cn * cn + ce * ce + 2 * f.corr_north_east * cn * ce);
  };
  // Z21's H; with the tilt columns; Z21's H with the accelerometers' level (no INS tilt in H^n).
  for (const auto& [tilt, level] : {std::pair{"elevation-z21", "ins"}, {"elevation", "ins"}, {"elevation-z21", "accelerometer"}}) {
    const Rig rig = load("zhang2021-static.yaml", {{"navigation.measurement", tilt},
                                                   {"navigation.integrated_level", level}});
    const NavigationRun run = navigate(d, rig);
    const PositionError sins = position_error(run.fixes[0].back(), t), pns = position_error(run.fixes[1].back(), t),
                        both = position_error(run.fixes[2].back(), t);
    const double sigma = sigma_along(run.filter.back());
    std::printf("Z21 static, 1200 s, measurement %s, level %s: SINS %.1f km (along the sun %.2f km); integrated along the sun "
                "%.2f km (σ %.2f km), across %.1f km; PNS %.2f km (along the sun %.2f km); %s\n", tilt, level,
                std::hypot(sins.north_m, sins.east_m) / 1000, along(sins) / 1000, along(both) / 1000, sigma / 1000,
                std::hypot(both.north_m, both.east_m) / 1000, std::hypot(pns.north_m, pns.east_m) / 1000,
                along(pns) / 1000, run.filter_summary.BriefReport().c_str());
    EXPECT_GT(std::hypot(sins.north_m, sins.east_m), 5e3);
    EXPECT_LT(std::abs(along(both)), std::abs(along(sins)) / 10);
    EXPECT_LT(sigma, 11e3);
    if (std::string(tilt) == "elevation" || std::string(level) == "accelerometer") {
      EXPECT_LT(std::abs(along(both)), 4 * sigma);
    }
    EXPECT_EQ(run.fixes[1].back().status, "converged");
    // PNS fixes along the sun too: a 300-reading window of 0.1° elevations (one: ~11 km); across it
    // the window's short arc of the sun leaves ~100 km (docs/validation.md).
    EXPECT_LT(std::abs(along(pns)), 11e3);
    EXPECT_NE(run.filter_summary.status, FilterStatus::NonFinite);
  }
}

TEST(NavigationStatistics, MaeRmseAndStdOfKnownErrors) {
  const std::vector<double> e{1, -1, 3, std::nan("")};
  const ErrorStatistics s = error_statistics(e);
  EXPECT_EQ(s.count, 3);
  EXPECT_DOUBLE_EQ(s.mae, 5.0 / 3);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(11.0 / 3));
  // mean 1, deviations 0, −2, 2.
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(8.0 / 3));
}

// ---- the installation calibration ------------------------------------------------------------

// Z21 Table 2 [SIM-trend] on the vehicle run (two headings and the turns between them: a static run
// leaves a unit's tilt and roll errors confounded, tests/test_unit_array.cpp): the fitted errors
// land on the injected ones within 4 of their standard errors (+0.01° for the chain's own angle
// error), and the sun's elevation error falls with them.
TEST(SlowNavigationInstallation, TheVehicleRunRecoversInjectedMountingErrors) {
  const Rig rig = load("zhang2021-vehicle.yaml", {{"device.units.mount_error_sd_deg", "1"}});
  const NavigationDataset d = simulate_navigation(rig);
  const InstallationRun run = calibrate_unit_array(d, rig);
  ASSERT_EQ(run.units.size(), 9u);
  EXPECT_EQ(run.attitude_from, "truth");
  double worst = 0;
  for (std::size_t i = 0; i < 9; ++i) {
    EXPECT_TRUE(run.units[i].converged) << i << ": " << run.units[i].termination;
    for (std::size_t a = 0; a < 3; ++a) {
      const double miss = std::abs(run.units[i].error_deg[a] - d.truth->units.mount_error_deg[i][a]);
      EXPECT_LT(miss, 4 * run.units[i].standard_error_deg[a] + 0.01) << "unit " << i + 1 << " axis " << a;
      worst = std::max(worst, miss);
    }
  }
  std::printf("vehicle installation: worst |δ̂ − δ| %.3g°; elevation error mean |e| %.3f° → %.3f°\n", worst,
              run.elevation_mae_before_deg, run.elevation_mae_after_deg);
  EXPECT_GT(run.elevation_mae_before_deg, 0.2);
  EXPECT_LT(run.elevation_mae_after_deg, run.elevation_mae_before_deg / 5);
  // The calibrated frames bring the integrated filter's sun back: its innovations shrink.
  NavigationOptions nominal, calibrated;
  nominal.modes = calibrated.modes = {NavigationMode::Integrated};
  calibrated.mounts = run.mounts();
  const NavigationRun a = navigate(d, rig, nominal), b = navigate(d, rig, calibrated);
  std::printf("innovation rms: nominal frames %.3g, calibrated %.3g\n", a.filter_summary.innovation_rms,
              b.filter_summary.innovation_rms);
  EXPECT_LT(b.filter_summary.innovation_rms, a.filter_summary.innovation_rms);
}

// ---- the commands ---------------------------------------------------------------------------

namespace {
class NavigationCli : public test::PolrigTest {
 protected:
  NavigationCli() : PolrigTest("polrig-navcli-", "") {}
  std::string cd() const { return "cd " + test::shell_quote(tmp) + " && "; }
  static std::string rig(const char* name) { return test::shell_quote(std::string(POLRIG_SOURCE_DIR) + "/rigs/" + name); }
  int lines(const std::string& file) const {
    int n = 0;
    for (char c : test::read_file(tmp / file)) n += c == '\n' ? 1 : 0;
    return n;
  }
};
}  // namespace

TEST_F(NavigationCli, SimulateThenNavigateWritesEveryMode) {
  ok("simulate " + rig("zhang2021-static.yaml") + " --set trajectory.duration_s=120 -o D", cd());
  for (const char* f : {"imu.csv", "units.csv", "truth.csv", "truth.yaml", "manifest.yaml", "rig.yaml"})
    EXPECT_TRUE(fs::exists(tmp / "D" / f)) << f;
  EXPECT_EQ(lines("D/imu.csv"), 1 + 12000);
  EXPECT_EQ(lines("D/units.csv"), 1 + 120 * 9);
  EXPECT_EQ(lines("D/truth.csv"), 1 + 12001);
  const Result r = ok("navigate D -o N", cd());
  EXPECT_HAS(r.out, "integrated filter: ");
  EXPECT_HAS(r.out, "vertical channel: held (navigation.hold_height: h = 50 m (sky.height_m), v_U = 0)");
  EXPECT_HAS(test::read_file(tmp / "N/filter_summary.yaml"), "\nvertical_channel: held  # navigation.hold_height");
  EXPECT_EQ(lines("N/solution.csv"), 1 + 3 * 120);
  EXPECT_EQ(lines("N/filter.csv"), 1 + 120);
  EXPECT_EQ(lines("N/summary.csv"), 1 + 6);
  EXPECT_HAS(test::read_file(tmp / "N/solution.csv"),
             "t_s,mode,lat_deg,lon_deg,h_m,roll_deg,pitch_deg,yaw_deg,v_e_mps,v_n_mps,v_u_mps,status,"
             "err_lat_deg,err_lon_deg,err_north_m,err_east_m,err_v_e_mps,err_v_n_mps,err_v_u_mps\n");
  EXPECT_HAS(test::read_file(tmp / "N/summary.csv"), "mode,coordinate,mae_deg,rmse_deg,std_deg,count,final_error_m\n");
  if (gnuplot_available()) {
    for (const char* png : {"latitude.png", "longitude.png", "position_error.png", "filter.png", "elevation.png"})
      EXPECT_TRUE(fs::exists(tmp / "N" / png)) << png;
  }
  // A held height stays held in every mode (the integrated one moved ±10 m over 20 minutes when
  // the filter's δh was fed back; the third review).
  const test::Csv sol = test::read_csv(tmp / "N/solution.csv");
  for (const auto& row : sol.rows) EXPECT_EQ(row[sol.col("h_m")], "50") << row[sol.col("mode")] << " at " << row[0];
  // One mode alone gives that mode's rows, the same numbers.
  ok("navigate D --mode sins -o S --no-plots", cd());
  EXPECT_EQ(lines("S/solution.csv"), 1 + 120);
  const std::string all = test::read_file(tmp / "N/solution.csv"), sins = test::read_file(tmp / "S/solution.csv");
  EXPECT_HAS(all, sins.substr(sins.find('\n') + 1, 200));
}

// The third review's finding 3: `navigate DS -o DS --force` deleted the dataset it read (the
// output swapped into place, the old folder removed). An output that is, contains or lies inside
// an input is refused before anything runs, for every command, and the input is left whole.
TEST_F(NavigationCli, AnOutputOverItsInputIsRefusedAndTheInputKept) {
  ok("simulate " + rig("zhang2021-static.yaml") + " --set trajectory.duration_s=20 -o D", cd());
  const std::string imu = test::read_file(tmp / "D/imu.csv");
  fs::create_directory_symlink("D", tmp / "L");
  const std::pair<const char*, const char*> cases[] = {
      {"navigate D -o D --force", "is the input D"},
      {"navigate D/ -o ./D --force --no-plots", "is the input D/"},
      {"navigate L -o D --force", "is the input L"},
      {"calibrate D --method unit-array -o D --force", "is the input D"},
      {"navigate D -o D/N", "lies inside the input D"},
      {"navigate D --rig D/rig.yaml -o N --force", ""},  // apart: runs
      // A value that only happens to name a folder is no input (the review of this change).
      {"navigate D --mode sins -o sins --force --no-plots", ""},
  };
  fs::create_directory(tmp / "sins");
  for (const auto& [command, says] : cases) {
    const Result r = polrig(command, cd());
    if (!*says) {
      EXPECT_EQ(r.status, 0) << command << r.err;
      continue;
    }
    EXPECT_EQ(r.status, 2) << command;
    EXPECT_HAS(r.err, says) << command;
  }
  EXPECT_EQ(test::read_file(tmp / "D/imu.csv"), imu);
  EXPECT_FALSE(fs::exists(tmp / "D/N"));
  // A rig file inside the folder a command would replace.
  fs::create_directories(tmp / "R");
  fs::copy_file(std::string(POLRIG_SOURCE_DIR) + "/rigs/wang2019-indoor.yaml", tmp / "R/rig.yaml");
  const Result r = polrig("simulate R/rig.yaml -o R --force --no-plots", cd());
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "the output folder R contains the input R/rig.yaml");
  EXPECT_TRUE(fs::exists(tmp / "R/rig.yaml"));
}

// The third review's findings 9, 13 and 14: a UTF-8 byte-order mark is passed over in every file
// of the dataset; an empty file names its own header; truth.csv's longitude and height are range
// checked, naming the file, the line and the column.
TEST_F(NavigationCli, DatasetFilesTakeAByteOrderMarkAndNameTheirOwnHeader) {
  ok("simulate " + rig("zhang2021-static.yaml") + " --set trajectory.duration_s=20 -o D --no-plots", cd());
  fs::create_directories(tmp / "B");
  for (const char* f : {"imu.csv", "units.csv", "truth.csv", "rig.yaml"}) {
    const std::string text = test::read_file(tmp / "D" / f);
    test::write_file(tmp / "B" / f, std::string(f).ends_with(".csv") ? "\xEF\xBB\xBF" + text : text);
  }
  ok("navigate D -o N1 --no-plots", cd());
  ok("navigate B -o N2 --no-plots", cd());
  EXPECT_EQ(test::read_file(tmp / "N1/solution.csv"), test::read_file(tmp / "N2/solution.csv"));
  const std::pair<const char*, const char*> empty[] = {
      {"imu.csv", "B/imu.csv: the file is empty; expected a header line such as t_s,dtheta_x_rad,"},
      {"units.csv", "B/units.csv: the file is empty; expected a header line such as t_s,unit,aop_deg,dop"},
      {"truth.csv", "B/truth.csv: the file is empty; expected a header line such as t_s,lat_deg,lon_deg,"}};
  for (const auto& [file, says] : empty) {
    const std::string kept = test::read_file(tmp / "B" / file);
    test::write_file(tmp / "B" / file, "");
    const Result r = polrig("navigate B -o N", cd());
    EXPECT_EQ(r.status, 2) << file;
    EXPECT_HAS(r.err, says);
    EXPECT_LACKS(r.err, "theta_R_deg");
    test::write_file(tmp / "B" / file, kept);
  }
  const std::string truth = test::read_file(tmp / "D/truth.csv");
  const auto with_cell = [&](int column, const char* value) {
    std::string t = truth;
    std::size_t p = t.find('\n', t.find('\n') + 1) + 1;  // line 3
    for (int c = 0; c < column; ++c) p = t.find(',', p) + 1;
    t.replace(p, t.find(',', p) - p, value);
    return t;
  };
  test::write_file(tmp / "B/truth.csv", with_cell(2, "1000"));
  EXPECT_HAS(polrig("navigate B -o N", cd()).err, "B/truth.csv:3: column 'lon_deg': expected a longitude within ±360°, got 1000");
  test::write_file(tmp / "B/truth.csv", with_cell(3, "1e300"));
  EXPECT_HAS(polrig("navigate B -o N", cd()).err, "B/truth.csv:3: column 'h_m': expected a height in [-11000, 100000] m");
  // Finding 15: readings past the end of imu.csv, refused by calibrate as by navigate.
  test::write_file(tmp / "B/truth.csv", truth);
  const std::string imu = test::read_file(tmp / "D/imu.csv");
  std::size_t cut = 0;
  for (int l = 0; l < 1 + 1000; ++l) cut = imu.find('\n', cut) + 1;  // the header and 10 s
  test::write_file(tmp / "B/imu.csv", imu.substr(0, cut));
  for (const char* command : {"calibrate B --method unit-array -o N", "navigate B -o N"}) {
    const Result r = polrig(command, cd());
    EXPECT_EQ(r.status, 2) << command;
    EXPECT_HAS(r.err, "B/units.csv:92: column 't_s': the reading at 1") << command;  // the 11th, at 11 s
    EXPECT_HAS(r.err, "falls on no IMU sample of imu.csv within 1 ms (its samples end at ") << command;
  }
  EXPECT_FALSE(fs::exists(tmp / "N"));
}

// Finding 4: a reader that has opened a dataset's folder reads every file from it even when
// another process swaps a new dataset into its place (simulate --force's atomic exchange), and
// fails, naming the file, once the old one is deleted: one dataset, or an error; never a mix.
TEST_F(NavigationCli, AReaderSeesOneDatasetWhileItIsReplaced) {
  ok("simulate " + rig("zhang2021-static.yaml") + " --set trajectory.duration_s=20 -o D --no-plots", cd());
  ok("simulate " + rig("zhang2021-static.yaml") + " --set trajectory.duration_s=30 -o E --no-plots", cd());
  const Rig r = load_rig(tmp / "D/rig.yaml").rig;
  const DatasetFolder folder(tmp / "D");
  ASSERT_EQ(rename_exchange(tmp / "D", tmp / "E"), 0);  // D's name now holds the 30 s dataset
  const NavigationDataset old = read_navigation_dataset(folder, r);
  EXPECT_EQ(old.imu.size(), 2000u);
  EXPECT_EQ(old.compass.size(), 20u);
  EXPECT_EQ(read_navigation_dataset(tmp / "D", r).imu.size(), 3000u);
  fs::remove_all(tmp / "E");  // the old folder, deleted as commit() does
  EXPECT_THROW(
      {
        try {
          read_navigation_dataset(folder, r);
        } catch (const DataError& e) {
          EXPECT_HAS(std::string(e.what()), "imu.csv: cannot read the file: no such file");
          throw;
        }
      },
      DataError);
}

// Finding 1: a legal 5000 s static run drives the integrated solution past the pole (it wrote
// latitude 90.01° at 4691 s, then nan, status ok, exit 0). The solution says `diverged` from the
// epoch it leaves the INS's domain, at its last state inside it; the filter's summary says so; no
// row holds a nan but the PNS's window filling (documented). The finding's filter (Z21's H, the
// 0.0032° bench chain, an INS started at the truth) stays off the pole since the held vertical
// channel is pinned (physics.md §18.6); started at 88.5° N it leaves the domain at 1064 s.
class SlowNavigationCli : public NavigationCli {};
TEST_F(SlowNavigationCli, ARunPastThePoleIsReportedDiverged) {
  ok("simulate " + rig("zhang2021-static.yaml") + " --set trajectory.duration_s=3000 --set sky.lat_deg=88.5 "
     "--set navigation.measurement=elevation-z21 --set electronics.noise_sigma_V=1e-4 --set navigation.initial_errors=none "
     "-o D --no-plots", cd());
  const Result r = polrig("navigate D -o N --no-plots", cd());
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_HAS(r.out, "integrated filter: diverged:");
  EXPECT_HAS(r.err, "polrig: warning: integrated diverged at t = ");
  const test::Csv sol = test::read_csv(tmp / "N/solution.csv");
  bool diverged = false;
  for (const auto& row : sol.rows) {
    const std::string& status = row[sol.col("status")];
    if (row[sol.col("mode")] == "integrated") {
      if (diverged) {
        EXPECT_EQ(status, "diverged") << row[0];
      }
      diverged = diverged || status == "diverged";
      EXPECT_LE(std::abs(std::stod(row[sol.col("lat_deg")])), 89.0) << row[0];
    }
    if (status == "window_filling") continue;
    for (std::size_t c = 0; c < row.size(); ++c) {
      const bool pns_velocity = row[sol.col("mode")] == "pns" && sol.header[c].find("v_") != std::string::npos;
      if (!pns_velocity) {
        EXPECT_NE(row[c], "nan") << row[0] << " " << row[1] << " " << sol.header[c];
      }
    }
  }
  EXPECT_TRUE(diverged);
  // The azimuth's, the rest detector's and the PNS fix's columns: nan (not measured, navigation.zupt
  // off, no pns-fix).
  const test::Csv filter = test::read_csv(tmp / "N/filter.csv");
  for (const auto& row : filter.rows)
    for (std::size_t c = 0; c < row.size(); ++c) {
      const std::string& h = filter.header[c];
      if (h.find("azimuth") == std::string::npos && h.find("rest_") == std::string::npos &&
          h.find("zero_velocity_nis") == std::string::npos && h.find("pns_fix") == std::string::npos) {
        EXPECT_NE(row[c], "nan") << row[0] << " " << filter.header[c];
      }
    }
}

// The third review's §1: an IMU log alone (no units.csv, or its header alone) runs SINS from
// imu.csv and rig.yaml, at every IMU sample or a rate that divides it; a 125.057 Hz log is not
// refused for a simulate-only key (trajectory.duration_s's whole IMU intervals) it never set.
TEST_F(NavigationCli, AnImuLogAloneRunsSinsAtItsOwnRate) {
  ok("simulate " + rig("zhang2021-static.yaml") + " --set trajectory.duration_s=10 -o D --no-plots", cd());
  fs::create_directories(tmp / "L");
  fs::copy_file(tmp / "D/rig.yaml", tmp / "L/rig.yaml");
  const double rate = 125.057, g = 9.80;
  std::string imu = "t_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps\n";
  for (int k = 1; k <= 1250; ++k) imu += fmt::format("{},0,{},{},0,0,{}\n", k / rate, 5.6e-5 / rate, 4.7e-5 / rate, g / rate);
  test::write_file(tmp / "L/imu.csv", imu);
  const Result r = ok("navigate L --mode sins --set imu.rate_hz=125.057 -o S --no-plots", cd());
  EXPECT_HAS(r.out, "1250 IMU samples, 0 compass readings");
  EXPECT_EQ(lines("S/solution.csv"), 1 + 1250);
  const test::Csv sol = test::read_csv(tmp / "S/solution.csv");
  EXPECT_EQ(sol.rows.back()[sol.col("t_s")], fmt::format("{}", 1250 / rate));
  for (const auto& row : sol.rows) EXPECT_NE(row[sol.col("v_e_mps")], "nan");
  test::write_file(tmp / "L/units.csv", "t_s,unit,aop_deg,dop\n");
  ok("navigate L --mode sins --sins-rate-hz 25.0114 --set imu.rate_hz=125.057 -o T --no-plots", cd());
  EXPECT_EQ(lines("T/solution.csv"), 1 + 250);
  Result b = polrig("navigate L --set imu.rate_hz=125.057 -o N", cd());
  EXPECT_EQ(b.status, 2);
  EXPECT_HAS(b.err, "no compass readings (units.csv): PNS and the integrated mode need them; an IMU log alone runs mode sins");
  b = polrig("navigate L --mode sins --sins-rate-hz 7 --set imu.rate_hz=125.057 -o N", cd());
  EXPECT_HAS(b.err, "the SINS output rate 7 Hz does not divide imu.rate_hz (125.057 Hz)");
  // A truth that lacks a SINS output time: refused, exit 2 (it was an internal error, exit 1).
  ok("simulate " + rig("zhang2021-static.yaml") + " --set trajectory.duration_s=10 -o E --no-plots", cd());
  fs::create_directories(tmp / "F");
  for (const char* f : {"imu.csv", "units.csv", "rig.yaml"}) fs::copy_file(tmp / "E" / f, tmp / "F" / f);
  std::string sparse;
  int n = 0;
  for (const std::string& line : test::lines_of(test::read_file(tmp / "E/truth.csv"))) {
    if (n == 0 || (n - 1) % 100 == 0) sparse += line + "\n";  // the header, t = 0, then every reading's row
    ++n;
  }
  test::write_file(tmp / "F/truth.csv", sparse);
  ok("navigate F --mode sins -o G --no-plots", cd());  // at the readings: every time is there
  b = polrig("navigate F --mode sins --sins-rate-hz 50 -o N", cd());
  EXPECT_EQ(b.status, 2);
  EXPECT_HAS(b.err, "truth.csv has no row at t = 0.02");
  // simulate keeps the run's rules.
  b = polrig("simulate L/rig.yaml --set imu.rate_hz=125.057 -o N", cd());
  EXPECT_EQ(b.status, 2);
  EXPECT_HAS(b.err, "expected a rate that divides imu.rate_hz");
  EXPECT_FALSE(fs::exists(tmp / "N"));
}

TEST_F(NavigationCli, AMeasuredDatasetWithoutTruthNavigates) {
  ok("simulate " + rig("zhang2021-static.yaml") + " --set trajectory.duration_s=60 -o D", cd());
  fs::create_directories(tmp / "M");
  for (const char* f : {"imu.csv", "units.csv", "rig.yaml"}) fs::copy_file(tmp / "D" / f, tmp / "M" / f);
  const Result r = ok("navigate M -o N --no-plots", cd());
  EXPECT_FALSE(fs::exists(tmp / "N/summary.csv"));
  EXPECT_LACKS(test::read_file(tmp / "N/solution.csv"), "err_lat_deg");
  EXPECT_EQ(lines("N/solution.csv"), 1 + 3 * 60);
}

TEST_F(NavigationCli, BadInputIsNamedAndNothingIsWritten) {
  ok("simulate " + rig("zhang2021-static.yaml") + " --set trajectory.duration_s=30 -o D", cd());
  // A folder without its rig.
  fs::create_directories(tmp / "E");
  Result r = polrig("navigate E -o N", cd());
  EXPECT_NE(r.status, 0);
  EXPECT_HAS(r.err, "E: no rig.yaml");
  // A unit missing at one time: the file, the line and the column.
  fs::create_directories(tmp / "B");
  for (const char* f : {"imu.csv", "rig.yaml"}) fs::copy_file(tmp / "D" / f, tmp / "B" / f);
  std::string units = test::read_file(tmp / "D/units.csv");
  const std::size_t line5 = [&] { std::size_t p = 0; for (int i = 0; i < 4; ++i) p = units.find('\n', p) + 1; return p; }();
  units.erase(line5, units.find('\n', line5) + 1 - line5);  // drops unit 4 of the first reading
  test::write_file(tmp / "B/units.csv", units);
  r = polrig("navigate B -o N", cd());
  EXPECT_NE(r.status, 0);
  EXPECT_HAS(r.err, "units.csv:5: column 'unit': expected unit 4 next");
  // A DoP outside [0, 1]: the first reading's unit 1 (line 2), its fourth column.
  units = test::read_file(tmp / "D/units.csv");
  const std::size_t row = units.find('\n') + 1;
  std::size_t c = row;
  for (int i = 0; i < 3; ++i) c = units.find(',', c) + 1;
  units.replace(c, units.find(',', c) - c, "1.5");
  test::write_file(tmp / "B/units.csv", units);
  r = polrig("navigate B -o N", cd());
  EXPECT_HAS(r.err, "units.csv:2: column 'dop': expected a DoP in [0, 1], got 1.5");
  // imu.csv: a gap (a sample missing), a NaN, a rate beyond the gyro's range.
  const std::string imu = test::read_file(tmp / "D/imu.csv");
  const auto line_start = [&](const std::string& text, int line) {
    std::size_t p = 0;
    for (int i = 1; i < line; ++i) p = text.find('\n', p) + 1;
    return p;
  };
  for (const char* f : {"units.csv"}) fs::copy_file(tmp / "D" / f, tmp / "B" / f, fs::copy_options::overwrite_existing);
  std::string gap = imu;
  gap.erase(line_start(gap, 11), line_start(gap, 12) - line_start(gap, 11));  // drops the 10th sample
  test::write_file(tmp / "B/imu.csv", gap);
  r = polrig("navigate B -o N", cd());
  EXPECT_HAS(r.err, "imu.csv:11: column 't_s': time ");
  EXPECT_HAS(r.err, "expected one IMU period, 0.01 s (imu.rate_hz 100 Hz), within 10 %");
  std::string bad = imu;
  std::size_t p = line_start(bad, 3);
  p = bad.find(',', p) + 1;  // dtheta_x of the second sample
  bad.replace(p, bad.find(',', p) - p, "nan");
  test::write_file(tmp / "B/imu.csv", bad);
  r = polrig("navigate B -o N", cd());
  EXPECT_HAS(r.err, "imu.csv:3: column 'dtheta_x_rad': expected a finite number, got 'nan'");
  bad = imu;
  p = bad.find(',', line_start(bad, 3)) + 1;
  bad.replace(p, bad.find(',', p) - p, "0.5");
  test::write_file(tmp / "B/imu.csv", bad);
  r = polrig("navigate B -o N", cd());
  EXPECT_HAS(r.err, "imu.csv:3: column 'dtheta_x_rad': 0.5 rad over 0.01");
  EXPECT_HAS(r.err, "beyond a gyro's 2000°/s");
  EXPECT_FALSE(fs::exists(tmp / "N"));
  // Not a unit array's dataset.
  ok("simulate " + rig("wang2019-outdoor1.yaml") + " -o W --no-plots", cd());
  r = polrig("navigate W -o N", cd());
  EXPECT_NE(r.status, 0);
  EXPECT_HAS(r.err, "navigate needs a unit array");
  // calibrate --method unit-array, and navigate with its frames; a calibration of another layout refused.
  ok("calibrate D --method unit-array -o C --no-plots", cd());
  EXPECT_HAS(test::read_file(tmp / "C/calibration.yaml"), "units:\n  - unit: 1\n    error_deg: [");
  ok("navigate D --calibration C/calibration.yaml -o K --no-plots", cd());
  // The written file records the layout it was fitted for.
  const std::string good = test::read_file(tmp / "C/calibration.yaml");
  // Finding 16: 30 s of a static run fix fewer than three angles of a unit: said, with no
  // standard error (was exactly 0, termination "Running"), and not used.
  EXPECT_HAS(good, "    standard_error_deg: [null, null, null]\n");
  EXPECT_HAS(good, "    termination: RankDeficient\n    converged: false\n");
  EXPECT_LACKS(good, "Running");
  EXPECT_HAS(test::read_file(tmp / "C/installation.csv"), ",,,");
  EXPECT_HAS(good, "    nominal_axes_b: [[");
  // Hand-made calibrations of D's layout: unit 2 12° off (a converged unit must be within ±10°);
  // unit 1 not converged (keeps its nominal frame); a `converged` that says neither.
  const auto axes_line = [&](int unit) {
    const std::size_t at = good.find(fmt::format("  - unit: {}\n", unit));
    const std::size_t b = good.find("    nominal_axes_b:", at);
    return good.substr(b, good.find('\n', b) + 1 - b);
  };
  const auto hand_made = [&](const std::vector<int>& order, double unit2_error, const char* unit2_converged) {
    std::string cal = "units:\n";
    for (int u : order)
      cal += fmt::format("  - unit: {}\n    error_deg: [{}, 0, 0]\n    converged: {}\n", u, u == 2 ? unit2_error : 0.1,
                         u == 1 ? "false" : u == 2 ? unit2_converged : "true") + axes_line(u);
    return cal;
  };
  const std::vector<int> in_order{1, 2, 3, 4, 5, 6, 7, 8, 9};
  test::write_file(tmp / "C/bad.yaml", hand_made(in_order, 12, "true"));
  r = polrig("navigate D --calibration C/bad.yaml -o N", cd());
  EXPECT_HAS(r.err, "C/bad.yaml:7: key 'units[1].error_deg (unit 2)': expected a mounting error within ±10°, got 12");
  test::write_file(tmp / "C/bad.yaml", hand_made(in_order, 0.2, "maybe"));
  r = polrig("navigate D --calibration C/bad.yaml -o N", cd());
  EXPECT_HAS(r.err, "key 'units[1].converged (unit 2)': expected true or false");
  // The third review's finding 5: entries are taken by their unit number, so a file with its
  // entries swapped gives the same solution; a number out of range, repeated, or a unit fitted for
  // another layout is refused.
  test::write_file(tmp / "C/ordered.yaml", hand_made(in_order, 0.2, "true"));
  test::write_file(tmp / "C/swapped.yaml", hand_made({3, 2, 1, 4, 5, 6, 9, 8, 7}, 0.2, "true"));
  ok("navigate D --calibration C/ordered.yaml --mode integrated -o O1 --no-plots", cd());
  ok("navigate D --calibration C/swapped.yaml --mode integrated -o O2 --no-plots", cd());
  EXPECT_EQ(test::read_file(tmp / "O1/solution.csv"), test::read_file(tmp / "O2/solution.csv"));
  bad = hand_made(in_order, 0.2, "true");
  bad.replace(bad.find("unit: 1\n"), 8, "unit: 7\n");
  test::write_file(tmp / "C/bad.yaml", bad);
  r = polrig("navigate D --calibration C/bad.yaml -o N", cd());
  EXPECT_HAS(r.err, "C/bad.yaml:5: key 'units[0].nominal_axes_b (unit 7)': unit 7 was fitted for another layout");
  bad = hand_made(in_order, 0.2, "true");
  bad.replace(bad.find("  - unit: 7\n"), bad.find("  - unit: 8\n") - bad.find("  - unit: 7\n"),
              bad.substr(bad.find("  - unit: 6\n"), bad.find("  - unit: 7\n") - bad.find("  - unit: 6\n")));
  test::write_file(tmp / "C/bad.yaml", bad);
  r = polrig("navigate D --calibration C/bad.yaml -o N", cd());
  EXPECT_HAS(r.err, "C/bad.yaml:26: key 'units[6].unit': unit 6 is given twice (first as units[5])");
  bad = hand_made(in_order, 0.2, "true");
  bad.replace(bad.find("unit: 1\n"), 8, "unit: 10\n");
  test::write_file(tmp / "C/bad.yaml", bad);
  r = polrig("navigate D --calibration C/bad.yaml -o N", cd());
  EXPECT_HAS(r.err, "C/bad.yaml:2: key 'units[0].unit': expected a unit number 1 … 9 (the dataset's layout), got 10");
  ok("simulate " + rig("zhang2021-static.yaml") + " --set trajectory.duration_s=30 --set device.units.ring_tilt_deg=40 -o T", cd());
  r = polrig("navigate T --calibration C/calibration.yaml -o N", cd());
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "unit 2 was fitted for another layout: its nominal axes are 10° from the dataset's unit 2");
  // Finding 6: a key given twice, an unknown key at the top or in a unit.
  test::write_file(tmp / "C/bad.yaml", good + "units: []\n");
  r = polrig("navigate D --calibration C/bad.yaml -o N", cd());
  EXPECT_HAS(r.err, "key 'units': duplicate key (first at line 3)");
  test::write_file(tmp / "C/bad.yaml", good + "unit_count: 9\n");
  r = polrig("navigate D --calibration C/bad.yaml -o N", cd());
  EXPECT_HAS(r.err, "key 'unit_count': unknown key (expected units, elevation_error_deg)");
  bad = good;
  bad.insert(bad.find("    converged:"), "    offset_deg: 1\n");
  test::write_file(tmp / "C/bad.yaml", bad);
  r = polrig("navigate D --calibration C/bad.yaml -o N", cd());
  EXPECT_HAS(r.err, "key 'units[0].offset_deg': unknown key");
  // Findings 7 and 8: an empty name, a folder.
  r = polrig("navigate D --calibration '' -o N", cd());
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "--calibration '': expected a file name");
  r = polrig("navigate D --rig '' -o N", cd());
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "--rig '': expected a file name");
  r = polrig("navigate D --calibration C -o N", cd());
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "C: cannot read the calibration file: it is a directory (expected a file)");
  r = polrig("navigate D --mode best -o N", cd());
  EXPECT_EQ(r.status, 2);
  EXPECT_FALSE(fs::exists(tmp / "N"));
}

// The sun's azimuth as a heading measurement (navigation.measurement azimuth, ins/filter.h): a
// noise-free compass and a perfect IMU, the INS started 2° off in heading. The azimuth sees the
// heading (H's −1 on φ_U) and brings it back within 0.01° in 60 readings; the elevation cannot (φ_U
// is not in its H), and leaves the 2°. A wrong sign in the azimuth's tilt or heading columns
// drives the heading away instead.
// navigation.measurement pns-fix: the filter takes no sun update but one PNS fix per window of
// navigation.pns_window_s that does not overlap the last (four in 1200 s of 300-s windows, two
// scalar updates each), each fix the positioning fit of that window's readings alone (the PNS mode's
// own fit over the same readings, with the filter's position as its prior: the same root); a PNS
// levelled by the free SINS is refused (its errors would be the filter's own).
// A compass read at the IMU's own rate leaves one IMU sample a reading: no window for the rest
// detector, so navigation.zupt tests nothing and updates nothing (the review's finding: the detector
// refused the one-sample window and ended the run).
TEST(NavigationAiding, ZuptWithOneImuSampleAReadingTestsNothing) {
  const Rig rig = load("zhang2021-static.yaml", {{"navigation.zupt", "true"}, {"imu.rate_hz", "10"},
                                                 {"device.units.rate_hz", "10"}, {"trajectory.duration_s", "20"}});
  const NavigationDataset d = simulate_navigation(rig);
  NavigationOptions o;
  o.modes = {NavigationMode::Integrated};
  const NavigationRun run = navigate(d, rig, o);
  ASSERT_EQ(run.filter.size(), 200u);
  for (const FilterEpoch& f : run.filter) EXPECT_TRUE(std::isnan(f.rest_statistic));
  EXPECT_EQ(run.filter_summary.zero_velocity_updates, 0);
  EXPECT_EQ(run.filter_summary.updates, 200);
}

TEST(NavigationAiding, APnsFixPerWindowIsALooselyCoupledUpdate) {
  const Rig rig = load("zhang2021-static.yaml", {{"navigation.measurement", "pns-fix"}, {"navigation.adaptive", "false"}});
  const NavigationDataset d = simulate_navigation(rig);
  NavigationOptions o;
  o.modes = {NavigationMode::Pns, NavigationMode::Integrated};
  const NavigationRun run = navigate(d, rig, o);
  std::vector<std::size_t> fixes;
  for (std::size_t k = 0; k < run.filter.size(); ++k) {
    const FilterEpoch& f = run.filter[k];
    EXPECT_TRUE(std::isnan(f.update.nis) && std::isnan(f.azimuth_update.nis)) << k;
    if (std::isfinite(f.position_update.nis())) fixes.push_back(k);
  }
  ASSERT_EQ(fixes, (std::vector<std::size_t>{299, 599, 899, 1199}));
  EXPECT_EQ(run.filter_summary.updates, 8);
  EXPECT_TRUE(std::isnan(run.filter_summary.final_R));  // a whitened fix has no R of the sun's to report
  // The PNS mode's fix at the window's end is over the same readings: the same minimum from another
  // start, to the fit's tolerances along its flat direction (σ ~100 km across the sun): < 1 m.
  for (std::size_t k : fixes) {
    EXPECT_NEAR(run.filter[k].pns_fix_lat_rad, run.fixes[0][k].lat_rad, 1.5e-7) << k;
    EXPECT_NEAR(run.filter[k].pns_fix_lon_rad, run.fixes[0][k].lon_rad, 1.5e-7) << k;
  }
  EXPECT_HAS(rig_error("zhang2021-static.yaml", {{"navigation.measurement", "pns-fix"}, {"navigation.pns_level", "sins"}}),
             "key 'navigation.pns_level': expected accelerometer with navigation.measurement pns-fix");
}

TEST(NavigationAiding, TheSunsAzimuthFixesTheHeadingTheElevationCannot) {
  std::vector<RigOverride> o = ideal(60);
  o.push_back({"navigation.initial_attitude_error_deg", "[0, 0, 2]"});
  o.push_back({"navigation.adaptive", "false"});
  const NavigationDataset d = simulate_navigation(load("zhang2021-static.yaml", o));
  const double true_yaw = rad2deg(euler_from_C_bn(d.truth->trajectory.back().C_bn).yaw_rad);
  for (const char* m : {"azimuth", "sun-vector", "elevation"}) {
    std::vector<RigOverride> with = o;
    with.push_back({"navigation.measurement", m});
    NavigationOptions integrated;
    integrated.modes = {NavigationMode::Integrated};
    const NavigationRun run = navigate(d, load("zhang2021-static.yaml", with), integrated);
    const double miss = std::remainder(rad2deg(run.fixes[0].back().attitude.yaw_rad) - true_yaw, 360.0);
    std::printf("%s: heading error after 60 s %.4f° (σ %.4f°)\n", m, miss, rad2deg(run.filter.back().sigma_heading_rad));
    if (std::string(m) == "elevation") {
      EXPECT_NEAR(miss, 2.0, 0.05);
    } else {
      EXPECT_LT(std::abs(miss), 0.01) << m;
      EXPECT_TRUE(std::isfinite(run.filter.back().azimuth_update.nis)) << m;
    }
  }
}
