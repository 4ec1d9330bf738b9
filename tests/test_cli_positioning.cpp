// polrig study positioning, run through the executable on rigs/wang2016-static.yaml (W16's
// static hour at 1 Hz, levelled).
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "support.h"

namespace fs = std::filesystem;
using namespace polrig::test;

namespace {

class CliPositioning : public PolrigTest {
 protected:
  CliPositioning() : PolrigTest("polrig_test_cli_positioning_", "") {}
};

const std::string kRig = POLRIG_SOURCE_DIR "/rigs/wang2016-static.yaml";  // the study reads its sky and times

}  // namespace

// Bit-identical for any thread count; the cells of the three sweeps; a noise-free cell recovers
// the site to metres; the white-noise error scales with σ (the same noise in every cell).
TEST_F(CliPositioning, StudyIsDeterministicAndScalesWithNoise) {
  const std::string common = "study positioning " + shell_quote(kRig) +
                             " --trials 12 --windows 600,3600 --noise 0,0.07,0.14 --tilts 0,0.1";
  const Result first = ok(common + " --threads 1 -o " + shell_quote(tmp / "a"));
  // The stdout line names Eq. 15's azimuth span and W16's mirror root M′.
  EXPECT_HAS(first.out, "Eq. 15 over Δβ = 14.54°: 87.8 km");
  EXPECT_HAS(first.out, "fixes nearer it");
  ok(common + " --threads 2 --no-plots -o " + shell_quote(tmp / "b"));
  for (const char* f : {"summary.csv", "trials.csv"})
    EXPECT_EQ(read_file(tmp / "a" / f), read_file(tmp / "b" / f)) << f;
  for (const char* png : {"error_vs_window.png", "error_vs_noise.png", "error_vs_tilt.png", "fixes.png"})
    EXPECT_TRUE(starts_with_png_signature(tmp / "a" / png)) << png;
  EXPECT_FALSE(fs::exists(tmp / "b" / "fixes.png"));
  const Csv s = read_csv(tmp / "a" / "summary.csv");
  ASSERT_EQ(s.rows.size(), 2u + 3u + 2u);
  const auto at = [&](std::size_t row, const char* col) { return std::stod(s.rows[row][s.col(col)]); };
  EXPECT_EQ(s.rows[0][s.col("factor")], "window");
  EXPECT_EQ(s.rows[2][s.col("factor")], "noise");
  EXPECT_EQ(s.rows[5][s.col("factor")], "tilt");
  EXPECT_EQ(at(1, "sightings"), 3601);
  EXPECT_EQ(at(0, "sightings"), 601);
  EXPECT_LT(at(2, "max_km"), 1e-3);  // σ = 0: metres
  // σ = 0.07° against 0.14°: the same normal deviates, a near-linear fit: half the error.
  EXPECT_NEAR(at(3, "rms_km") / at(4, "rms_km"), 0.5, 0.01);
  // Eq. 15 over the hour's Δβ = 14.54°: 0.14·√2/sin Δβ·111.32 = 87.8 km.
  EXPECT_NEAR(at(4, "eq15_km"), 87.77, 0.01);
  EXPECT_NEAR(at(4, "delta_beta_deg"), 14.54, 0.01);
  // M′ (the equal-altitude circles' other intersection) is far on the other side of the sun's track,
  // and no trial's fix ended nearer it (tests/test_positioning.cpp checks M′ against the geometry).
  EXPECT_GT(at(4, "mirror_km"), 5000);
  for (std::size_t row = 0; row < s.rows.size(); ++row) EXPECT_EQ(at(row, "wrong_root"), 0) << row;
  // A shorter window: a larger error.
  EXPECT_GT(at(0, "rms_km"), 3 * at(1, "rms_km"));
  const Csv t = read_csv(tmp / "a" / "trials.csv");
  EXPECT_EQ(t.rows.size(), 7u * 12u);
  EXPECT_HAS(read_file(tmp / "a" / "manifest.yaml"), "summary.csv");
}

