#pragma once
// The one seam between a rig and its light. Every source model implements Source; the
// simulation, the studies and the commands ask a source what it can do (flags()) and never which
// model it is, as pbrt-v4's integrators call Light::SampleLi and Mitsuba 3's ask an emitter's
// flags. make_source (source/factory.cpp) is the only place that names the models.
//
// Frames: the table angle θ_R and the eccentricity are in the rig frame (geometry/geometry.h);
// the polarization angle θ a source reports is in the sensor's frame (θ = θ_R − ψ_P for a port
// polarizer at ψ_P), as Eq. 15 takes it.
#include <array>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

#include "polrig/device/sensor.h"
#include "polrig/geometry/geometry.h"
#include "polrig/geometry/turn.h"
#include "polrig/progress.h"
#include "polrig/source/cos4.h"
#include "polrig/source/scene.h"
#include "polrig/source/sky_settings.h"
#include "polrig/vec3.h"

namespace polrig {

// The rig's source settings, as the `source.*` rig keys write them. A Source keeps only what is
// expensive to make (a traced sphere's solve) and reads these at every query, so that --set,
// sweeps and rig copies change them without making a new source.
struct SourceSpec {
  std::string model = "cos4";  // the kind make_source builds (rig key source.model)
  Cos4Source cos4;             // L_o (every model: port plane to photosensitive plane), E_0 (cos4)
  double polarizer_deg = 0.0;  // port polarizer axis ψ_P in the rig frame (cos4)
  std::string scene;           // traced: the scene file, an absolute path once loaded
  SkySettings sky;             // sky: site, time, sky model and the sensor's mount (sky.* keys)
};

// What a source reads of the rig at a pose: the sensor (its ring, its films through the true
// parameters, the d it is told), the eccentricity and the source settings.
struct SourceView {
  const SensorSpec& sensor;
  const Eccentricity& eccentricity;
  const SourceSpec& settings;
};

// A pose of the table: its angle and the time since the first stop (time-dependent sources).
struct SourcePose {
  double theta_R_deg = 0;
  double t_s = 0;
};

// The polarization the sensor sees: angle θ in the sensor frame, [0°, 180°), and degree d.
struct Polarization {
  double theta_deg = 0;
  double d = 0;
};

// The light arriving along one view, in the rig frame (below): no Stokes reference axis crosses
// the seam, only the E-vector's direction.
struct ViewLight {
  double S0 = 0;  // radiance along the view, in the source's intensity unit (≥ 0)
  Vec3 e{};       // the E-vector's direction: unit, ⊥ the view; zero when d = 0
  double d = 0;   // degree of linear polarization, [0, 1]
};

// An instrument's frame at a pose: its axes X, Y, Z (right-handed, Z its optical axis, towards
// the light) as unit vectors in the rig frame.
struct InstrumentAxes {
  Vec3 x{1, 0, 0}, y{0, 1, 0}, z{0, 0, 1};
};

// The light along many views at one pose (Source::light_along_views): what is expensive per pose
// (the sun's place) is computed once when it is made; along() is thread-safe.
//
// The rig frame, 3-D: for the sphere rig (cos4, traced) x and y are geometry/geometry.h's rig
// frame in the photosensitive plane (angles anticlockwise seen from the instrument looking up
// into the port) and z = x × y points down, from the port towards the instrument (the light's
// direction); for the sky, ENU (x east, y north, z up).
class LightAlongViews {
 public:
  virtual ~LightAlongViews() = default;
  // The instrument's frame at the pose: for the sphere rig a camera turned by the table as the
  // six-photodiode sensor is (docs/physics.md §1: a port polarizer at ψ_P is seen on the axis at
  // θ_R − ψ_P from X towards Y); under the sky, sky/sensor_view.h's [X_s Y_s Z_s].
  InstrumentAxes axes;
  // The light arriving along each view: views[i] a unit vector in the rig frame, from the
  // instrument towards where the light comes from; out.size() == views.size().
  virtual void along(std::span<const Vec3> views, std::span<ViewLight> out) const = 0;
};

// Where a source's once-only expensive part came from, for the manifest: the traced sphere
// "solved" here or "loaded" from the sphere cache (sphere_cache.h), and the cache file read or
// written ("" when none was).
struct LightOrigin {
  std::string sphere;
  std::string cache_file;
};

class Source {
 public:
  // What a source can do; callers choose their path and their columns from these.
  enum Flag : unsigned {
    // Several independent estimates ("shifts", shifts() > 1): results carry standard errors.
    kStandardErrors = 1u << 0,
    // Eq. 6's closed-form CS constant exists (eq6_log_ratio).
    kClosedFormEq6 = 1u << 1,
    // The light changes during a run (the sky: its angle and degree drift with the sun);
    // queries carry the time since the first stop.
    kTimeDependent = 1u << 2,
    // The ideal, eccentricity-free irradiance is uniform (cos⁴'s E_0): the CS study needs no
    // coaxial reference, and ΔV is Eq. 5's bias of the pose's irradiances alone.
    kUniformReference = 1u << 3,
    // The polarized radiance along any view at the instrument (light_along_views): what a pixel
    // array (the DoFP camera) sees.
    kStokesAlongViews = 1u << 4,
  };

