#pragma once
// The sphere cache: solved spheres kept between runs, keyed by everything a solve depends on,
// so that a second study of a scene skips the solve. source/ owns the hook (this interface and
// the one installed instance); io/sphere_cache implements it with files (docs/formats.md,
// "Sphere cache files"), and the front end installs it.
#include <memory>
#include <string>

#include "polrig/progress.h"
#include "polrig/source/scene.h"
#include "polrig/source/source.h"

namespace polrig {

class SphereTracer;
struct SphereSolution;

class SphereCache {
 public:
  virtual ~SphereCache() = default;
  // The solution stored for `scene`, or null: none stored, or a file not trusted (the
  // implementation says why and the caller solves again). Never throws for a bad file.
  virtual std::unique_ptr<SphereSolution> load(const SceneSpec& scene) const = 0;
  // Keeps `solution` of `scene`; returns the file written, or "" when nothing was (a cache that
  // only reads, or a write that failed, which the implementation says). Never throws.
  virtual std::string store(const SceneSpec& scene, const SphereSolution& solution) const = 0;
  // The file that holds (or would hold) `scene`'s solution.
  virtual std::string file_for(const SceneSpec& scene) const = 0;
};

// The cache every traced source and `trace_scene` use: none (null) until a front end installs
// one (the CLI: io's, from the environment). Thread-safe; a source reads it when it solves.
void install_sphere_cache(std::shared_ptr<const SphereCache> cache);
std::shared_ptr<const SphereCache> installed_sphere_cache();

// The solution of `tracer`'s scene: loaded from the installed cache when `may_load` and it holds
// a good one, else solved (SphereTracer::solve, reported to `progress`) and stored in it.
// `origin` says which, and the file.
SphereSolution solve_sphere(const SphereTracer& tracer, bool may_load, const Progress& progress,
                            LightOrigin& origin);

}  // namespace polrig
