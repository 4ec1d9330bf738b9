#pragma once
// An optical scene for the traced source: the integrating sphere (Lambertian wall), its exit port
// with a linear-polarizer film, the lamps and the baffles that hide them from the port, and the
// sensor optics below the port. Frame: the sphere's centre at the origin, z up; the port is the
// cap around −z, opening downwards. Millimetres, degrees, watts.
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <optional>
#include <vector>

#include "polrig/vec3.h"

namespace polrig {


struct SphereSpec {
  double diameter = 500.0;
  double reflectance = 0.98;  // Lambertian wall reflectance ρ
  double radius() const { return 0.5 * diameter; }
};

// A sheet linear polarizer: transmittance τ_M for light polarized along its axis, τ_m across it.
struct PolarizerFilm {
  double axis_deg = 0.0;
  double tau_M = 0.62;
  double tau_m = 0.18;
  double degree_of_polarization() const { return (tau_M - tau_m) / (tau_M + tau_m); }
  double g_up() const { return 0.5 * (tau_M + tau_m); }  // gain for unpolarized light
  double g_tp() const { return 0.5 * (tau_M - tau_m); }  // gain for totally polarized light
};

struct PortSpec {
  double diameter = 100.0;
  PolarizerFilm polarizer;
  double radius() const { return 0.5 * diameter; }
};

// A spherical lamp (radius 0: a point) emitting `power` watts, diffusely from its surface.
struct LampSpec {
  Vec3 position{0.0, 0.0, 150.0};
  double radius = 10.0;
  double power = 100.0;
  double reflectance = 0.0;
};

// A thin disk that hides lamps from the port; both faces Lambertian with `reflectance`.
struct BaffleSpec {
  Vec3 centre{0.0, 0.0, 90.0};
  Vec3 normal{0.0, 0.0, 1.0};
  double radius = 40.0;
  double reflectance = 0.98;
};

// The sensor below the port. `bare`: photodiodes in the photosensitive plane L_o below the port
// (the paper's simulation). `lensed`: the real sensor, film, filter and plano-convex lens in
// front of each photodiode in a housing whose top is `top_distance` below the port.
struct SensorOpticsSpec {
  std::string geometry = "bare";
  double L_o = 20.0;                 // bare: port plane to photosensitive plane
  double photodiode_size = 1.3;      // square side
  double filter_transmittance = 0.8;
  double top_distance = 20.0;        // lensed: port plane to the housing top (film plane)
  double housing_height = 100.0;
  double film_to_lens = 2.0;
  double lens_focal_length = 50.0;
  double lens_diameter = 12.7;
  double lens_thickness = 3.5;
  double lens_index = 1.5168;        // N-BK7 at 587.6 nm
  double lens_to_photodiode = 48.0;  // from the lens's plane face
};

struct TraceSettings {
  long long photons = 2000000;  // sphere solve
  int batches = 16;             // independent batches for standard errors
  int wall_bins_theta = 90;     // wall radiance map, polar angle from +z
  int wall_bins_phi = 180;
  double field_step_deg = 2.0;     // grid step of the computed wall field (wall_field.h)
  long long plane_samples = 4096;  // quasi-random samples per point for plane and sensor integrals
  std::uint64_t seed = 1;
};

// The sphere solve's photon count set by hand (`polrig trace --photons`, Python's
// trace(photons=)): in [1000, 1e11] and at least 100 per batch; then (given or not) rounded down
// to whole batches, as traced. Returns what is wrong with `photons`, or nothing (and sets it).
std::optional<std::string> set_trace_photons(TraceSettings& trace, std::optional<long long> photons);

struct SceneSpec {
  SphereSpec sphere;
  PortSpec port;
  std::vector<LampSpec> lamps{LampSpec{}};
  std::vector<BaffleSpec> baffles{BaffleSpec{}};
  SensorOpticsSpec sensor;
  TraceSettings trace;

  // z of the port plane (the circle where the port meets the wall): −√(R² − a²).
  double port_plane_z() const {
    const double R = sphere.radius(), a = port.radius();
    return -std::sqrt(R * R - a * a);
  }
};

}  // namespace polrig
