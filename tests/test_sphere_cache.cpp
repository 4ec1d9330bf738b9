// The sphere cache (issue 23 §4): its key, its files, and the CLI taking a solved sphere from it
// with the same outputs, bit for bit. Every cache here lives in a temporary folder: the user's
// ~/.cache is never touched (tests/CMakeLists.txt sets POLRIG_CACHE_DIR=off for all tests).
#include <gtest/gtest.h>

#include <bit>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "polrig/io/scene_yaml.h"
#include "polrig/io/sphere_cache.h"
#include "polrig/source/sphere_cache.h"
#include "polrig/source/sphere_tracer.h"
#include "polrig/source/traced_source.h"
#include "support.h"

namespace polrig {
namespace {

namespace fs = std::filesystem;

// A small JF-500-like scene: a lamp behind a baffle, few photons.
const std::string kScene =
    "# a small sphere for the cache tests\n"
    "sphere: {diameter: 500, reflectance: 0.98}\n"
    "port: {diameter: 100, polarizer: {axis_deg: 0, tau_M: 0.62, tau_m: 0.18}}\n"
    "lamps:\n  - {position: [0, 150, 100], radius: 10, power: 100, reflectance: 0}\n"
    "baffles:\n  - {centre: [0, 130.05, 54.13], normal: [0, 0.399, 0.917], radius: 25, reflectance: 0.98}\n"
    "trace: {photons: 20000, plane_samples: 64, field_step_deg: 6}\n";

SceneSpec small_scene() { return parse_scene(kScene, "scene.yaml"); }

// The small scene solved once, shared by the tests.
const SphereSolution& small_solution() {
  static const SphereSolution s = SphereTracer(small_scene()).solve();
  return s;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}
bool same_bits(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }

void expect_same_solution(const SphereSolution& a, const SphereSolution& b) {
  EXPECT_EQ(a.wall.n_theta, b.wall.n_theta);
  EXPECT_EQ(a.wall.n_phi, b.wall.n_phi);
  EXPECT_TRUE(same_bits(a.wall.E, b.wall.E));
  EXPECT_TRUE(same_bits(a.wall.E_se, b.wall.E_se));
  EXPECT_TRUE(same_bits(a.wall.E_first, b.wall.E_first));
  EXPECT_TRUE(same_bits(a.wall.E_first_se, b.wall.E_first_se));
  EXPECT_TRUE(same_bits(a.wall.wall_area_mm2, b.wall.wall_area_mm2));
  EXPECT_TRUE(same_bits(a.field.C, b.field.C));
  EXPECT_EQ(a.field.n_theta, b.field.n_theta);
  EXPECT_EQ(a.field.n_phi, b.field.n_phi);
  EXPECT_TRUE(same_bits(a.field.delta, b.field.delta));
  EXPECT_TRUE(same_bits(a.field.R, b.field.R));
  ASSERT_EQ(a.baffle_E.size(), b.baffle_E.size());
  for (std::size_t i = 0; i < a.baffle_E.size(); ++i)
    EXPECT_TRUE(same_bits(a.baffle_E[i][0], b.baffle_E[i][0]) && same_bits(a.baffle_E[i][1], b.baffle_E[i][1]));
  EXPECT_EQ(a.ledger.launched, b.ledger.launched);
  EXPECT_EQ(a.ledger.absorbed_wall, b.ledger.absorbed_wall);
  EXPECT_EQ(a.ledger.absorbed_baffles, b.ledger.absorbed_baffles);
  EXPECT_EQ(a.ledger.absorbed_lamps, b.ledger.absorbed_lamps);
  EXPECT_EQ(a.ledger.escaped, b.ledger.escaped);
  EXPECT_EQ(a.ledger.leaked, b.ledger.leaked);
  EXPECT_EQ(a.ledger.rays, b.ledger.rays);
  EXPECT_TRUE(same_bits(a.batch_indirect_W, b.batch_indirect_W));
  EXPECT_TRUE(same_bits(a.power_W, b.power_W));
  EXPECT_TRUE(same_bits(a.seconds, b.seconds));
}

// A cache in a temporary folder that keeps its warnings; installed for the test's lifetime.
struct TestCache {
  test::TempDir dir{"polrig_test_sphere_cache_"};
  std::vector<std::string> warnings;
  std::shared_ptr<SphereCacheFolder> cache = std::make_shared<SphereCacheFolder>(
      dir.path() / "spheres", true, [this](const std::string& w) { warnings.push_back(w); });
  TestCache() { install_sphere_cache(cache); }
  ~TestCache() { install_sphere_cache(nullptr); }
};

TEST(SphereCache, RoundTripIsBitExact) {
  const SceneSpec scene = small_scene();
  const std::string bytes = encode_sphere_cache_file(scene, small_solution());
  expect_same_solution(decode_sphere_cache_file(bytes, scene), small_solution());

  TestCache t;
  const std::string file = t.cache->store(scene, small_solution());
  EXPECT_EQ(file, t.cache->file_for(scene));
  EXPECT_EQ(test::read_file(file), bytes);
  const std::unique_ptr<SphereSolution> loaded = t.cache->load(scene);
  ASSERT_TRUE(loaded);
  expect_same_solution(*loaded, small_solution());
  EXPECT_TRUE(t.warnings.empty());
  // No temporary file is left beside it.
  EXPECT_EQ(test::entries_where(t.dir.path() / "spheres", [](const std::string&) { return true; }).size(), 1u);
}

TEST(SphereCache, KeyFollowsEveryValueButNotTheFileLayout) {
  const std::string key = sphere_cache_key(small_scene());
  EXPECT_EQ(key.size(), 16u);
  // Comments, blank lines, flow or block style and a value's spelling do not change the key.
  const std::string relaid =
      "sphere:\n  diameter: 500.0   # mm\n  reflectance: 9.8e-1\n\n"
      "port: {diameter: 100, polarizer: {axis_deg: 0, tau_M: 0.62, tau_m: 0.18}}\n"
      "lamps: [{position: [0, 150, 100], radius: 10, power: 100, reflectance: 0}]\n"
      "baffles:\n  - {centre: [0, 130.05, 54.13], normal: [0, 0.399, 0.917], radius: 25, reflectance: 0.98}\n"
      "trace:\n  photons: 20000\n  plane_samples: 64\n  field_step_deg: 6.0\n";
  EXPECT_EQ(sphere_cache_key(parse_scene(relaid, "relaid.yaml")), key);
  // Any value does, trace settings included.
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"reflectance: 0.98}\nport", "reflectance: 0.97}\nport"},
           {"power: 100", "power: 100.000001"},
           {"photons: 20000", "photons: 24000"},
           {"field_step_deg: 6", "field_step_deg: 5"},
           {"plane_samples: 64", "plane_samples: 64, seed: 2"},
           {"plane_samples: 64", "plane_samples: 64, batches: 8"}}) {
    std::string text = kScene;
    ASSERT_NE(text.find(from), std::string::npos) << from;
    text.replace(text.find(from), from.size(), to);
    EXPECT_NE(sphere_cache_key(parse_scene(text, "changed.yaml")), key) << to;
  }
  // What the solve does not read: the sensor below the port, the port integrals' samples, and
  // photons beyond whole batches (20007 photons in 16 batches trace 20000).
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"plane_samples: 64", "plane_samples: 128"},
           {"photons: 20000", "photons: 20007"},
           {"trace:", "sensor: {geometry: lensed, L_o: 30}\ntrace:"}}) {
    std::string text = kScene;
    text.replace(text.find(from), from.size(), to);
    EXPECT_EQ(sphere_cache_key(parse_scene(text, "same-solve.yaml")), key) << to;
  }
  // The key text names polrig's version and revision.
  EXPECT_NE(sphere_cache_key_text(small_scene()).find("git_revision: "), std::string::npos);
}

