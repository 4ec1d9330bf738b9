#pragma once
// Positioning from the sun's zenith angle over an observation window, and the heading at the fix
// (W16 Eqs. 15–18, spec sky-and-compasses.md §3.4; docs/physics.md "Position from the sun's
// zenith angle").
//
// Frames and senses (spec §0): latitude L north positive, longitude λ east positive (degrees at
// the interface, radians inside); the sun's azimuth β is geographic (clockwise from north); hour
// angles run westwards. The sun vector of a sighting is in the frame l of a LEVEL camera (Z_l up,
// X_l, Y_l anticlockwise seen from above; compass/orientation.h): θ_S = acos(s_z/|s|), and W16's
// clockwise α_S = −atan2(s_y, s_x), so ψ = β − α_S = β + atan2(s_y, s_x) (camera_heading_deg).
//
// The model (Eq. 17): cos θ_S(L, λ, t) = sin L·sin δ(t) + cos L·cos δ(t)·cos(GHA(t) + λ), with δ and
// GHA the sun's apparent TOPOCENTRIC declination and Greenwich hour angle of sky/sun.h (ERFA),
// which make this exact for the site they were computed at (sun.h). They depend on the site
// through the parallax (8.8″) and diurnal aberration, so the fit evaluates them along a SunTrack
// built at the current estimate and re-linearizes (a new track at the new estimate) until the
// estimate moves less than `site_tolerance_m`: the residuals at the end are those of the exact
// ephemeris at the fix (< 1e-6° from sun_position, a SunTrack's bound), the Jacobian analytic.
#include <array>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/sky/sun.h"
#include "polrig/vec3.h"

namespace polrig {

// One zenith-angle sighting: θ_S measured at `utc`, with a weight w ≥ 0 in Σ w·r² (0 leaves it out).
struct ZenithSighting {
  UtcTime utc;
  double zenith_deg = 0;
  double weight = 1;
};

// Work is bounded by counts, never by time (as calib/fit.h's FitOptions).
struct PositionOptions {
  SunSettings sun;             // the ephemeris' settings: the same as the data's (refraction, UT1 − UTC)
  int max_iterations = 50;     // Jacobian evaluations over all re-linearizations
  int max_evaluations = 200;   // residual evaluations
  int max_relinearizations = 8;  // SunTracks built at successive estimates
  double site_tolerance_m = 1e-3;  // a re-linearization that moves the estimate less: converged
  double function_tolerance = 1e-13;   // Levenberg–Marquardt's (MINPACK's ftol)
  double parameter_tolerance = 1e-13;  // (xtol)
  // σ_min/σ_max of the Jacobian in metric units (north, east) below this: rank deficient. The ratio
  // is about the spread of the sun's azimuth over the window in radians (1 s of window: ~7e-5).
  double min_singular_ratio = 1e-7;
  double track_node_spacing_s = 1800;  // the SunTrack's nodes (sky/sun.h)
  bool second_root = true;  // look for the mirror root (a start reflected about the sun's track)
  // The sun's δ and GHA from this track for every linearization, instead of a track at each estimate:
  // one linearization, no re-linearizing. For many fits near one site (navigate's PNS, a fix per
  // reading): the topocentric δ and GHA move with the site by the parallax, 8.8″·(distance/R), so a
  // track at a site 100 km away changes θ_S by < 0.14″. Must cover the sightings' times.
  std::shared_ptr<const SunTrack> ephemeris;
};
// Throws std::invalid_argument naming the option and its value.
void check_position_options(const PositionOptions& options);

enum class PositionTermination {
  Converged,       // the fit converged, every direction determined
  NoConvergence,   // an iteration, evaluation or re-linearization limit came first
  RankDeficient,   // the window cannot fix both coordinates (one instant, a degenerate sun track)
  TooFewSightings  // fewer than two sightings with a positive weight
};
// "converged", "no_convergence", "rank_deficient", "too_few_sightings"
std::string_view position_termination_name(PositionTermination t);

// How one root's fit ended (after calib/fit.h's FitSummary and Ceres's Solver::Summary).
struct PositionSummary {
  PositionTermination termination = PositionTermination::TooFewSightings;
  std::string message;        // why it stopped, for the user
  std::string solver_status;  // Eigen's LevenbergMarquardtSpace::Status of the last pass
  double initial_cost_deg2 = std::numeric_limits<double>::quiet_NaN();  // ½·Σ w·r² at the start
  double final_cost_deg2 = std::numeric_limits<double>::quiet_NaN();    // ½·Σ w·r² at the end
  double residual_rms_deg = std::numeric_limits<double>::quiet_NaN();   // √(Σ w·r² / Σ w)
  int iterations = 0, evaluations = 0, relinearizations = 0;
  int sightings = 0;  // used (positive weight)
  int rank = 0;       // of the Jacobian: 2, or less when rank deficient
  double singular_ratio = 0;  // σ_min/σ_max of the Jacobian in metric units (the conditioning)

