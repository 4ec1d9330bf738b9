#include "polrig/source/traced_source.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include "polrig/device/sensor.h"
#include "polrig/optics/lens.h"
#include "polrig/optics/polarized_ray.h"
#include "polrig/units.h"
#include "polrig/random.h"
#include "polrig/source/sphere_cache.h"
#include "polrig/source/sphere_tracer.h"
#include "polrig/source/traced_port.h"

namespace polrig {

TracedSource::TracedSource(const SceneSpec& scene)
    : scene_(scene), tracer_(std::make_unique<SphereTracer>(scene_)) {}

TracedSource::~TracedSource() = default;

void TracedSource::solve(const Progress& progress) const {
  std::call_once(solved_, [&] {
    // The first caller solves for all, usually from inside a parallel loop. Isolated, so that
    // while this thread waits in the solve's own loops it takes no other task of the caller's
    // loop (which would ask for the solution again, on this thread: a deadlock); in its own task
    // group context, so that a failure elsewhere in the caller's loop cannot cancel it halfway
    // (TBB returns from a cancelled nested loop as if it had finished). Its own error is kept and
    // given to every caller, rather than tried again by each thread.
    try {
      tbb::task_group_context own(tbb::task_group_context::isolated);
      tbb::this_task_arena::isolate([&] {
        tbb::parallel_for(0, 1, [&](int) {
          auto sol = std::make_unique<SphereSolution>(solve_sphere(*tracer_, true, progress, origin_));
          L_ref_ = mean_port_radiance(*tracer_, *sol, scene_.sensor.L_o);
          solution_ = std::move(sol);
        }, own);
      });
      if (!solution_) throw std::runtime_error("the sphere solve was cancelled");
    } catch (...) {
      solve_failure_ = std::current_exception();
    }
  });
  if (solve_failure_) std::rethrow_exception(solve_failure_);
}

const SphereSolution& TracedSource::solution() const {
  solve({});
  return *solution_;
}

std::optional<LightOrigin> TracedSource::origin() const {
  // solution_ is set once, inside call_once, by the thread that solved: read after the solve.
  if (!solution_) return std::nullopt;
  return origin_;
}

long long TracedSource::solve_rays() const { return solution().ledger.rays; }
double TracedSource::solve_seconds() const { return solution().seconds; }

namespace {
// The R4 sequence (generalised golden ratio in 4-D): a rank-1 lattice for the lensed integral.
constexpr double kPhi4 = 1.1673039782614187;

// The port film (horizontal, at the port) and the channel's analyzer (horizontal, below it) on
// a ray of unit unpolarized radiance travelling along k; the Stokes vector after both.
struct FilmPair {
  PolarizerFilm port;
  AnalyzerFilm analyzer;
  double tau_M = 1, tau_m = 0;  // the analyzer's, from its efficiency: τm/τM = (1 − e)/(1 + e)
  double gains = 1;             // g_up·g_up'