TEST(SphereCache, BadFilesAreIgnoredWithAWarning) {
  const SceneSpec scene = small_scene();
  const std::string good = encode_sphere_cache_file(scene, small_solution());
  SceneSpec other = scene;
  other.sphere.reflectance = 0.97;
  std::string flipped = good, foreign = good;
  flipped[good.size() / 2] ^= 0x01;
  foreign[0] = 'X';
  const std::vector<std::pair<std::string, std::string>> cases{
      {"truncated", good.substr(0, good.size() - 9)},
      {"empty", ""},
      {"a flipped bit", flipped},
      {"a foreign magic", foreign},
      {"one more byte", good + "x"},
      {"another scene's", encode_sphere_cache_file(other, small_solution())}};
  for (const auto& [what, bytes] : cases) {
    EXPECT_THROW(decode_sphere_cache_file(bytes, scene), std::runtime_error) << what;
    TestCache t;
    fs::create_directories(t.cache->folder());
    test::write_file(t.cache->file_for(scene), bytes);
    EXPECT_FALSE(t.cache->load(scene)) << what;
    ASSERT_EQ(t.warnings.size(), 1u) << what;
    EXPECT_NE(t.warnings[0].find("ignored"), std::string::npos) << t.warnings[0];
  }
}

TEST(SphereCache, TracedSourceSolvesOverABadFileThenLoads) {
  const SceneSpec scene = small_scene();
  TestCache t;
  fs::create_directories(t.cache->folder());
  test::write_file(t.cache->file_for(scene), "POLRIGSC and then nothing useful");
  const TracedSource first(scene);
  EXPECT_FALSE(first.origin());  // nothing solved yet
  first.prepare({});
  ASSERT_TRUE(first.origin());
  EXPECT_EQ(first.origin()->sphere, "solved");
  EXPECT_EQ(first.origin()->cache_file, t.cache->file_for(scene));
  EXPECT_EQ(t.warnings.size(), 1u);
  // The bad file was replaced by the solve: a second source of the scene loads it.
  const TracedSource second(scene);
  second.prepare({});
  EXPECT_EQ(second.origin()->sphere, "loaded");
  EXPECT_EQ(t.warnings.size(), 1u);
  const Point2 p{1.5, -2.0};
  const AnalyzerFilm film{30.0, 0.95};
  const std::vector<double> a = first.channel_signal(p, 20, film), b = second.channel_signal(p, 20, film);
  EXPECT_TRUE(same_bits(a, b));
}

