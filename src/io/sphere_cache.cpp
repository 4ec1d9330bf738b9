#include "polrig/io/sphere_cache.h"

#include <dlfcn.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <bit>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/fnv.h"
#include "polrig/io/csv.h"
#include "polrig/io/scene_yaml.h"
#include "polrig/version.h"

namespace polrig {
namespace fs = std::filesystem;

namespace {
constexpr std::string_view kMagic{"POLRIGSC", 8};
constexpr std::uint64_t kFormat = 1;

// A build from a modified tree ("-dirty") has no revision of its own: its binary's size and
// modification time stand in, so that a rebuilt binary never reads its predecessor's spheres.
std::string build_identity() {
  const std::string_view rev = POLRIG_GIT_REVISION;
  if (!rev.ends_with("-dirty") && rev != "unknown") return "";
  Dl_info info{};
  struct stat st {};
  const bool found = ::dladdr(reinterpret_cast<void*>(&build_identity), &info) != 0 && info.dli_fname &&
                     ::stat(info.dli_fname, &st) == 0;
  if (!found && ::stat("/proc/self/exe", &st) != 0) return "build: unidentified\n";
  return fmt::format("build: {} bytes, modified {}.{:09}\n", st.st_size, st.st_mtim.tv_sec, st.st_mtim.tv_nsec);
}

// Little-endian bytes, whatever the machine.
void put_u64(std::string& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}
void put_f64(std::string& out, double v) { put_u64(out, std::bit_cast<std::uint64_t>(v)); }
void put_doubles(std::string& out, const std::vector<double>& v) {
  put_u64(out, v.size());
  for (double x : v) put_f64(out, x);
}

// Reads what put_* wrote; throws on running past the end.
struct Reader {
  std::string_view in;
  std::size_t at = 0;
  std::string_view take(std::uint64_t n) {
    if (n > in.size() - at) throw std::runtime_error("truncated");
    const std::string_view s = in.substr(at, static_cast<std::size_t>(n));
    at += static_cast<std::size_t>(n);
    return s;
  }
  std::uint64_t u64() {
    const std::string_view b = take(8);
    std::uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(b[static_cast<std::size_t>(i)]);
    return v;
  }
  long long i64() { return static_cast<long long>(u64()); }
  int count() {
    const std::uint64_t v = u64();
    if (v > 1u << 30) throw std::runtime_error("a count out of range");
    return static_cast<int>(v);
  }
  double f64() { return std::bit_cast<double>(u64()); }
  std::vector<double> doubles() {
    const std::uint64_t n = u64();
    if (n > (in.size() - at) / 8) throw std::runtime_error("truncated");
    std::vector<double> v(static_cast<std::size_t>(n));
    for (double& x : v) x = f64();
    return v;
  }
};

std::string encode_solution(const SphereSolution& s) {
  std::string out;
  const WallMap& w = s.wall;
  put_u64(out, static_cast<std::uint64_t>(w.n_theta));
  put_u64(out, static_cast<std::uint64_t>(w.n_phi));
  for (const auto* v : {&w.E, &w.E_se, &w.E_first, &w.E_first_se, &w.wall_area_mm2}) put_doubles(out, *v);
  put_f64(out, s.field.C);
  put_u64(out, static_cast<std::uint64_t>(s.field.n_theta));
  put_u64(out, static_cast<std::uint64_t>(s.field.n_phi));
  put_doubles(out, s.field.delta);
  put_f64(out, s.field.R);
  put_u64(out, s.baffle_E.size());
  for (const auto& b : s.baffle_E) put_f64(out, b[0]), put_f64(out, b[1]);
  const EnergyLedger& L = s.ledger;
  for (long long c : {L.launched, L.absorbed_wall, L.absorbed_baffles, L.absorbed_lamps, L.escaped, L.leaked, L.rays})
    put_u64(out, static_cast<std::uint64_t>(c));
  put_doubles(out, s.batch_indirect_W);
  put_f64(out, s.power_W);
  put_f64(out, s.seconds);
  return out;
}

SphereSolution decode_solution(Reader& r) {
  SphereSolution s;
  WallMap& w = s.wall;
  w.n_theta = r.count();
  w.n_phi = r.count();
  for (auto* v : {&w.E, &w.E_se, &w.E_first, &w.E_first_se, &w.wall_area_mm2}) *v = r.doubles();
  s.field.C = r.f64();
  s.field.n_theta = r.count();
  s.field.n_phi = r.count();
  s.field.delta = r.doubles();
  s.field.R = r.f64();
  s.baffle_E.resize(static_cast<std::size_t>(r.count()));
  for (auto& b : s.baffle_E) b = {r.f64(), r.f64()};
  EnergyLedger& L = s.ledger;
  for (long long* c : {&L.launched, &L.absorbed_wall, &L.absorbed_baffles, &L.absorbed_lamps, &L.escaped, &L.leaked, &L.rays})
    *c = r.i64();
  s.batch_indirect_W = r.doubles();
  s.power_W = r.f64();
  s.seconds = r.f64();
  return s;
}

// The shapes the scene implies: a file whose key text matches has them, unless it was forged.
void check_shape(const SphereSolution& s, const SceneSpec& scene) {
  const std::size_t bins = static_cast<std::size_t>(s.wall.n_theta) * static_cast<std::size_t>(s.wall.n_phi);
  bool ok = s.wall.n_theta == scene.trace.wall_bins_theta && s.wall.n_phi == scene.trace.wall_bins_phi &&
            s.baffle_E.size() == scene.baffles.size() &&
            s.field.delta.size() == static_cast<std::size_t>(s.field.n_theta) * static_cast<std::size_t>(s.field.n_phi) &&
            s.batch_indirect_W.size() == static_cast<std::size_t>(scene.trace.batches);
  for (const auto* v : {&s.wall.E, &s.wall.E_se, &s.wall.E_first, &s.wall.E_first_se, &s.wall.wall_area_mm2})
    ok = ok && v->size() == bins;
  if (!ok) throw std::runtime_error("its arrays do not have the scene's shapes");
}

std::string read_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open it");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The scene as the solve sees it: SphereTracer::solve reads neither the sensor below the port nor
// trace.plane_samples (the port integrals'), and traces whole batches. Scenes that differ only
// there share a solve (a bare and a lensed rig of one sphere).
SceneSpec solved_part(SceneSpec scene) {
  scene.sensor = SensorOpticsSpec{};
  scene.trace.plane_samples = TraceSettings{}.plane_samples;
  if (scene.trace.batches > 0) scene.trace.photons -= scene.trace.photons % scene.trace.batches;
  return scene;
}
}  // namespace

std::string sphere_cache_key_text(const SceneSpec& scene) {
  return fmt::format("polrig sphere cache {}\nversion: {}\ngit_revision: {}\n{}", kFormat, POLRIG_VERSION,
                     POLRIG_GIT_REVISION, build_identity()) +
         scene_to_yaml(solved_part(scene));
}

std::string sphere_cache_key(const SceneSpec& scene) {
  return fmt::format("{:016x}", fnv1a(sphere_cache_key_text(scene)));
}

// magic, format, key, key text (its length, its bytes), payload (its length, its bytes), then the
// FNV-1a of everything before it.
std::string encode_sphere_cache_file(const SceneSpec& scene, const SphereSolution& solution) {
  const std::string key_text = sphere_cache_key_text(scene), payload = encode_solution(solution);
  std::string out(kMagic);
  put_u64(out, kFormat);
  put_u64(out, fnv1a(key_text));
  put_u64(out, key_text.size());
  out += key_text;
  put_u64(out, payload.size());
  out += payload;
  put_u64(out, fnv1a(out));
  return out;
}

SphereSolution decode_sphere_cache_file(std::string_view bytes, const SceneSpec& scene) {
  Reader r{bytes};
  if (bytes.size() < kMagic.size() || r.take(kMagic.size()) != kMagic) throw std::runtime_error("not a sphere cache file");
  if (const std::uint64_t f = r.u64(); f != kFormat)
    throw std::runtime_error(fmt::format("format {}, expected {}", f, kFormat));
  const std::string key_text = sphere_cache_key_text(scene);
  const std::uint64_t key = r.u64();
  if (key != fnv1a(key_text) || r.take(r.u64()) != key_text)
    throw std::runtime_error("it holds another scene, settings or polrig build");
  Reader payload{r.take(r.u64())};
  const std::size_t checked = r.at;
  if (r.u64() != fnv1a(bytes.substr(0, checked))) throw std::runtime_error("wrong checksum");
  if (r.at != bytes.size()) throw std::runtime_error("bytes after its end");
  SphereSolution s = decode_solution(payload);
  if (payload.at != payload.in.size()) throw std::runtime_error("a payload longer than its solution");
  check_shape(s, scene);
  return s;
}

SphereCacheFolder::SphereCacheFolder(fs::path folder, bool write, CacheWarning warn)
    : folder_(std::move(folder)), write_(write), warn_(std::move(warn)) {}

std::string SphereCacheFolder::file_for(const SceneSpec& scene) const {
  return (folder_ / (sphere_cache_key(scene) + ".bin")).string();
}

std::unique_ptr<SphereSolution> SphereCacheFolder::load(const SceneSpec& scene) const {
  const fs::path file = file_for(scene);
  std::error_code ec;
  if (!fs::exists(file, ec)) return nullptr;
  try {
    return std::make_unique<SphereSolution>(decode_sphere_cache_file(read_bytes(file), scene));
  } catch (const std::exception& e) {
    if (warn_) warn_(fmt::format("sphere cache file {} ignored ({}): solving the sphere again", file.string(), e.what()));
    return nullptr;
  }
}

std::string SphereCacheFolder::store(const SceneSpec& scene, const SphereSolution& solution) const {
  if (!write_) return "";
  const fs::path file = file_for(scene);
  try {
    write_file(file, encode_sphere_cache_file(scene, solution));
    return file.string();
  } catch (const std::exception& e) {
    if (warn_) warn_(fmt::format("the sphere cache was not written: {}", e.what()));
    return "";
  }
}

// A temporary file of this process and call, synced, renamed over the file: readers see the old
// file or the new one, whole; two writers of one key each rename a whole file.
void SphereCacheFolder::write_file(const fs::path& file, const std::string& bytes) const {
  static std::atomic<unsigned> calls{0};
  fs::create_directories(folder_);
  const fs::path temp = folder_ / fmt::format(".{}.{}-{}.tmp", file.filename().string(), ::getpid(), calls++);
  try {
    TextFileWriter out(temp);
    out.write(bytes);
    out.sync();
    out.close();
    fs::rename(temp, file);
  } catch (...) {
    std::error_code ec;
    fs::remove(temp, ec);
    throw;
  }
}

std::optional<fs::path> sphere_cache_folder_from_environment() {
  const auto env = [](const char* name) -> std::string {
    const char* v = std::getenv(name);
    return v ? v : "";
  };
  const std::string dir = env("POLRIG_CACHE_DIR"), xdg = env("XDG_CACHE_HOME"), home = env("HOME");
  if (dir == "off") return std::nullopt;
  if (!dir.empty()) return fs::path(dir) / "spheres";
  if (!xdg.empty() && fs::path(xdg).is_absolute()) return fs::path(xdg) / "polrig" / "spheres";
  if (!home.empty()) return fs::path(home) / ".cache" / "polrig" / "spheres";
  return std::nullopt;
}

std::shared_ptr<const SphereCache> sphere_cache_from_environment(bool write, CacheWarning warn) {
  const std::optional<fs::path> folder = sphere_cache_folder_from_environment();
  if (!folder) return nullptr;
  std::error_code ec;
  const fs::path absolute = fs::absolute(*folder, ec);
  return std::make_shared<const SphereCacheFolder>(ec ? *folder : absolute, write, std::move(warn));
}

}  // namespace polrig