  FilmPair(const PolarizerFilm& p, const AnalyzerFilm& a) : port(p), analyzer(a) {
    tau_m = (1 - a.efficiency) / (1 + a.efficiency);
    gains = p.g_up() * 0.5 * (tau_M + tau_m);
  }
  // The same two films as one closed form (S0 alone, for the bare sensor).
  SheetPolarizerPair sheets() const {
    const double psi = deg2rad(port.axis_deg), beta = deg2rad(analyzer.axis_deg);
    return {{0, 0, 1}, {std::cos(psi), std::sin(psi), 0}, port.tau_M, port.tau_m,
            {std::cos(beta), std::sin(beta), 0}, tau_M, tau_m};
  }
  PolarizedRay through(const Vec3& k) const {
    const Vec3 z{0, 0, 1};
    const double psi = deg2rad(port.axis_deg), beta = deg2rad(analyzer.axis_deg);
    PolarizedRay ray = unpolarized_ray(k, 1.0);
    pass_sheet_polarizer(ray, z, {std::cos(psi), std::sin(psi), 0}, port.tau_M, port.tau_m);
    pass_sheet_polarizer(ray, z, {std::cos(beta), std::sin(beta), 0}, tau_M, tau_m);
    return ray;
  }
};
}  // namespace

std::vector<double> TracedSource::lensed_signal(const Point2& p, double top, const AnalyzerFilm& film) const {
  const SensorOpticsSpec& o = scene_.sensor;
  const PlanoConvexLens lens =
      PlanoConvexLens::from_focal_length(o.lens_focal_length, o.lens_thickness, o.lens_diameter, o.lens_index);
  const double zp = scene_.port_plane_z(), a = scene_.port.radius();
  const double z0 = zp - top - o.film_to_lens - o.lens_thickness;  // the lens's plane face
  const double a_lens = 0.5 * o.lens_diameter, size = o.photodiode_size;
  const FilmPair films(scene_.port.polarizer, film);
  const long long samples = scene_.trace.plane_samples;
  const SphereSolution& sol = solution();
  double alpha[4];
  for (int k = 0; k < 4; ++k) alpha[k] = std::pow(1.0 / kPhi4, k + 1);
  std::vector<double> signal(static_cast<std::size_t>(shifts_));
  for (int sh = 0; sh < shifts_; ++sh) {
    double start[4];
    for (int k = 0; k < 4; ++k) start[k] = uniform_unit(scene_.trace.seed, static_cast<std::uint64_t>(sh), 0x1E25, static_cast<std::uint64_t>(k));
    double e = 0;
    for (long long n = 0; n < samples; ++n) {
      double u[4];
      for (int k = 0; k < 4; ++k) u[k] = std::fmod(start[k] + alpha[k] * static_cast<double>(n + 1), 1.0);
      // A photodiode point and a point of the lens's plane face, in the channel's lens frame.
      // The square is not turned with the table: its second moments, all that a smooth
      // irradiance sees across 1.3 mm, are the same at any angle.
      const std::array<double, 3> s{(u[0] - 0.5) * size, (u[1] - 0.5) * size, -o.lens_to_photodiode};
      const double rho = a_lens * std::sqrt(u[2]), phi = 2 * kPi * u[3];
      const std::array<double, 3> q{rho * std::cos(phi), rho * std::sin(phi), 0.0};
      const std::array<double, 3> d{q[0] - s[0], q[1] - s[1], q[2] - s[2]};
      const double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], r = std::sqrt(r2);
      // Traced backwards from the photodiode for the path; up to the port plane, where light
      // only comes through the port.
      const auto out = trace_through(lens, LensRay{s, {d[0] / r, d[1] / r, d[2] / r}, 1.0});
      if (!out) continue;
      const double t = (zp - (z0 + out->origin[2])) / out->direction[2];
      const Vec3 Q{p.x() + out->origin[0] + t * out->direction[0], p.y() + out->origin[1] + t * out->direction[1], zp};
      if (Q[0] * Q[0] + Q[1] * Q[1] > a * a) continue;
      const Vec3 up{out->direction[0], out->direction[1], out->direction[2]};
      const SphereTracer::Hit h = tracer_->first_hit(Q, up, 0.0);
      // Then forwards, as the light goes: both films, the lens's two faces (from 1 mm above it).
      const Vec3 k{-up[0], -up[1], -up[2]};
      PolarizedRay ray = films.through(k);
      const LensRay in{{out->origin[0] + up[0], out->origin[1] + up[1], out->origin[2] + up[2]}, k, 1.0};
      if (!trace_through(lens, in, &ray)) continue;
      // cos θ_s · cos θ_q / r² (both faces parallel to the photodiode), per unit lens area.
      e += tracer_->radiance(sol, h) * ray.S[0] * (d[2] * d[2]) / (r2 * r2);
    }
    signal[static_cast<std::size_t>(sh)] =
        o.filter_transmittance * e * kPi * a_lens * a_lens / static_cast<double>(samples) / films.gains;
  }
  return signal;
}

std::vector<std::vector<double>> TracedSource::bare_signals(const Point2& p, double L_o,
                                                           const std::vector<AnalyzerFilm>& films) const {
  std::vector<FilmPair> pairs;
  std::vector<SheetPolarizerPair> sheets;
  for (const AnalyzerFilm& f : films) {
    pairs.emplace_back(scene_.port.polarizer, f);
    sheets.push_back(pairs.back().sheets());
  }
  std::vector<RayTransmission> T;
  for (std::size_t f = 0; f < films.size(); ++f)
    T.push_back([&, f](const Vec3& k) { return sheets[f].transmittance(k) / pairs[f].gains; });
  const SphereSolution& sol = solution();
  const TracedPort port(*tracer_, sol, L_ref_);
  const long long samples = std::max<long long>(16, scene_.trace.plane_samples / 4);
  // 2 × 2 Gauss–Legendre points over the square photodiode: exact for irradiance that varies as
  // a cubic across it.
  const double g = 0.5 * scene_.sensor.photodiode_size / std::sqrt(3.0);
  std::vector<std::vector<double>> signal(films.size(), std::vector<double>(static_cast<std::size_t>(shifts_), 0.0));
  for (int k = 0; k < 4; ++k) {
    const double x = p.x() + ((k & 1) ? g : -g), y = p.y() + ((k & 2) ? g : -g);
    const std::vector<std::vector<double>> e = port.irradiance(x, y, L_o, T, samples, shifts_);
    for (std::size_t f = 0; f < films.size(); ++f)
      for (std::size_t i = 0; i < signal[f].size(); ++i) signal[f][i] += 0.25 * e[f][i];
  }
  return signal;
}

