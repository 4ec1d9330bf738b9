#pragma once
// Heading from one E-vector and the sun (W19 Eqs. 22–25, reconstructed in spec
// sky-and-compasses.md §1.5).
//
// Frames and senses (spec §0):
// - n-frame ENU (x east, y north, z up); the sun's unit vector s_n = (s_E, s_N, s_U).
// - body frame b (SPAN-CPT): X right, Y forward, Z up; the sensor looks along +Z_b.
// - θ_b: the E-vector's angle in the body's X–Y plane, from X_b towards Y_b (anticlockwise seen
//   from above): e_b = (cos θ_b, sin θ_b, 0). It is axial (defined modulo 180°).
// - heading H: clockwise from north seen from above (geographic, as the sun's azimuth A_s);
//   pitch λ: positive nose up, a right-hand rotation about X_b; roll γ: positive right side
//   down, a right-hand rotation about Y_b.  C_b^n = Rz(−H)·Rx(λ)·Ry(γ), R_a the active
//   right-hand rotation about axis a.
//
// Eq. 25: e_b·s_b = 0. With u = Rx(λ)·Ry(γ)·e_b,
//   a = u_x·s_E + u_y·s_N,  b = u_y·s_E − u_x·s_N,  c = −u_z·s_U,
//   a·cos H + b·sin H = c   ⇒   H = atan2(b, a) ± arccos(c/√(a² + b²)),
// where √(a² + b²) = √(1 − u_z²)·cos h_s. Level, H = A_s + θ_b (mod 180°).
#include <optional>
#include <string_view>

#include "polrig/sky/rayleigh.h"
#include "polrig/vec3.h"

namespace polrig {

// The body's attitude apart from its heading, degrees.
struct Tilt {
  double roll_deg = 0;   // γ, right side down positive
  double pitch_deg = 0;  // λ, nose up positive
};

// Failures are data: every solve returns a status.
enum class HeadingStatus {
  Ok,             // two roots
  Clamped,        // |c|/√(a²+b²) exceeded 1 by at most the tolerance (noise): clamped to 1, the
                  // two roots coincide
  SunNearZenithOrVerticalE,  // √(a²+b²) = √(1 − u_z²)·cos h_s below the threshold: the sun
                             // too close to the zenith, or the E-vector (u = Rx(λ)·Ry(γ)·e_b,
                             // in the levelled frame) too close to vertical under a steep tilt,
                             // for Eq. 25 to fix a heading
  Inconsistent    // |c| > √(a²+b²) beyond the tolerance: no heading puts e_b ⊥ s_b
};
std::string_view heading_status_name(HeadingStatus s);  // "ok", "clamped", "sun-near-zenith-or-vertical-e",
                                                        // "inconsistent"
inline bool has_heading(HeadingStatus s) {
  return s == HeadingStatus::Ok || s == HeadingStatus::Clamped;
}

struct HeadingSettings {
  // √(a²+b²) = √(1 − u_z²)·cos h_s below this: no solution. sin 1° ≈ 0.01745: for small tilts
  // a sun above about 89° elevation; at any sun elevation, a levelled E-vector within about
  // 1°/cos h_s of vertical (e.g. pitch 89.5° with θ_b = 90°). The heading's sensitivity to an error ε (rad) in the sun's
  // or the E-vector's direction grows as ε/√(a²+b²), so this caps it at about 57·ε.
  double min_horizontal = 0.01745240643728351;
  // |c|/√(a²+b²) − 1 up to this is clamped (status Clamped); beyond it, Inconsistent. Near the
  // tangent the roots are √(2·excess) rad apart, so 1e-6 moves a root by at most 0.081°.
  double tangent_tolerance = 1e-6;
};

struct HeadingSolution {
  HeadingStatus status = HeadingStatus::Ok;
  double heading_deg = 0;      // the chosen root, clockwise from north, [0°, 360°)
  double heading_alt_deg = 0;  // the other root (equal to heading_deg when Clamped)
  double a = 0, b = 0, c = 0;  // Eq. 25's coefficients
  double sun_forward = 0;      // s_b,y at the chosen root (the sun's forward component, body)
  bool from_prior = false;     // chosen as the root nearest a prior (else: sun in front)
};

// Solves Eq. 25. `sun_enu`: unit vector to the sun (ENU). `aop_body_deg`: θ_b. The choice of
// root: with a prior, the root nearest it (circular distance); without, the root that puts the
// sun in front: the larger s_b·Y_b, the sun's component along the body's forward axis (one root
// has it > 0 and the other < 0 except when the sun lies in the body's X–Z plane).
// Throws std::invalid_argument naming sun_enu when |‖sun_enu‖ − 1| > 1e-9 (check_sun_enu).
HeadingSolution solve_heading(const Vec3& sun_enu, double aop_body_deg, const Tilt& tilt,
                              std::optional<double> prior_deg = std::nullopt,
                              const HeadingSettings& settings = {});

// C_b^n = Rz(−H)·Rx(λ)·Ry(γ) applied to a body vector, and its transpose.
Vec3 body_to_enu(const Vec3& v_b, double heading_deg, const Tilt& tilt);
Vec3 enu_to_body(const Vec3& v_n, double heading_deg, const Tilt& tilt);

// The forward model: what a sensor looking along +Z_b sees of a single-scattering sky
// (sky/rayleigh.h, spec §1.2): v = Z_b in n, e = (s × v)/|s × v|, e_b = C_n^b·e and
// θ_b = atan2(e_b,y, e_b,x) mod 180°; d = P(γ). Undefined (NaN) when v ∥ s.
struct BodySkyView {
  double aop_body_deg = 0;  // θ_b in [0°, 180°)
  double dop = 0;
};
// Throws as solve_heading for a sun_enu that is not a unit vector.
BodySkyView sky_view_body(const Vec3& sun_enu, double heading_deg, const Tilt& tilt,
                          const SkyModel& model = {});
// The precondition of solve_heading and sky_view_body: sun_enu a unit vector within 1e-9, else
// std::invalid_argument naming it and its length.
void check_sun_enu(const Vec3& sun_enu);
// The same from an E-vector already in n (no sky model): θ_b of e_n seen by the body.
double aop_body_deg(const Vec3& e_enu, double heading_deg, const Tilt& tilt);

// H wrapped into [0°, 360°).
double wrap_heading_deg(double deg);
// a − b wrapped into [−180°, 180°).
double heading_difference_deg(double a, double b);

}  // namespace polrig
