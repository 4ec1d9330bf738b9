#include "polrig/report/trace_report.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "polrig/io/csv.h"
#include "polrig/io/exr.h"
#include "polrig/io/plot.h"
#include "polrig/io/scene_yaml.h"
#include "polrig/statistics.h"
#include "polrig/source/sphere_cache.h"
#include "polrig/source/sphere_tracer.h"
#include "polrig/source/traced_port.h"
#include "polrig/units.h"

namespace polrig {

std::vector<DatasetFile> trace_scene(const std::filesystem::path& dir, const SceneSpec& scene,
                                     bool plots, const Progress& progress, LightOrigin* origin) {
  const SphereTracer tracer(scene);
  LightOrigin how;
  const SphereSolution sol = solve_sphere(tracer, false, progress, how);
  if (origin) *origin = how;
  const EnergyLedger& L = sol.ledger;
  if (L.leaked > 0)
    throw std::runtime_error(fmt::format("the sphere leaked {} of {} photons: the geometry is not "
                                         "closed; nothing was written", L.leaked, L.launched));
  const WallMap& w = sol.wall;
  const double rho = scene.sphere.reflectance;

  // Wall radiance map: L = ρE/π, with its standard error.
  ExrChannel Lc{"L", {}}, Lse{"L_se", {}};
  CsvTable wall({"i_theta", "i_phi", "cos_theta", "phi_deg", "L_Wm2sr", "L_se_Wm2sr"});
  for (int it = 0; it < w.n_theta; ++it)
    for (int ip = 0; ip < w.n_phi; ++ip) {
      const std::size_t b = static_cast<std::size_t>(w.bin(it, ip));
      const double l = rho * w.E[b] / kPi, se = rho * w.E_se[b] / kPi;
      Lc.pixels.push_back(static_cast<float>(l));
      Lse.pixels.push_back(static_cast<float>(se));
      wall.add_row({static_cast<double>(it), static_cast<double>(ip), 1.0 - (2.0 * it + 1.0) / w.n_theta,
                    360.0 * (ip + 0.5) / w.n_phi, l, se});
    }
  write_exr(dir / "wall_radiance.exr", w.n_phi, w.n_theta, {Lc, Lse});
  write_text_file(dir / "wall_radiance.csv", wall.text());

  // Stokes irradiance on the plane L_o below the port, over ±1.5 port radii.
  const TracedPort port(tracer, sol, mean_port_radiance(tracer, sol, scene.sensor.L_o));
  const double a = scene.port.radius(), L_o = scene.sensor.L_o;
  const int N = 61;
  const double half = 1.5 * a;
  std::vector<StokesIrradiance> grid(static_cast<std::size_t>(N * N));
  const long long map_samples = std::max<long long>(64, scene.trace.plane_samples / 8);
  progress.begin("trace: plane map", N * N);
  tbb::parallel_for(0, N * N, [&](int k) {
    const double x = -half + 2 * half * (k % N) / (N - 1), y = half - 2 * half * (k / N) / (N - 1);
    grid[static_cast<std::size_t>(k)] = port.plane_stokes(x, y, L_o, map_samples, 4);
    progress.advance();
  });
  progress.finish();
  ExrChannel s0{"S0", {}}, s1{"S1", {}}, s2{"S2", {}}, s0se{"S0_se", {}};
  CsvTable plane({"x_mm", "y_mm", "S0", "S1", "S2", "S0_se"});
  for (int k = 0; k < N * N; ++k) {
    const StokesIrradiance& e = grid[static_cast<std::size_t>(k)];
    s0.pixels.push_back(static_cast<float>(e.S0));
    s1.pixels.push_back(static_cast<float>(e.S1));
    s2.pixels.push_back(static_cast<float>(e.S2));
    s0se.pixels.push_back(static_cast<float>(e.S0_se));
    plane.add_row({-half + 2 * half * (k % N) / (N - 1), half - 2 * half * (k / N) / (N - 1), e.S0, e.S1, e.S2, e.S0_se});
  }
  write_exr(dir / "plane_stokes.exr", N, N, {s0, s1, s2, s0se});
  write_text_file(dir / "plane_stokes.csv", plane.text());

  // Azimuthally averaged profile against the distance from the port axis, with the uniform-disk
  // formula and cos⁴φ scaled to the centre for comparison.
  const int azimuths = 8, radii = 31;
  const double g_film = scene.port.polarizer.g_up();
  const RayTransmission through_film = [g_film](const Vec3&) { return g_film; };
  const long long samples = scene.trace.plane_samples;
  std::vector<std::array<double, 2>> prof(static_cast<std::size_t>(radii));
  tbb::parallel_for(0, radii, [&](int i) {
    const double r = 1.5 * a * i / (radii - 1);
    double s = 0, s2sum = 0;
    for (int j = 0; j < azimuths; ++j) {
      const double phi = 2 * kPi * j / azimuths;
      const MeanAndSpread e = mean_and_standard_error(
          port.irradiance(r * std::cos(phi), r * std::sin(phi), L_o, through_film, samples, 8));
      s += e.mean / azimuths;
      s2sum += e.sd * e.sd / (azimuths * azimuths);
    }
    prof[static_cast<std::size_t>(i)] = {s, std::sqrt(s2sum)};
  });
  const PolarizerFilm& film = scene.port.polarizer;
  const double g_up = film.g_up();
  const double L_mean = prof[0][0] / (g_up * disk_irradiance(1.0, a, L_o, 0.0));
  CsvTable profile({"r_mm", "S0", "S0_stderr", "L_o_mm", "S0_uniform_disk", "S0_cos4"});
  for (int i = 0; i < radii; ++i) {
    const double r = 1.5 * a * i / (radii - 1);
    const double cos4 = std::pow(L_o * L_o / (L_o * L_o + r * r), 2);
    profile.add_row({r, prof[static_cast<std::size_t>(i)][0], prof[static_cast<std::size_t>(i)][1], L_o,
                     g_up * disk_irradiance(L_mean, a, L_o, r), prof[0][0] * cos4});
  }
  write_text_file(dir / "plane_profile.csv", profile.text());

  // The ledger and sphere theory's mean wall irradiance for this lamp power.
  const double R = scene.sphere.radius(), A_s = 4 * kPi * R * R * 1e-6;
  const double f = (R - std::sqrt(R * R - a * a)) / (2 * R);
  double first_W = 0, area = 0, indirect = 0;
  for (std::size_t b = 0; b < w.E.size(); ++b) {
    first_W += w.E_first[b] * w.wall_area_mm2[b] * 1e-6;
    indirect += (w.E[b] - w.E_first[b]) * w.wall_area_mm2[b];
    area += w.wall_area_mm2[b];
  }
  std::string summary = fmt::format(
      "photons_launched: {}\nabsorbed_wall: {}\nabsorbed_baffles: {}\nabsorbed_lamps: {}\n"
      "escaped: {}\nleaked: {}\nrays: {}\n"
      "lamp_power_W: {}\nfirst_strike_on_wall_W: {}\nport_fraction: {}\n"
      "mean_indirect_wall_irradiance_Wm2: {}\nsphere_theory_Wm2: {}\n"
      "mean_port_radiance_Wm2sr: {}\n",
      L.launched, L.absorbed_wall, L.absorbed_baffles, L.absorbed_lamps, L.escaped, L.leaked, L.rays,
      sol.power_W, first_W, f, indirect / area,
      first_W * rho / (A_s * (1 - rho * (1 - f))), L_mean);
  write_text_file(dir / "trace_summary.yaml", summary);
  write_text_file(dir / "scene.yaml", scene_to_yaml(scene));

  std::vector<DatasetFile> files{
      {"wall_radiance.exr", 1, "wall radiance L and its standard error (W/m²/sr), equal-area bins: rows cos θ from +1 down to −1, columns φ from 0 to 360°"},
      {"wall_radiance.csv", 1, "the same map as a table"},
      {"plane_stokes.exr", 1, "Stokes irradiance S0, S1, S2 and S0's standard error (W/m²) on the plane L_o below the port, 61 × 61 over ±1.5 port radii (x right, y up)"},
      {"plane_stokes.csv", 1, "the same map as a table"},
      {"plane_profile.csv", 1, "azimuthally averaged S0 against the distance from the port axis, with the uniform-disk formula and cos⁴φ"},
      {"trace_summary.yaml", 1, "energy ledger, speed and sphere theory"},
      {"scene.yaml", 1, "the scene traced (every key); loads back to the same scene"}};
  if (!plots) return files;
  Plot wall_png{"wall_radiance.png", "Wall radiance (W/m²/sr)", "φ (°)", "cos θ"};
  wall_png.series = {{"wall_radiance.csv", "$phi_deg:$cos_theta:$L_Wm2sr", "L", "image"}};
  wall_png.extra = "set key off\nset xrange [0:360]\nset yrange [-1:1]";
  Plot plane_png{"plane_S0.png", fmt::format("S0 on the plane {} mm below the port (W/m²)", L_o), "x (mm)", "y (mm)"};
  plane_png.series = {{"plane_stokes.csv", "$x_mm:$y_mm:$S0", "S0", "image"}};
  plane_png.extra = "set key off\nset size ratio -1";
  Plot prof_png{"plane_profile.png", "Irradiance below the port against the distance from its axis",
                "r (mm)", "S0 (W/m²)"};
  prof_png.series = {{"plane_profile.csv", "$r_mm:$S0:$S0_stderr", "traced", "yerrorlines lw 2 pt 7 ps 0.6"},
                     {"plane_profile.csv", "$r_mm:$S0_uniform_disk", "uniform disk (view factor)", "lines lw 2 dt 2"},
                     {"plane_profile.csv", "$r_mm:$S0_cos4", "cos⁴φ from the centre", "lines lw 2 dt 3"}};
  render_plots(dir, "plots.gp", {wall_png, plane_png, prof_png});
  files.push_back({"wall_radiance.png", 1, "preview of the wall radiance map"});
  files.push_back({"plane_S0.png", 1, "preview of S0 below the port"});
  files.push_back({"plane_profile.png", 1, "the profile against the view factor and cos⁴φ"});
  return files;
}

}  // namespace polrig