TEST_F(CliPositioning, BadInputWritesNothing) {
  const std::string base = "study positioning " + shell_quote(kRig) + " --trials 2 --no-plots ";
  Result r = polrig(base + "--windows 7200 -o " + shell_quote(tmp / "w"));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "--windows");
  EXPECT_HAS(r.err, "7200");
  r = polrig(base + "--noise 0.1,x -o " + shell_quote(tmp / "n"));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "--noise");
  r = polrig(base + "--tilts 11 -o " + shell_quote(tmp / "t"));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "--tilts");
  // A rig without a sky.
  r = polrig("study positioning " + shell_quote(kDefaultRigFile) + " -o " + shell_quote(tmp / "s"));
  EXPECT_NE(r.status, 0);
  EXPECT_HAS(r.err, "sky");
  for (const char* d : {"w", "n", "t", "s"}) EXPECT_FALSE(fs::exists(tmp / d)) << d;
  ok(base + "--windows 600 --noise 0.1 --tilts 0 -o " + shell_quote(tmp / "o"));
  r = polrig(base + "--windows 600 --noise 0.1 --tilts 0 -o " + shell_quote(tmp / "o"));
  EXPECT_NE(r.status, 0);
  EXPECT_HAS(r.err, "--force");
}

// `polrig locate` on a small noise-free four-camera dataset (W16's static hour, 13 stops 5 min
// apart, the quarter-resolution sensor of docs/cli.md). The chain is simulate → fused AoP →
// eigenvector sun → Eq. 17 fix → ψ = β − α_S. Its only error is the fused image's interpolation:
// each stop's sun must be within that of the true sun of stops.csv, and the fix within Eq. 15's
// two-sighting error for the largest zenith-angle error seen, ε√2/sin Δβ (the first and last stop
// span Δβ ≈ 14.5°; the least-squares fix over 13 stops is no worse than its two ends alone).
TEST_F(CliPositioning, LocateFromAFourCameraDatasetFindsTheSiteAndHeading) {
  const std::string quarter =
      " --set schedule.step_deg=0 --set schedule.count=13 --set schedule.dwell_s=300"
      " --set device.cameras.noise=false --set device.cameras.width_px=258 --set device.cameras.height_px=194"
      " --set 'device.cameras.fx_px=[192.5, 192.8, 192.225, 192.65]'"
      " --set 'device.cameras.fy_px=[192.5, 192.8, 192.225, 192.65]'"
      " --set 'device.cameras.cx_px=[129, 129.6, 128.925, 129.475]'"
      " --set 'device.cameras.cy_px=[97, 96.95, 97.575, 97.15]'";
  const fs::path data = tmp / "w16", out = tmp / "loc";
  ok("simulate " + shell_quote(std::string(POLRIG_SOURCE_DIR "/rigs/wang2016-static.yaml")) + " --layers aop --no-plots" + quarter +
     " -o " + shell_quote(data));
  ok("locate " + shell_quote(data) + " --prior 29,113.5 -o " + shell_quote(out));
  // The stops run side by side: the same files from one thread.
  ok("locate " + shell_quote(data) + " --prior 29,113.5 --threads 1 -o " + shell_quote(tmp / "loc1"));
  for (const char* f : {"sun.csv", "fix.csv", "heading.csv", "map.csv"})
    EXPECT_EQ(read_file(out / f), read_file(tmp / "loc1" / f)) << f;
  const Csv stops = read_csv(data / "stops.csv"), sun = read_csv(out / "sun.csv");
  const Csv fix = read_csv(out / "fix.csv"), heading = read_csv(out / "heading.csv");
  ASSERT_EQ(sun.rows.size(), 13u);
  ASSERT_EQ(heading.rows.size(), 13u);
  const double deg = 180.0 / std::acos(-1.0);
  double worst_zenith = 0;
  for (std::size_t i = 0; i < 13; ++i) {
    const auto st = [&](const char* c) { return std::stod(stops.rows[i][stops.col(c)]); };
    const auto sn = [&](const char* c) { return std::stod(sun.rows[i][sun.col(c)]); };
    EXPECT_EQ(sun.rows[i][sun.col("status")], "ok");
    const double az = std::atan2(st("sun_y_cam1"), st("sun_x_cam1")) * deg;
    const double el = std::asin(st("sun_z_cam1")) * deg;
    // The fused image's AoP is within 5.4e-4° of the sky's at this resolution (test_four_camera).
    EXPECT_NEAR(std::remainder(sn("sun_az_deg") - az, 360.0), 0.0, 2e-3) << i;
    EXPECT_NEAR(sn("sun_el_deg"), el, 2e-3) << i;
    worst_zenith = std::max(worst_zenith, std::abs(sn("sun_el_deg") - el));
    EXPECT_NEAR(std::remainder(std::stod(heading.rows[i][heading.col("heading_error_deg")]), 360.0), 0.0, 2e-3) << i;
  }
  ASSERT_EQ(fix.rows[0][fix.col("root")], "chosen");
  EXPECT_EQ(fix.rows[0][fix.col("termination")], "converged");
  const double eq15_km = worst_zenith * std::sqrt(2.0) / std::sin(14.5 / deg) * 111.32;
  EXPECT_LT(std::stod(fix.rows[0][fix.col("error_km")]), eq15_km);
  EXPECT_LT(eq15_km, 1.0);  // the bound itself is tight: the fix is good to better than a km
  // The mirror root lies in the southern hemisphere, far from the prior.
  ASSERT_EQ(fix.rows.size(), 2u);
  EXPECT_LT(std::stod(fix.rows[1][fix.col("lat_deg")]), -40.0);
  EXPECT_HAS(read_file(out / "manifest.yaml"), "sun.csv");

  // The plots (issue 23 §4): fix.png, the fix, the truth and each stop's line of position from
  // map.csv; heading.png, heading.csv's headings against time. gnuplot's own table of each plot
  // gives the columns read by name (6 significant digits).
  for (const char* f : {"map.csv", "fix.png", "heading.png", "plots.gp"})
    EXPECT_HAS(read_file(out / "manifest.yaml"), fmt::format("  {}:", f));
  const Csv map = read_csv(out / "map.csv");
  const auto cell = [](const Csv& c, std::size_t row, const char* name) { return std::stod(c.rows[row][c.col(name)]); };
  ASSERT_EQ(map.rows.size(), 2u + 13u);
  EXPECT_EQ(map.rows[0][map.col("mark")], "fix");
  EXPECT_EQ(map.rows[0][map.col("lat_deg")], fix.rows[0][fix.col("lat_deg")]);
  EXPECT_EQ(map.rows[0][map.col("lon_deg")], fix.rows[0][fix.col("lon_deg")]);
  EXPECT_EQ(map.rows[1][map.col("mark")], "truth");
  EXPECT_EQ(cell(map, 1, "lat_deg"), 28.221);
  EXPECT_EQ(cell(map, 1, "lon_deg"), 112.992);
  // Each stop's line of position passes `residual_deg` of arc from the fix away from the sun's
  // azimuth β, perpendicular to β (the intercept method), at equal ground scale at the truth.
  const double fix_lat = cell(fix, 0, "lat_deg"), fix_lon = cell(fix, 0, "lon_deg"), c = std::cos(28.221 / deg);
  for (std::size_t k = 0; k < 13; ++k) {
    EXPECT_EQ(map.rows[2 + k][map.col("mark")], "line");
    EXPECT_EQ(map.rows[2 + k][map.col("utc")], heading.rows[k][heading.col("utc")]);
    const double r = cell(heading, k, "residual_deg"), b = cell(heading, k, "beta_deg") / deg;
    EXPECT_NEAR(cell(map, 2 + k, "lat_deg"), fix_lat - r * std::cos(b), 1e-12) << k;
    EXPECT_NEAR(cell(map, 2 + k, "lon_deg"), fix_lon - r * std::sin(b) / c, 1e-12) << k;
    EXPECT_NEAR(cell(map, 2 + k, "dlat_deg") * std::cos(b) + cell(map, 2 + k, "dlon_deg") * c * std::sin(b), 0.0, 1e-12);
  }
  const auto plots = tabulate_script(out, "plots.gp");
  ASSERT_EQ(plots.size(), 2u);
  const auto finite_rows = [&](const std::string& png, const std::string& title) {
    std::vector<std::vector<double>> rows;
    for (const auto& [name, curves] : plots)
      for (const auto& [t, r] : curves)
        if (name == png && t == title)
          for (const auto& row : r)
            if (!row.empty() && std::isfinite(row[0])) rows.push_back(row);
    return rows;
  };
  const auto near = [](double a, double b) { return std::abs(a - b) <= 1e-5 * std::abs(b); };
  const auto fix_point = finite_rows("fix.png", "fix");
  ASSERT_EQ(fix_point.size(), 1u);
  EXPECT_TRUE(near(fix_point[0][0], fix_lon) && near(fix_point[0][1], fix_lat)) << fix_point[0][0] << " " << fix_point[0][1];
  const auto truth_point = finite_rows("fix.png", "truth");
  ASSERT_EQ(truth_point.size(), 1u);
  EXPECT_TRUE(near(truth_point[0][0], 112.992) && near(truth_point[0][1], 28.221));
  const auto lines = finite_rows("fix.png", "each stop's line of position");
  ASSERT_EQ(lines.size(), 13u);
  for (std::size_t k = 0; k < 13; ++k) {  // from one end by twice the half line (6 digits of each): centred on the point
    ASSERT_EQ(lines[k].size(), 4u);
    EXPECT_NEAR(lines[k][0] + 0.5 * lines[k][2], cell(map, 2 + k, "lon_deg"), 1.2e-3) << k;
    EXPECT_NEAR(lines[k][1] + 0.5 * lines[k][3], cell(map, 2 + k, "lat_deg"), 1.2e-3) << k;
  }
  // heading.png's x is the time (a string in the table): its y values, stop by stop.
  for (const auto& [title, column] : {std::pair{"heading", "heading_deg"}, {"true heading", "heading_true_deg"}}) {
    std::vector<std::vector<double>> rows;
    for (const auto& [name, curves] : plots)
      for (const auto& [t, r] : curves)
        if (name == "heading.png" && t == title) rows = r;
    ASSERT_EQ(rows.size(), 13u) << title;
    for (std::size_t k = 0; k < 13; ++k) EXPECT_TRUE(near(rows[k].at(0), cell(heading, k, column))) << title << " " << k;
  }
}