  bool usable() const { return termination == PositionTermination::Converged; }
  std::string brief_report() const;  // one line: termination, counts, cost, rms, conditioning
};

struct PositionRoot {
  double lat_deg = 0, lon_deg = 0;  // L̂ (geodetic), λ̂ in (−180°, 180°]
  double prior_distance_km = 0;     // great-circle distance to the prior
  // 1σ of north and east (km) and the 1σ ellipse's semi-major axis, from s²·(JᵀWJ)⁻¹ with
  // s² = Σw·r²/(Σw·(N − 2)/N): NaN with two sightings only or without rank 2.
  double sd_north_km = std::numeric_limits<double>::quiet_NaN();
  double sd_east_km = std::numeric_limits<double>::quiet_NaN();
  double sd_major_km = std::numeric_limits<double>::quiet_NaN();
  double corr_north_east = std::numeric_limits<double>::quiet_NaN();  // of the same covariance
  PositionSummary summary;
  Site site(double height_m = 0) const { return {lat_deg, lon_deg, height_m}; }
};

// Both roots (W16's M and M′: mirror images about the sun's ground track); `chosen` is the one
// nearest the prior. The alternative is missing when its search was off, or when its start
// converged onto the chosen root (within 1 km) or failed (then alternative_note says why).
struct PositionFix {
  PositionRoot chosen;
  std::optional<PositionRoot> alternative;
  std::string alternative_note;
  bool usable() const { return chosen.summary.usable(); }
};

// Eq. 17 by Levenberg–Marquardt (Eigen) from the prior, then from the prior's (or the first
// root's) mirror image about the great circle through the first and last sub-solar points. The
// prior's height is the site's height. Failures are data (summary.termination); throws
// std::invalid_argument for a programming error: a prior out of range (site_problem), a zenith
// angle outside [0°, 180°] or not finite, a weight < 0 or not finite, bad options, a time the
// ephemeris refuses.
PositionFix fix_position(std::span<const ZenithSighting> sightings, const Site& prior,
                         const PositionOptions& options = {});

// Eq. 17's model at one instant: θ_S and its partial derivatives (radians per radian) for the
// sun's topocentric declination δ and Greenwich hour angle GHA (radians).
struct ZenithModel {
  double zenith_rad = 0;
  double d_lat = 0, d_lon = 0;  // ∂θ_S/∂L, ∂θ_S/∂λ
};
ZenithModel zenith_model(double dec_rad, double gha_rad, double lat_rad, double lon_rad);

// Eq. 15, the two-sighting fix error (reconstructed, spec §3.4): ε_M = √(ε_γA² + ε_γB²) /
// |sin(α_A − α_B)|, an angle on the Earth, and in km at W16's 111.32 km/°. Infinite when the two
// azimuths coincide (mod 180°). Throws std::invalid_argument for a negative or non-finite error.
struct TwoSightingError {
  double angle_deg = 0;
  double km = 0;
};
inline constexpr double kKmPerDegree = 111.32;  // W16's (the equatorial 6378.137 km·π/180)
TwoSightingError two_sighting_error(double eps_gamma_a_deg, double eps_gamma_b_deg,
                                    double azimuth_a_deg, double azimuth_b_deg);

// The great-circle distance between two sites on a sphere of the IUGG mean radius 6371.0088 km.
inline constexpr double kEarthMeanRadiusKm = 6371.0088;
double great_circle_km(double lat1_deg, double lon1_deg, double lat2_deg, double lon2_deg);

// ---------------------------------------------------------------------------------------------
// The locate core: sun vectors of a level camera → fix and heading (issue 13 §3).
// ---------------------------------------------------------------------------------------------

// One sighting of the sun: its vector in frame l of a level camera (any length > 0) at `utc`.
struct SunSighting {
  UtcTime utc;
  Vec3 sun_camera{};
  double weight = 1;
};

// Per sighting at the fix.
struct LocateSample {
  UtcTime utc;
  double weight = 1;
  double zenith_deg = 0;      // θ_S = acos(s_z/|s|), measured (Eq. 16)
  double zenith_fix_deg = 0;  // the ephemeris' θ_S at the fix (refracted when the settings say so)
  double residual_deg = 0;    // measured − fix
  double alpha_s_deg = 0;     // W16's α_S, clockwise seen from above: −atan2(s_y, s_x), [0°, 360°)
  double beta_deg = 0;        // the sun's geographic azimuth at the fix, [0°, 360°)
  double heading_deg = 0;     // ψ = β − α_S (Eq. 18), [0°, 360°): the geographic azimuth of X_l
};

struct Location {
  PositionFix fix;
  std::vector<LocateSample> samples;  // in the input's order; headings need a usable fix
  double heading_mean_deg = std::numeric_limits<double>::quiet_NaN();  // circular mean (weighted)
  double heading_sd_deg = std::numeric_limits<double>::quiet_NaN();    // RMS deviation from it
};

// The zenith angles of the sightings, then fix_position, then per sighting θ_S and β at the fix
// and the heading. Throws std::invalid_argument for a sun vector that is zero or not finite (naming
// its index), and as fix_position. Without a usable fix the samples' model columns and headings
// are NaN.
Location locate(std::span<const SunSighting> sightings, const Site& prior,
                const PositionOptions& options = {});

}  // namespace polrig
