// polrig heading and polrig study heading, run through the executable.
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "polrig/sky/sun.h"
#include "support.h"

namespace fs = std::filesystem;
using namespace polrig::test;

namespace {

class CliNav : public PolrigTest {
 protected:
  CliNav() : PolrigTest("polrig_test_cli_nav_", "") {}
};

double rad(double d) { return d * std::numbers::pi / 180.0; }

// θ_b of a sensor looking along Z_b (spec §1.5 frames; Eigen, independent of compass/).
double theta_b(double H, double roll, double pitch, const Eigen::Vector3d& s) {
  using Eigen::AngleAxisd;
  using Eigen::Vector3d;
  const Eigen::Matrix3d C = (AngleAxisd(-rad(H), Vector3d::UnitZ()) * AngleAxisd(rad(pitch), Vector3d::UnitX()) *
                             AngleAxisd(rad(roll), Vector3d::UnitY())).toRotationMatrix();
  const Vector3d e_b = C.transpose() * s.cross(C.col(2)).normalized();
  return std::atan2(e_b.y(), e_b.x()) * 180.0 / std::numbers::pi;
}

}  // namespace

TEST_F(CliNav, HeadingRecoversTheTruthAndWritesEveryRow) {
  const polrig::Site dalian;  // W19's roof
  struct Row { const char* utc; double H, roll, pitch; };
  const Row rows[] = {{"2019-07-01T11:01:00Z", 250.0, 3.0, -4.0},   // W19's dynamic run, h_s 2.9°
                      {"2019-07-01T06:00:00Z", 10.0, -7.0, 2.0},
                      {"2019-07-01T16:00:00Z", 123.0, 1.0, 1.0}};   // sun below the horizon
  std::string text = "utc,roll_deg,pitch_deg,aop_deg,heading_prior_deg,note\n";
  for (const Row& r : rows) {
    const polrig::SunPosition sun = polrig::sun_position(polrig::parse_utc(r.utc), dalian);
    const polrig::Vec3 s = polrig::sun_direction_enu(sun);
    text += fmt::format("{},{},{},{},{},kept\n", r.utc, r.roll, r.pitch,
                        theta_b(r.H, r.roll, r.pitch, {s[0], s[1], s[2]}), r.H + 3.0);
  }
  // The sun 0.6° from the zenith (Tropic of Cancer at local noon): no solution, row still written.
  text += "2019-07-01T04:00:00Z,0,0,30,,kept\n";
  write_file(tmp / "in.csv", text);
  const fs::path out = tmp / "h";
  ok("heading " + shell_quote(tmp / "in.csv") + " --site 38.879167,121.543889 -o " + shell_quote(out));
  const Csv csv = read_csv(out / "heading.csv");
  ASSERT_EQ(csv.rows.size(), 4u);
  for (std::size_t k = 0; k < 3; ++k) {
    SCOPED_TRACE(k);
    EXPECT_EQ(csv.rows[k][csv.col("status")], "ok");
    EXPECT_EQ(csv.rows[k][csv.col("note")], "kept");
    const double H = std::stod(csv.rows[k][csv.col("heading_deg")]);
    EXPECT_NEAR(std::remainder(H - rows[k].H, 360.0), 0.0, 1e-9);
  }
  EXPECT_LT(std::stod(csv.rows[2][csv.col("sun_el_deg")]), 0.0);
  EXPECT_TRUE(fs::exists(out / "manifest.yaml"));

  // lat_deg/lon_deg columns instead of --site.
  write_file(tmp / "tropic.csv", "utc,lat_deg,lon_deg,roll_deg,pitch_deg,aop_deg\n"
                                 "2019-07-01T04:00:00Z,23.44,121.5,0,0,30\n");
  ok("heading " + shell_quote(tmp / "tropic.csv") + " -o " + shell_quote(tmp / "t"));
  const Csv t = read_csv(tmp / "t" / "heading.csv");
  ASSERT_EQ(t.rows.size(), 1u);
  ASSERT_EQ(t.rows[0].size(), t.header.size());
  EXPECT_EQ(t.rows[0][t.col("status")], "sun-near-zenith-or-vertical-e");
  EXPECT_EQ(t.rows[0][t.col("heading_deg")], "nan");
  EXPECT_EQ(t.rows[0][t.col("heading_alt_deg")], "nan");

  // --ut1-minus-utc and --refraction reach the sun: the same place as sky/sun gives with them.
  ok("heading " + shell_quote(tmp / "in.csv") + " --site 38.879167,121.543889 --ut1-minus-utc 0.5 "
     "--refraction -o " + shell_quote(tmp / "u"));
  const Csv u = read_csv(tmp / "u" / "heading.csv");
  polrig::SunSettings settings;
  settings.ut1_minus_utc_s = 0.5;
  settings.refraction = true;
  for (std::size_t k = 0; k < 3; ++k) {
    const polrig::SunPosition sun = polrig::sun_position(polrig::parse_utc(rows[k].utc), dalian, settings);
    EXPECT_EQ(std::stod(u.rows[k][u.col("sun_az_deg")]), sun.azimuth_deg);
    EXPECT_EQ(std::stod(u.rows[k][u.col("sun_el_deg")]), sun.elevation_deg);
    // 0.5 s of UT1 turns the sky by 0.0021° of hour angle: the azimuth moves.
    EXPECT_NE(u.rows[k][u.col("sun_az_deg")], csv.rows[k][csv.col("sun_az_deg")]);
  }
}

