#include "polrig/source/sphere_cache.h"

#include <mutex>

#include "polrig/source/sphere_tracer.h"

namespace polrig {

namespace {
std::mutex& cache_mutex() {
  static std::mutex m;
  return m;
}
std::shared_ptr<const SphereCache>& cache_slot() {
  static std::shared_ptr<const SphereCache> cache;
  return cache;
}
}  // namespace

void install_sphere_cache(std::shared_ptr<const SphereCache> cache) {
  const std::lock_guard lock(cache_mutex());
  cache_slot() = std::move(cache);
}

std::shared_ptr<const SphereCache> installed_sphere_cache() {
  const std::lock_guard lock(cache_mutex());
  return cache_slot();
}

SphereSolution solve_sphere(const SphereTracer& tracer, bool may_load, const Progress& progress,
                            LightOrigin& origin) {
  const std::shared_ptr<const SphereCache> cache = installed_sphere_cache();
  if (cache && may_load)
    if (std::unique_ptr<SphereSolution> loaded = cache->load(tracer.scene())) {
      origin = {"loaded", cache->file_for(tracer.scene())};
      return std::move(*loaded);
    }
  SphereSolution solved = tracer.solve(progress);
  origin = {"solved", cache ? cache->store(tracer.scene(), solved) : std::string()};
  return solved;
}

}  // namespace polrig
