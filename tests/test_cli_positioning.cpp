// polrig study positioning, run through the executable on tests/position-static.yaml (W16's
// static hour at 1 Hz, levelled).
#include <cmath>
#include <string>

#include "support.h"

namespace fs = std::filesystem;
using namespace polrig::test;

namespace {

class CliPositioning : public PolrigTest {
 protected:
  CliPositioning() : PolrigTest("polrig_test_cli_positioning_", "") {}
};

const std::string kRig = POLRIG_SOURCE_DIR "/tests/position-static.yaml";

}  // namespace

// Bit-identical for any thread count; the cells of the three sweeps; a noise-free cell recovers
// the site to metres; the white-noise error scales with σ (the same noise in every cell).
TEST_F(CliPositioning, StudyIsDeterministicAndScalesWithNoise) {
  const std::string common = "study positioning " + shell_quote(kRig) +
                             " --trials 12 --windows 600,3600 --noise 0,0.07,0.14 --tilts 0,0.1";
  ok(common + " --threads 1 -o " + shell_quote(tmp / "a"));
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
