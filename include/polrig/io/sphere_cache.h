#pragma once
// The sphere cache's files (docs/formats.md, "Sphere cache files"): one file per solved sphere,
// SPHERES/<key>.bin, the key a 64-bit FNV-1a (polrig/fnv.h) of everything the solve depends on —
// the scene as parsed (scene_to_yaml: every value, no comment or layout) but for what the solve
// does not read, its trace settings among them, and polrig's version and git revision. A file is written whole or not at all (a
// temporary file renamed into place) and read only if its magic, format, key text, lengths and
// checksum all hold; otherwise it is ignored with a warning and the sphere solved again.
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "polrig/source/sphere_cache.h"
#include "polrig/source/sphere_tracer.h"

namespace polrig {

// What the key hashes: the format, polrig's version and revision (and, for a build from a
// modified tree, its binary's size and time), then the scene as scene_to_yaml writes it, but
// with what the solve does not read left at its defaults (the sensor, trace.plane_samples) and
// trace.photons rounded down to whole batches, as traced.
std::string sphere_cache_key_text(const SceneSpec& scene);
// The key: 16 lowercase hex digits, the file's name without ".bin".
std::string sphere_cache_key(const SceneSpec& scene);

// A cache file's bytes for `solution` of `scene`.
std::string encode_sphere_cache_file(const SceneSpec& scene, const SphereSolution& solution);
// The solution a cache file holds for `scene`; throws std::runtime_error saying what is wrong
// (not a cache file, another format, another key, truncated, a wrong checksum or shape).
SphereSolution decode_sphere_cache_file(std::string_view bytes, const SceneSpec& scene);

// Said when a file is ignored or cannot be written (the CLI prints "polrig: warning: …").
using CacheWarning = std::function<void(const std::string&)>;

// The files of one folder. `write` false: reads only (MPI ranks but 0).
class SphereCacheFolder final : public SphereCache {
 public:
  SphereCacheFolder(std::filesystem::path folder, bool write, CacheWarning warn);
  std::unique_ptr<SphereSolution> load(const SceneSpec& scene) const override;
  std::string store(const SceneSpec& scene, const SphereSolution& solution) const override;
  std::string file_for(const SceneSpec& scene) const override;
  const std::filesystem::path& folder() const { return folder_; }

 private:
  void write_file(const std::filesystem::path& file, const std::string& bytes) const;
  std::filesystem::path folder_;
  bool write_;
  CacheWarning warn_;
};

// The spheres' folder: $POLRIG_CACHE_DIR/spheres when set, else
// ${XDG_CACHE_HOME:-$HOME/.cache}/polrig/spheres; null when POLRIG_CACHE_DIR is "off" (the
// cache disabled) or neither it nor a home is set.
std::optional<std::filesystem::path> sphere_cache_folder_from_environment();
// A SphereCacheFolder there, or null.
std::shared_ptr<const SphereCache> sphere_cache_from_environment(bool write, CacheWarning warn);

}  // namespace polrig