TEST_F(CliNav, HeadingRefusesBadRowsAndWritesNothing) {
  const std::string good = "utc,roll_deg,pitch_deg,aop_deg\n2019-07-01T11:01:00Z,0,0,30\n";
  const struct { std::string row, message; } cases[] = {
      {"2019-07-01T11:01:00,0,0,30", "bad.csv:3: column 'utc': '2019-07-01T11:01:00'"},
      {"2019-07-01T11:01:00Z,0,95,30", "bad.csv:3: column 'pitch_deg': 95 is outside"},
      {"2019-07-01T11:01:00Z,x,0,30", "bad.csv:3: column 'roll_deg': expected a finite number, got 'x'"},
      {"2019-07-01T11:01:00Z,0,0,inf", "bad.csv:3: column 'aop_deg': expected a finite number, got 'inf'"},
  };
  for (const auto& c : cases) {
    write_file(tmp / "bad.csv", good + c.row + "\n");
    const Result r = polrig("heading " + shell_quote(tmp / "bad.csv") + " --site 38,121 -o " +
                            shell_quote(tmp / "o"));
    EXPECT_EQ(r.status, 2);
    EXPECT_HAS(r.err, c.message);
    EXPECT_FALSE(fs::exists(tmp / "o"));
  }
  write_file(tmp / "nocol.csv", "utc,roll_deg,aop_deg\n2019-07-01T11:01:00Z,0,30\n");
  EXPECT_HAS(polrig("heading " + shell_quote(tmp / "nocol.csv") + " --site 38,121 -o " + shell_quote(tmp / "o")).err,
             "nocol.csv:1: missing column 'pitch_deg' (see docs/formats.md, \"6.13 polrig heading\")");
  write_file(tmp / "in.csv", good);
  EXPECT_HAS(polrig("heading " + shell_quote(tmp / "in.csv") + " -o " + shell_quote(tmp / "o")).err,
             "no site");
  EXPECT_HAS(polrig("heading " + shell_quote(tmp / "in.csv") + " --site 38,200 -o " + shell_quote(tmp / "o")).err,
             "--site '38,200': longitude 200 is outside [-180, 180]");
  EXPECT_FALSE(fs::exists(tmp / "o"));
  ok("heading " + shell_quote(tmp / "in.csv") + " --site 38,121 -o " + shell_quote(tmp / "o"));
  EXPECT_NE(polrig("heading " + shell_quote(tmp / "in.csv") + " --site 38,121 -o " + shell_quote(tmp / "o")).status, 0);
}

// The Monte-Carlo: bit-identical for any thread count; the sync error alone is ω·Δt exactly
// (a pure turn about the vertical moves the heading, nothing else).
TEST_F(CliNav, StudyHeadingIsDeterministicAndSyncErrorIsTurnTimesOffset) {
  const std::string common = "study heading " + shell_quote(kDefaultRigFile) + " --trials 300 --no-plots";
  ok(common + " --threads 1 -o " + shell_quote(tmp / "a"));
  ok(common + " --threads 2 -o " + shell_quote(tmp / "b"));
  for (const char* f : {"trials.csv", "summary.csv", "cdf.csv"})
    EXPECT_EQ(read_file(tmp / "a" / f), read_file(tmp / "b" / f)) << f;
  const Csv csv = read_csv(tmp / "a" / "trials.csv");
  ASSERT_EQ(csv.rows.size(), 300u);
  for (const auto& row : csv.rows) {
    ASSERT_EQ(row[csv.col("status")], "ok");
    const double expected = std::stod(row[csv.col("turn_rate_dps")]) * std::stod(row[csv.col("sync_s")]);
    EXPECT_NEAR(std::stod(row[csv.col("error_sync_deg")]), expected, 1e-9);
  }
  EXPECT_HAS(polrig("study heading " + shell_quote(kDefaultRigFile) +
                    " --utc 2019-07-01T11:01:00 -o " + shell_quote(tmp / "c")).err, "--utc");
  // The sun's settings, as for heading and sky: UT1 − UTC within [−1, 1] s.
  ok("study heading " + shell_quote(kDefaultRigFile) + " --trials 20 --no-plots --refraction "
     "--ut1-minus-utc -0.3 -o " + shell_quote(tmp / "d"));
  EXPECT_EQ(polrig("study heading " + shell_quote(kDefaultRigFile) + " --trials 20 --no-plots "
                   "--ut1-minus-utc 2 -o " + shell_quote(tmp / "e")).status, 2);
  // No sky in the rig: W19's dynamic run, Dalian 2019-07-01 19:01 Beijing (spec §1.1: h_s = 2.9°,
  // A_s = 297.6°).
  const std::string d = read_file(tmp / "d" / "sun.yaml");
  EXPECT_HAS(d, "utc: 2019-07-01T11:01:00Z");
  EXPECT_HAS(d, "azimuth_deg: 297.6");
  // A sky rig's block gives the site and the time (Outdoor1's first stop: spec §1.1's Dalian sun
  // at h_s = 4.42°); --utc overrides it.
  const std::string outdoor = POLRIG_SOURCE_DIR "/rigs/wang2019-outdoor1.yaml";
  ok("study heading " + shell_quote(outdoor) + " --trials 20 --no-plots -o " + shell_quote(tmp / "f"));
  const std::string f = read_file(tmp / "f" / "sun.yaml");
  EXPECT_HAS(f, "utc: 2018-11-16T08:09:40Z");
  EXPECT_HAS(f, "elevation_deg: 4.41");
  ok("study heading " + shell_quote(outdoor) + " --trials 20 --no-plots --utc 2018-11-16T08:11:28Z -o " +
     shell_quote(tmp / "g"));
  EXPECT_HAS(read_file(tmp / "g" / "sun.yaml"), "elevation_deg: 4.1");
}