std::vector<double> TracedSource::channel_signal(const Point2& p, double L_o, const AnalyzerFilm& film) const {
  if (scene_.sensor.geometry == "lensed") return lensed_signal(p, L_o, film);
  return bare_signals(p, L_o, {film})[0];
}

std::vector<std::vector<double>> TracedSource::channel_signals(const Point2& p, double L_o,
                                                               const std::vector<AnalyzerFilm>& films) const {
  if (scene_.sensor.geometry != "lensed") return bare_signals(p, L_o, films);
  std::vector<std::vector<double>> signals;
  for (const AnalyzerFilm& f : films) signals.push_back(lensed_signal(p, L_o, f));
  return signals;
}

Polarization TracedSource::polarization(const SourceView&, const SourcePose& pose) const {
  return {sensor_polarization_angle_deg(pose.theta_R_deg, polarizer_axis_rig_deg()), degree_of_polarization()};
}

TracedChannel TracedSource::channel(const SourceView& rig, double theta_R_deg, int m) const {
  const Point2 p = photodiode_positions(rig.sensor.ring, rig.eccentricity, theta_R_deg)[static_cast<std::size_t>(m)] -
                   port_centre(rig.eccentricity);
  const CalibrationParams& truth = rig.sensor.truth;
  // The sensor frame is the scene frame turned by −θ_R (both seen from above; the table turns
  // anticlockwise seen from below): a sensor-frame angle φ is at φ − θ_R in the scene.
  const AnalyzerFilm film{film_axis_from_alpha_deg(truth, m) - theta_R_deg, 1.0 + truth.kd[static_cast<std::size_t>(m)]};
  const double theta = sensor_polarization_angle_deg(theta_R_deg, polarizer_axis_rig_deg());
  return {to_scene(p), film, channel_response(truth, m, theta, degree_of_polarization())};
}

void TracedSource::irradiance(const SourceView& rig, const SourcePose& pose, std::span<double> E) const {
  for (int m = 0; m < 6; ++m) {
    const TracedChannel c = channel(rig, pose.theta_R_deg, m);
    std::vector<double> e = channel_signal(c.p_scene, rig.settings.cos4.L_o, c.film);
    for (double& x : e) x /= c.bracket;
    for (std::size_t k = 0; k < e.size(); ++k) E[k * 6 + static_cast<std::size_t>(m)] = e[k];
  }
}

void TracedSource::irradiance_over_turn(const SourceView& rig, const CsTurn& turn, std::span<double> E,
                                        const Progress& progress) const {
  const int n = turn.steps(), S = shifts();
  std::vector<TracedChannel> channels(static_cast<std::size_t>(6 * n));
  for (int mk = 0; mk < 6 * n; ++mk) channels[static_cast<std::size_t>(mk)] = channel(rig, turn.theta_R_deg(mk % n), mk / n);
  // Channels whose photodiodes sit at one point (to 1 pm: a coaxial rig turning in steps that
  // divide the ring's spacing brings every channel to the same points) share the port's rays
  // and radiance, at the point of the first of them.
  std::map<std::pair<long long, long long>, std::size_t> group_at;
  std::vector<std::vector<int>> groups;
  for (int mk = 0; mk < 6 * n; ++mk) {
    const Point2& p = channels[static_cast<std::size_t>(mk)].p_scene;
    const auto [it, added] = group_at.try_emplace({std::llround(p.x() * 1e9), std::llround(p.y() * 1e9)}, groups.size());
    if (added) groups.emplace_back();
    groups[it->second].push_back(mk);
  }
  // Isolated: a sweep's outer loop must not run another grid point on this thread while it
  // waits here, since that point would share this thread's scratch.
  tbb::this_task_arena::isolate([&] { tbb::parallel_for(std::size_t{0}, groups.size(), [&](std::size_t g) {
    const std::vector<int>& members = groups[g];
    std::vector<AnalyzerFilm> films;
    for (int mk : members) films.push_back(channels[static_cast<std::size_t>(mk)].film);
    const std::vector<std::vector<double>> e =
        channel_signals(channels[static_cast<std::size_t>(members[0])].p_scene, rig.settings.cos4.L_o, films);
    for (std::size_t j = 0; j < members.size(); ++j) {
      const std::size_t mk = static_cast<std::size_t>(members[j]);
      for (int sh = 0; sh < S; ++sh) {
        double x = e[j][static_cast<std::size_t>(sh)];
        x /= channels[mk].bracket;
        E[static_cast<std::size_t>(sh) * static_cast<std::size_t>(6 * n) + mk] = x;
      }
    }
    progress.advance(static_cast<long long>(members.size()));
  }); });
}

