#pragma once
// What the six-photodiode sensor on its turntable sees of the sky (spec sky-and-compasses.md
// §1.3): it looks along its axis Z_s (the zenith when level); the sky is at infinity, so every
// channel sees the same light (no parallax, no eccentricity bias).
//
// Frames and senses (docs/physics.md §1 and §10): the sensor's θ runs from its x-axis X_s towards
// Y_s, anticlockwise seen from above (polrig's sensor frame, the mirror of the spec's "looking
// into the source"). The table turns the sensor clockwise seen from above by θ_R (the rig frame,
// anticlockwise seen from the sensor looking up), so a fixed light is seen at θ = θ_R + const.
//   level:   X_s at geographic azimuth A_x = mount_deg + θ_R, Y_s = ẑ × X_s;
//   tilted:  the table and the sensor on it, [X_s Y_s Z_s] = [X_0 Y_0 ẑ]·Rx(pitch)·Ry(roll)·Rz(−θ_R)
//            with X_0 at azimuth mount_deg (pitch about X_0, Y_0 up for pitch > 0; roll about Y_0,
//            X_0 down for roll > 0, as spec §1.5's SPAN angles).
//   θ = atan2(e·Y_s, e·X_s) mod 180°, e the sky's E-vector along Z_s; d = the sky's DoP there.
// Level, with the zenith E-vector at azimuth A_s ± 90°: θ = mount_deg + θ_R − A_s ∓ 90°, which
// falls as the sun's azimuth rises (spec's sense: +ΔA_s, spec §1.4).
#include "polrig/sky/sky.h"

namespace polrig {

// The sensor's outdoor mount (the rig's `sky.*` mount keys).
struct SkyMount {
  double mount_deg = 0;      // geographic azimuth of the sensor's 0° axis at table angle 0
  double roll_deg = 0;       // table tilt about Y_0 (X_0 down for > 0)
  double pitch_deg = 0;      // table tilt about X_0 (Y_0 up for > 0)
  double time_offset_s = 0;  // true time of a stop minus its nominal time: the sky at t + offset
  bool cone = false;         // average over the lens's field instead of a point sample
  // The field half-angle: atan(0.65 mm/50 mm), half the photodiode over the focal length,
  // assuming the photodiode at the lens focus (spec §1.3).
  double field_half_angle_deg = 0.74475;
  double E0_Wm2 = 1.0;  // each channel's irradiance for the sky radiance 1 (the zenith, uniform)
};

struct SkyView {
  double theta_deg = 0;  // sensor frame, [0°, 180°)
  double d = 0;          // degree of linear polarization
  double E_Wm2 = 0;      // every channel's irradiance: E0·radiance
};

// The E-vector e's angle in a sensor frame (X_s, Y_s): atan2(e·Y_s, e·X_s), from X_s towards Y_s
// (anticlockwise seen from above for a sensor looking up: polrig's sensor frame), in radians,
// (−π, π]. Every model of a sensor looking at the sky reads its angle here.
double sensor_frame_angle_rad(const Vec3& e, const Vec3& X_s, const Vec3& Y_s);

// The sensor's axes [X_s Y_s Z_s] in ENU at table angle θ_R (the header's formula): what a
// camera on the same mount uses as its frame l.
struct SensorAxesEnu {
  Vec3 x, y, z;
};
SensorAxesEnu sensor_axes_enu(const SkyMount& mount, double theta_R_deg);

// The sky seen at table angle θ_R, t_s seconds after sky.first_stop (looking along the sun's line
// the light is unpolarized: d = 0, θ = 0).
SkyView sky_seen(const Sky& sky, const SkyMount& mount, double theta_R_deg, double t_s);

// The same with the sun already computed (a caller that caches the sun's track).
SkyView sky_seen(const SunPosition& sun, const SkyModel& model, const SkyMount& mount,
                 double theta_R_deg);

}  // namespace polrig