TEST_F(CliPositioning, LocateRefusesWhatItCannotUse) {
  Result r = polrig("locate " + shell_quote(tmp / "none") + " -o " + shell_quote(tmp / "x"));
  EXPECT_EQ(r.status, 2);  // a usage error (docs/cli.md exit codes)
  EXPECT_HAS(r.err, "--prior");
  // Two unreadable stops, next to each other (both in flight at 2 threads): the first in stop
  // order is named, whichever thread met it, and nothing is written.
  const fs::path w16 = tmp / "w16";
  ok("simulate " + shell_quote(std::string(POLRIG_SOURCE_DIR "/rigs/wang2016-static.yaml")) +
     " --no-plots --set schedule.count=12 --set device.cameras.width_px=64 --set device.cameras.height_px=48"
     " --set 'device.cameras.fx_px=[48, 48, 48, 48]' --set 'device.cameras.fy_px=[48, 48, 48, 48]'"
     " --set 'device.cameras.cx_px=[32, 32, 32, 32]' --set 'device.cameras.cy_px=[24, 24, 24, 24]' -o " +
     shell_quote(w16));
  for (const char* stop : {"stop_0003.exr", "stop_0004.exr"}) write_file(w16 / "frames" / stop, "not an EXR");
  for (int run = 0; run < 3; ++run) {
    r = polrig("locate " + shell_quote(w16) + " --prior 28,113 --threads 2 -o " + shell_quote(tmp / "z"));
    EXPECT_EQ(r.status, 2) << r.err;  // a camera dataset's file (docs/cli.md "Exit status")
    EXPECT_HAS(r.err, "stop_0003.exr");
    EXPECT_FALSE(fs::exists(tmp / "z"));
  }
  // A DoFP camera's dataset has no camera array.
  const fs::path dofp = tmp / "dofp";
  ok("simulate " + shell_quote(std::string(POLRIG_SOURCE_DIR "/rigs/han2017-outdoor.yaml")) +
     " --set device.width_px=32 --set device.height_px=24 --set schedule.step_deg=180 -o " + shell_quote(dofp));
  r = polrig("locate " + shell_quote(dofp) + " --prior 28,113 -o " + shell_quote(tmp / "y"));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "locate needs");
  EXPECT_FALSE(fs::exists(tmp / "y"));
}
