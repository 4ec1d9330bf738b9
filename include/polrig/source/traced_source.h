#pragma once
// The traced source as a rig's light (source.model: traced): the scene's sphere is solved once,
// and each channel's signal is the port integral of traced_port.h through the films (and lens)
// in front of its photodiode.
//
// The quasi-random samples are the same for every photodiode and pose; each of `shifts`
// independent random shifts gives a complete estimate, so studies run once per shift and report
// the spread of the shifts as standard errors.
#include <filesystem>
#include <exception>
#include <memory>
#include <mutex>
#include <vector>

#include "polrig/progress.h"
#include "polrig/geometry/geometry.h"
#include "polrig/source/scene.h"
#include "polrig/source/source.h"

namespace polrig {

// The rig frame is seen from the sensor looking up, the scene frame from above (z up): mirror
// images sharing the x-axis. A rig-plane offset from the port centre in scene coordinates:
inline Point2 to_scene(const Point2& rig) { return {rig.x(), -rig.y()}; }

class SphereTracer;
struct SphereSolution;

// A channel's analyzer film: its transmission axis in the scene frame (degrees from +x towards
// +y) and its polarizing efficiency e = (τM − τm)/(τM + τm) (1 + kd_m of Eq. 15).
struct AnalyzerFilm {
  double axis_deg = 0;
  double efficiency = 1;
};

// What a traced channel's effective irradiance is computed from at a pose: its photodiode (or
// lens axis) in the scene frame, port-centred, the analyzer film turned with the table, and
// Eq. 15's normal-incidence bracket at the pose's (θ, d).
struct TracedChannel {
  Point2 p_scene;
  AnalyzerFilm film;
  double bracket = 1;
};

class TracedSource final : public Source {
 public:
  explicit TracedSource(const SceneSpec& scene);
  ~TracedSource() override;

  const SceneSpec& scene() const { return scene_; }

  // --- Source: the port film sets θ and d; each channel's signal is traced (per shift).
  std::string_view kind() const override { return "traced"; }
  unsigned flags() const override { return kStandardErrors | kStokesAlongViews; }
  int shifts() const override { return shifts_; }
  std::optional<double> fixed_degree_of_polarization() const override { return degree_of_polarization(); }
  void prepare(const Progress& progress) const override { solve(progress); }
  // "solved" or "loaded" (the installed sphere cache, sphere_cache.h) and its file, once solved.
  std::optional<LightOrigin> origin() const override;
  Polarization polarization(const SourceView& rig, const SourcePose& pose) const override;
  // channel_signal of each channel (its analyzer the film the truth's α_m and kd_m stand for,
  // turned with the table) divided by its bracket: obliquity effects included.
  void irradiance(const SourceView& rig, const SourcePose& pose, std::span<double> E) const override;
  // Channels that sit at one point (to 1 pm) over the turn share the port's rays and radiance.
  void irradiance_over_turn(const SourceView& rig, const CsTurn& turn, std::span<double> E,
                            const Progress& progress = {}) const override;
  TracedChannel channel(const SourceView& rig, double theta_R_deg, int m) const;

  // A camera looking up into the port (docs/physics.md §13): its pinhole on the port's axis
  // scene().sensor.L_o below the port plane (the scene's photosensitive plane). Each view is a ray
  // from the pinhole; where it crosses the port plane inside the port it goes on to the sphere's
  // first hit (SphereTracer::first_hit), whose radiance (SphereTracer::radiance) travels back
  // along k = −view through the port film at its own incidence (pass_sheet_polarizer): S0 is the
  // radiance after the film, W/m²/sr (the tracer's unit; no geometric factor: the camera applies
  // its own cos⁴γ), e the film's transmitted E-vector and d its degree. Elsewhere (outside the
  // port, or not looking up) S0 = 0. No random sampling: one ray per view, the same bits for any
  // thread count. Solves the sphere first, if that has not been done. The camera's axes at θ_R
  // are Cos4PortSource's: X = Rot(θ_R)·x̂, Y = −Rot(θ_R)·ŷ, Z = −ẑ. The result reads this
  // source's tracer and solution (const, thread-safe queries): use it while the source lives.
  std::unique_ptr<const LightAlongViews> light_along_views(const SourceView& rig,
                                                           const SourcePose& pose) const override;

  // The signal of one channel, per shift (0 … shifts() − 1): the flux reaching its photodiode
  // through the port film, the channel's analyzer film and, lensed, the blue filter and the lens,
  // per unit area, divided by the two films' gains for unpolarized light, g_up·g_up'. Each ray
  // carries its Stokes vector through the films (O-type sheet polarizers at their oblique
  // incidence) and the lens's faces (Fresnel s and p), each in its own frame
  // (optics/polarized_ray.h). At normal incidence under a uniform port the signal is
  // E·[1 + d·e·cos 2(ψ − β)], Eq. 15's bracket times the irradiance.
  //
  // `p` is the photodiode's centre (bare) or its channel's lens axis (lensed), port-centred, in
  // the scene frame (mm). Bare (sensor.geometry: bare): the film lies on the photodiode, L_o
  // below the port (2 × 2 Gauss points over its square). Lensed: the film is L_o below the port,
  // then film_to_lens, the plano-convex lens and lens_to_photodiode.
  std::vector<double> channel_signal(const Point2& p, double L_o, const AnalyzerFilm& film) const;
  // channel_signal for several films at one point, [film][shift], each bit-identical to its
  // channel_signal; bare, the port's rays and radiance are computed once for all films.
  std::vector<std::vector<double>> channel_signals(const Point2& p, double L_o,
                                                   const std::vector<AnalyzerFilm>& films) const;

  // The port film: degree of polarization, and its axis in the rig frame (the scene's axis,
  // mirrored: −axis_deg).
  double degree_of_polarization() const { return scene_.port.polarizer.degree_of_polarization(); }
  double polarizer_axis_rig_deg() const { return -scene_.port.polarizer.axis_deg; }

  // Solves the sphere now (once; later calls return at once), reporting to `progress`. Otherwise
  // the first signal solves it, silently. The sphere cache's solution of the same scene, when
  // the installed cache holds one, is taken instead: the same bits (solve_sphere).
  void solve(const Progress& progress) const;

  // Rays traced by the sphere solve, and its time (for speed reports).
  long long solve_rays() const;
  double solve_seconds() const;

 private:
  // The sphere is solved on first use, once, whichever thread asks first.
  const SphereSolution& solution() const;
  std::vector<std::vector<double>> bare_signals(const Point2& p, double L_o,
                                                const std::vector<AnalyzerFilm>& films) const;
  std::vector<double> lensed_signal(const Point2& p, double top, const AnalyzerFilm& film) const;

  SceneSpec scene_;
  int shifts_ = 8;
  std::unique_ptr<SphereTracer> tracer_;
  mutable std::unique_ptr<SphereSolution> solution_;
  mutable double L_ref_ = 0;  // mean radiance seen through the port: the control variate
  mutable std::once_flag solved_;
  mutable std::exception_ptr solve_failure_;  // the solve's error, rethrown to every caller
  mutable LightOrigin origin_;                // set with solution_
};

}  // namespace polrig
