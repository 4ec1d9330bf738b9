#pragma once
// Polarization angle from the three pair voltages (spec §2 Eq. 2; §4 Eqs. 16–19) and the
// section algorithm. With theory parameters Eqs. 16–19 reduce to Eq. 2.
#include <array>
#include <string>

#include "polrig/device/params.h"
#include "polrig/device/electronics.h"

namespace polrig {

struct PairAngle {
  double theta_deg;  // in [0°, 180°)
  double d;          // degree of polarization the pair implies (≥ 0)
};

enum class PairInversion {
  Atan2,               // 2θ = atan2(d·sin2θ, d·cos2θ)
  ArctanSignExtension  // the paper's: θ = ½·arctan over 90°, +90° where the implied d < 0
};

// θ_ab and d_ab from voltages a and b (0-based pair indices, a ≠ b). Each pair i gives, with
// A_i = 10^((V_i − k_i)/(kv_i·v_dec)) and X = d·cos2θ, Y = d·sin2θ,
//   (1+kd_j)·(X·cosα_j − Y·sinα_j) + A_i·(1+kd_h)·(X·cosα_h − Y·sinα_h) = A_i − 1.
PairAngle pair_angle(const CalibrationParams& p, const Electronics& e,
                     const std::array<double, 3>& V, int a, int b,
                     PairInversion method = PairInversion::Atan2);

struct SensorAngles {
  PairAngle theta12, theta13, theta23;
  double theta_sec_deg;
  int section;  // 0..5, centred on 0°, 30°, …, 150°
};

// The section whose centre (a bad point) is nearest θ: ⌊(θ + 15°)/30°⌋ mod 6. Throws
// std::invalid_argument for a non-finite θ.
int section_of(double theta_deg);
// The voltage (0-based) with zero slope at the centre of a section: V1, V3, V2, V1, V3, V2.
// Throws std::out_of_range outside 0..5.
int bad_voltage_of(int section);

// θ12, θ13, θ23 and the section algorithm's θ_sec: θ12 picks the section, θ_sec is the pair
// that leaves out that section's bad voltage. Throws std::invalid_argument when θ12 is not
// finite (voltages far outside what the parameters can give: 10^((V − k)/(kv·v_dec)) overflows).
SensorAngles sensor_angles(const CalibrationParams& p, const Electronics& e,
                           const std::array<double, 3>& V,
                           PairInversion method = PairInversion::Atan2);

// The largest |V| a reading may have: no ADC polrig models reads beyond its reference, and a rig
// accepts electronics.vref_V up to 100 V.
inline constexpr double kMaxAdcVolts = 100.0;
// 10^x overflows or underflows a double beyond about ±308 decades: a pair's light ratio that
// large is not light.
inline constexpr double kMaxDecades = 300.0;

// Why V (volts) is no reading of any ADC ("column 'V2': 150 V is outside any ADC's range
// (|V| ≤ 100 V)"), or "" when every |V_i| ≤ kMaxAdcVolts.
std::string adc_range_problem(const std::array<double, 3>& V);

// sensor_angles of measured voltages (`polrig apply`): the angles and the d of the pair the
// section algorithm used, or `problem` saying why there are none: a voltage outside any ADC's
// range, one more than kMaxDecades of light ratio from its pair's offset, or angles or d that
// are not finite with these parameters.
struct MeasuredAngles {
  SensorAngles angles{};
  double d = 0;
  std::string problem;  // "" when the angles are valid
};
MeasuredAngles measured_angles(const CalibrationParams& p, const Electronics& e,
                               const std::array<double, 3>& V,
                               PairInversion method = PairInversion::Atan2);

}  // namespace polrig
