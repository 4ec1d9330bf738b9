#pragma once
// Kinematics of the calibration rig in the photosensitive plane (spec §3).
//
// Frame: origin at the rotary-table centre O_R; angles anticlockwise seen looking into the port
// from the sensor. The table turns the sensor anticlockwise by θ_R: P(θ_R) = Rot(θ_R)·P(0).
#include <array>

#include <Eigen/Core>

namespace polrig {

struct Eccentricity {
  double L_IS = 0.05;     // port centre offset from O_R, mm
  double alpha_IS = 0.0;  // its direction, degrees
  double L_S = 0.02;      // sensor centre offset from O_R at θ_R = 0, mm
  double alpha_S = 70.0;  // its direction, degrees
};

// Where the photodiodes sit on the sensor: a ring of radius L_photo around O_S, photodiode m at
// angle β_m from the x-axis (which runs from O_S through photodiode 1 at θ_R = 0).
struct PhotodiodeRing {
  double L_photo = 14.0;  // mm
  std::array<double, 6> beta_deg{0, -60, -120, -180, -240, -300};
};

using Point2 = Eigen::Vector2d;

Point2 port_centre(const Eccentricity& e);
Point2 sensor_centre(const Eccentricity& e, double theta_R_deg);
// P_m(θ_R) for m = 1..6 (index 0..5).
std::array<Point2, 6> photodiode_positions(const PhotodiodeRing& ring, const Eccentricity& e,
                                           double theta_R_deg);

// Rot(θ_R) as cos/sin, so hot loops over many rigs share one table of table angles.
struct TableRotation {
  double c = 1.0, s = 0.0;
  static TableRotation at_deg(double theta_R_deg);
  Point2 operator*(const Point2& p) const { return {c * p.x() - s * p.y(), s * p.x() + c * p.y()}; }
};

}  // namespace polrig

namespace polrig {

// Polarization angle θ seen by the sensor, in [0°, 180°).
//
// The sensor's own frame (its film axes and its reference direction, film 1 at 0°) is drawn
// seen from above, looking down onto its top face, as in the paper's Fig. 1c; the rig frame is
// seen from the sensor looking up into the port. The two are mirror images sharing the x-axis.
// A port polarizer at ψ_P in the rig frame, with the sensor turned by θ_R, is therefore at
// θ = θ_R − ψ_P in the sensor's frame: the polarization angle follows the table angle, as in
// the paper (§3.2) and as the signs of Table 2's α require.
double sensor_polarization_angle_deg(double theta_R_deg, double polarizer_deg);

}  // namespace polrig