namespace {
// The traced sphere along a camera's views. Frames: the rig frame (source.h: x, y in the
// photosensitive plane, angles anticlockwise seen from below; z = x × y pointing down) and the
// scene frame (scene.h: z up, seen from above) share the x-axis; y and z are reversed. The map
// (x, y, z) → (x, −y, −z) is the half-turn about x (a rotation, its own inverse): a rig-plane
// offset (x, y) is the scene's (x, −y) (to_scene), a view looking up (v_z < 0) looks up in the
// scene (z > 0), and the port film's scene axis ψ lies at −ψ in the rig frame
// (polarizer_axis_rig_deg).
Vec3 rig_to_scene(const Vec3& v) { return {v[0], -v[1], -v[2]}; }
Vec3 scene_to_rig(const Vec3& v) { return {v[0], -v[1], -v[2]}; }

class TracedPortViews final : public LightAlongViews {
 public:
  TracedPortViews(const SphereTracer& tracer, const SphereSolution& solution, const SceneSpec& scene)
      : tracer_(tracer), solution_(solution), film_(scene.port.polarizer), h_(scene.sensor.L_o),
        zp_(scene.port_plane_z()), a_(scene.port.radius()) {
    const double psi = deg2rad(film_.axis_deg);
    axis_ = {std::cos(psi), std::sin(psi), 0};
  }
  void along(std::span<const Vec3> views, std::span<ViewLight> out) const override {
    for (std::size_t i = 0; i < views.size(); ++i) out[i] = light(views[i]);
  }

 private:
  ViewLight light(const Vec3& view) const {
    const Vec3 up = rig_to_scene(view);  // from the pinhole towards the light, scene frame
    if (!(up[2] > 0)) return {};         // not looking up into the port
    // The pinhole P = (0, 0, z_p − h): the ray meets the port plane at P + (h/up_z)·up.
    const double t = h_ / up[2];
    const Vec3 Q{t * up[0], t * up[1], zp_};
    if (Q[0] * Q[0] + Q[1] * Q[1] > a_ * a_) return {};  // the dark surround of the port
    const double L = tracer_.radiance(solution_, tracer_.first_hit(Q, up, 0.0));
    if (!(L > 0)) return {};
    // Forwards, as the light goes: along k = −up through the horizontal port film.
    PolarizedRay ray = unpolarized_ray(vec3::mul(up, -1.0), L);
    pass_sheet_polarizer(ray, {0, 0, 1}, axis_, film_.tau_M, film_.tau_m);
    const double S0 = ray.S[0], p = std::hypot(ray.S[1], ray.S[2]);
    if (!(p > 0)) return {S0, {0, 0, 0}, 0.0};
    // The E-vector at χ = ½·atan2(S2, S1) from x̂ towards ŷ = k × x̂ (the ray's frame).
    const double chi = 0.5 * std::atan2(ray.S[2], ray.S[1]);
    const Vec3 y_hat = vec3::cross(ray.k, ray.x_hat);
    const Vec3 e = vec3::unit(vec3::add(vec3::mul(ray.x_hat, std::cos(chi)), vec3::mul(y_hat, std::sin(chi))));
    return {S0, scene_to_rig(e), std::min(1.0, p / S0)};
  }

  const SphereTracer& tracer_;
  const SphereSolution& solution_;
  PolarizerFilm film_;
  double h_, zp_, a_;
  Vec3 axis_;
};
}  // namespace

std::unique_ptr<const LightAlongViews> TracedSource::light_along_views(const SourceView&,
                                                                       const SourcePose& pose) const {
  // The solve here, once, before the camera's parallel loops ask along() for views.
  auto light = std::make_unique<TracedPortViews>(*tracer_, solution(), scene_);
  const double c = std::cos(deg2rad(pose.theta_R_deg)), s = std::sin(deg2rad(pose.theta_R_deg));
  light->axes = {{c, s, 0}, {s, -c, 0}, {0, 0, -1}};
  return light;
}

}  // namespace polrig