TEST(SphereCache, ReadOnlyCacheWritesNothing) {
  test::TempDir dir("polrig_test_sphere_cache_");
  const SphereCacheFolder cache(dir.path() / "spheres", false, {});
  EXPECT_EQ(cache.store(small_scene(), small_solution()), "");
  EXPECT_FALSE(fs::exists(dir.path() / "spheres"));
}

// ---- The CLI: study cs and simulate, with and without the cache --------------------------

class SphereCacheCli : public test::PolrigTest {
 protected:
  SphereCacheCli() : PolrigTest("polrig_test_sphere_cache_cli_", "logs") {
    test::write_file(tmp / "scene.yaml", kScene);
    test::write_file(tmp / "rig.yaml", "source: {model: traced, scene: scene.yaml}\n"
                                       "schedule: {start_deg: 0, step_deg: 90, stop_deg: 180, samples_per_stop: 2}\n");
  }
  std::string cache_env(const std::string& folder) { return "POLRIG_CACHE_DIR=" + test::shell_quote(folder) + " "; }
  std::string rig() { return test::shell_quote(tmp / "rig.yaml"); }
  std::string out(const std::string& name) { return test::shell_quote(tmp / name); }

  // Every file of folder `a` but manifest.yaml, byte for byte the same in `b`.
  void expect_same_files(const std::string& a, const std::string& b) {
    std::size_t n = 0;
    for (const auto& e : fs::recursive_directory_iterator(tmp / a)) {
      if (!e.is_regular_file() || e.path().filename() == "manifest.yaml") continue;
      const fs::path rel = fs::relative(e.path(), tmp / a);
      EXPECT_EQ(test::read_file(e.path()), test::read_file(tmp / b / rel)) << rel;
      ++n;
    }
    EXPECT_GE(n, 2u);  // simulate --no-plots: stops.csv, rig.yaml
  }
  std::string manifest(const std::string& folder) { return test::read_file(tmp / folder / "manifest.yaml"); }
};