  virtual ~Source() = default;

  // The model's name, as make_source knows it (for manifests and messages, never to branch on).
  virtual std::string_view kind() const = 0;
  virtual unsigned flags() const = 0;
  bool has(Flag f) const { return (flags() & f) != 0; }
  // Independent estimates per query (1 unless kStandardErrors).
  virtual int shifts() const { return 1; }
  // A degree of polarization the source sets itself (the traced port film), which the rig's
  // device.d must then equal; none when the rig's device.d is the light's.
  virtual std::optional<double> fixed_degree_of_polarization() const { return std::nullopt; }
  // The light's d that the rig's device.d must equal, from the rig's settings: the fixed d above
  // by default; a sky's d at the first stop (it changes during the run, and device.d is then the
  // d_a that calibrate decouples with). None when the rig's device.d is the light's.
  virtual std::optional<double> rig_degree_of_polarization(const SourceView&) const {
    return fixed_degree_of_polarization();
  }

  // Once-only expensive work (the traced sphere solve), reported to `progress`; a later call
  // returns at once. Queries do it silently if it has not been done. No-op by default.
  virtual void prepare(const Progress& progress) const;
  // How the expensive part was made, once prepare (or a query) has made it; null before, and for
  // a source with none. Never starts the work.
  virtual std::optional<LightOrigin> origin() const { return std::nullopt; }

  // The polarization the sensor sees at the pose.
  virtual Polarization polarization(const SourceView& rig, const SourcePose& pose) const = 0;
  // Each channel's (effective) irradiance at the pose, W/m², per shift: E[shift·6 + m],
  // E.size() = 6·shifts(). An effective irradiance is the channel's signal divided by Eq. 15's
  // normal-incidence bracket at polarization(), so that the device model, which applies the
  // bracket, reproduces the signal.
  virtual void irradiance(const SourceView& rig, const SourcePose& pose, std::span<double> E) const = 0;
  // The irradiance of the ideal, eccentricity-free measurement that V_ideal and ΔV refer to:
  // by default the mean over shifts of irradiance() with port and sensor on the table's axis;
  // a kUniformReference source returns its uniform level.
  virtual std::array<double, 6> ideal_irradiance(const SourceView& rig, const SourcePose& pose) const;

  // Irradiance at every step of a CS turn (the sweep's hot loop) into the caller's buffer,
  // E[(shift·6 + m)·n + k], E.size() = 6·shifts()·n, up to one positive factor per shift common
  // to all channels and steps (the CS study uses ratios only). The turn is at one time, t = 0.
  // By default irradiance() at each step, advancing `progress` by 6 per step.
  virtual void irradiance_over_turn(const SourceView& rig, const CsTurn& turn, std::span<double> E,
                                    const Progress& progress = {}) const;

  // Eq. 5's logarithm over a CS turn (the sweep's hot loop): ln(E_j/E_h) of pair i at step k into
  // out[i·n + k], out.size() = 3·n, of the first shift's irradiances. By default from
  // irradiance_over_turn, its ratios and log_array (pair_log_ratios); a source may override it
  // with a closed form of the same quantity, as exact or more.
  virtual void log_ratio_over_turn(const SourceView& rig, const CsTurn& turn, std::span<double> out) const;

  // The light along views at the pose, with kStokesAlongViews; throws std::logic_error for a
  // source without it.
  virtual std::unique_ptr<const LightAlongViews> light_along_views(const SourceView& rig,
                                                                   const SourcePose& pose) const;

  // Eq. 6's light term where kClosedFormEq6: ΔV_mr,i ≈ 2·kv_i·v_dec·eq6_log_ratio(i). Throws
  // std::logic_error for a source without the flag.
  virtual double eq6_log_ratio(const SourceView& rig, int pair) const;
  // eq6_log_ratio of the three pairs, the same values (every sweep point needs all three).
  virtual std::array<double, 3> eq6_log_ratios(const SourceView& rig) const;
};

// ln(E_j/E_h) of the three pairs from channel irradiances E[m·n + k] (n steps) into
// out[i·n + k]: the ratios, then their logarithms in vectors (log_array).
void pair_log_ratios(const double* E, int n, double* out);

// Reads the scene file a traced source names (io/scene_yaml's load_scene, resolved against the
// rig file): the factory stays below io/, and a caller decides how errors are reported.
using SceneLoader = std::function<SceneSpec(const std::string& scene_path)>;

// A source's setting that the factory refuses: the rig key and what was expected.
struct SourceSettingError : std::runtime_error {
  SourceSettingError(std::string key_, const std::string& message)
      : std::runtime_error(message), key(std::move(key_)) {}
  std::string key;
};

// The source of `settings.model`: "cos4" or "traced" (whose scene `load_scene` reads). The only
// place that names the models. Throws SourceSettingError for an unknown model or a missing
// setting; the loader's own exceptions pass through.
std::shared_ptr<const Source> make_source(const SourceSpec& settings, const SceneLoader& load_scene = {});
// The models make_source knows, for the source.model key's check and its documentation.
std::span<const std::string_view> source_kinds();
// The cos⁴ source (shared; it holds nothing): a default Rig's.
std::shared_ptr<const Source> cos4_source();

}  // namespace polrig
