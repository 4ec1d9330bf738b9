#pragma once
// The integrating sphere traced with Embree (design.md, "The traced source").
//
// Geometry is analytic (Embree user geometry: the wall, spherical lamps, disk baffles), so no
// ray can slip between triangles; intersections are recomputed in double precision. The sphere
// solve traces photons from the lamps until they are absorbed or leave through the port, and
// tallies the irradiance on the wall (an equal-area map in cos θ and φ) and on the baffles.
#include <memory>
#include <vector>

#include "polrig/progress.h"
#include "polrig/source/scene.h"
#include "polrig/source/wall_field.h"

namespace polrig {

// Where the photons went. Every launched photon ends in exactly one of the other counts.
struct EnergyLedger {
  long long launched = 0;
  long long absorbed_wall = 0, absorbed_baffles = 0, absorbed_lamps = 0;
  long long escaped = 0;  // through the port
  long long leaked = 0;   // lost by the geometry: must be 0
  long long rays = 0;     // rtcIntersect1 calls
  long long ended() const { return absorbed_wall + absorbed_baffles + absorbed_lamps + escaped + leaked; }
};

// Irradiance on the wall, W/m², per equal-area bin: θ from +z with cos θ uniform in bins, φ from
// +x towards +y. `first` is the part from photons' first strike; its complement is the
// "indirect" irradiance of sphere theory. Standard errors from the spread of independent batches.
struct WallMap {
  int n_theta = 0, n_phi = 0;
  std::vector<double> E, E_se, E_first, E_first_se;
  std::vector<double> wall_area_mm2;  // the part of each bin that is wall (the port cut removed)
  int bin(int i_theta, int i_phi) const { return i_theta * n_phi + i_phi; }
};

struct SphereSolution {
  WallMap wall;
  WallField field;  // the light after the first strike, computed (wall_field.h)
  std::vector<std::array<double, 2>> baffle_E;  // mean irradiance of each baffle's faces (+n, −n)
  EnergyLedger ledger;
  std::vector<double> batch_indirect_W;  // per batch: power landing on the wall after the first strike
  double power_W = 0;       // all lamps
  double seconds = 0;       // wall-clock time of the solve
};

class SphereTracer {
 public:
  explicit SphereTracer(const SceneSpec& scene);
  ~SphereTracer();
  SphereTracer(const SphereTracer&) = delete;
  SphereTracer& operator=(const SphereTracer&) = delete;

  // Traces scene.trace.photons photons in scene.trace.batches batches (in parallel; the result
  // does not depend on the thread count).
  // Then computes the wall field (wall_field.h) from them. Reports both stages to `progress`.
  // Reads neither scene().sensor nor trace.plane_samples: the sphere cache's key leaves them out
  // (io/sphere_cache.h), so a solve that came to read them must put them back there.
  SphereSolution solve(const Progress& progress = {}) const;
  // The photons alone: the solution without its wall field (for benchmarks of the tracer).
  SphereSolution trace_photons(const Progress& progress = {}) const;

  struct Hit {
    enum Kind { None, Wall, Lamp, Baffle } kind = None;
    int index = -1;  // lamp or baffle index
    Vec3 point{};
    double t = 0;
    bool front = true;  // baffle: hit on the face its normal points to
  };
  // The first surface along origin + t·dir, t > t_min, dir of unit length; None when the ray
  // leaves through the port (or starts outside and never enters).
  Hit first_hit(const Vec3& origin, const Vec3& dir, double t_min = 1e-9) const;

  // Radiance (W/m²/sr) of a point a ray has hit, from a solution: ρE/π of the wall (first strike
  // plus the computed field) or of the baffle face (uniform per face); a lamp's own exitance/π (its reflection is
  // not added).
  double radiance(const SphereSolution& s, const Hit& h) const;

  const SceneSpec& scene() const { return scene_; }

  // Irradiance (W/m²) on a wall point straight from the lamps (the first strike), computed, not
  // sampled: each lamp as a point of intensity Φ/(4π) at its centre, hidden where a baffle cuts
  // the line to it (a hard shadow; the penumbra of a finite lamp is not modelled).
  double direct_irradiance(const Vec3& wall_point) const;

  // For benchmarks. `count` rays such as a photon tracer casts: from wall points in
  // cosine-weighted directions.
  struct Ray {
    Vec3 origin, dir;
  };
  std::vector<Ray> wall_rays(long long count, std::uint64_t seed) const;
  // One plain rtcIntersect1 call on this scene for each ray, nothing else (the reference of
  // the tracer's speed). Returns the hits counted.
  long long plain_intersections(const std::vector<Ray>& rays) const;

  struct Impl;

 private:
  SceneSpec scene_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace polrig