TEST_F(SphereCacheCli, SecondStudyLoadsTheSphereWithTheSameOutputs) {
  const std::string cache = (tmp / "cache").string();
  ok("study cs " + rig() + " -o " + out("off") + " --no-plots --steps 8", "POLRIG_CACHE_DIR=off ");
  ok("study cs " + rig() + " -o " + out("first") + " --no-plots --steps 8", cache_env(cache));
  const Result second = ok("study cs " + rig() + " -o " + out("second") + " --no-plots --steps 8", cache_env(cache));
  const std::vector<std::string> files =
      test::entries_where(tmp / "cache" / "spheres", [](const std::string& f) { return f.ends_with(".bin"); });
  ASSERT_EQ(files.size(), 1u);
  const std::string file = (tmp / "cache" / "spheres" / files[0]).string();
  EXPECT_HAS(manifest("off"), "light:\n  sphere: solved\n  cache_file: none\n");
  EXPECT_HAS(manifest("first"), "light:\n  sphere: solved\n  cache_file: " + file + "\n");
  EXPECT_HAS(manifest("second"), "light:\n  sphere: loaded\n  cache_file: " + file + "\n");
  EXPECT_LACKS(second.err, "warning");
  expect_same_files("off", "second");
  expect_same_files("first", "second");

  // simulate takes it too, with the same dataset as without the cache.
  ok("simulate " + rig() + " -o " + out("sim-off") + " --no-plots", "POLRIG_CACHE_DIR=off ");
  ok("simulate " + rig() + " -o " + out("sim-cached") + " --no-plots", cache_env(cache));
  EXPECT_HAS(manifest("sim-cached"), "sphere: loaded");
  expect_same_files("sim-off", "sim-cached");
}

TEST_F(SphereCacheCli, TraceFillsTheCacheAndACorruptFileIsSolvedAgain) {
  const std::string cache = (tmp / "cache").string();
  ok("trace " + test::shell_quote(tmp / "scene.yaml") + " -o " + out("trace") + " --no-plots", cache_env(cache));
  EXPECT_HAS(manifest("trace"), "light:\n  sphere: solved\n  cache_file: " + cache);
  ok("study cs " + rig() + " -o " + out("after-trace") + " --no-plots --steps 8", cache_env(cache));
  EXPECT_HAS(manifest("after-trace"), "sphere: loaded");

  // Cut the file short: the next study says so, solves again, and its outputs are the same.
  const std::vector<std::string> files =
      test::entries_where(tmp / "cache" / "spheres", [](const std::string& f) { return f.ends_with(".bin"); });
  ASSERT_EQ(files.size(), 1u);
  const fs::path file = tmp / "cache" / "spheres" / files[0];
  fs::resize_file(file, fs::file_size(file) / 2);
  const Result r = ok("study cs " + rig() + " -o " + out("after-cut") + " --no-plots --steps 8", cache_env(cache));
  EXPECT_HAS(r.err, "polrig: warning: sphere cache file " + file.string() + " ignored (");
  EXPECT_HAS(manifest("after-cut"), "sphere: solved");
  expect_same_files("after-trace", "after-cut");
  ok("study cs " + rig() + " -o " + out("after-repair") + " --no-plots --steps 8", cache_env(cache));
  EXPECT_HAS(manifest("after-repair"), "sphere: loaded");
}

}  // namespace
}  // namespace polrig
