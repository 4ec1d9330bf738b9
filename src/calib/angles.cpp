#include "polrig/calib/angles.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include <Eigen/Dense>

#include "polrig/device/sensor.h"
#include "polrig/units.h"

namespace polrig {
namespace {

// One row of the linear system in (X, Y) = (d·cos2θ, d·sin2θ) from pair i (Eqs. 16–19).
struct PairRow {
  Eigen::RowVector2d coeff;
  double rhs;
};
PairRow pair_row(const CalibrationParams& p, const Electronics& e, const std::array<double, 3>& V,
                 int i) {
  const double A = std::pow(10.0, (V[i] - p.k_mV[i] * 1e-3) / (p.kv[i] * e.volts_per_decade));
  const int j = pair_j(i), h = pair_h(i);
  const double aj = deg2rad(p.alpha_deg[j]), ah = deg2rad(p.alpha_deg[h]);
  const double cj = 1.0 + p.kd[j], ch = 1.0 + p.kd[h];
  return {{cj * std::cos(aj) + A * ch * std::cos(ah), -(cj * std::sin(aj) + A * ch * std::sin(ah))},
          A - 1.0};
}

}  // namespace

PairAngle pair_angle(const CalibrationParams& p, const Electronics& e,
                     const std::array<double, 3>& V, int a, int b, PairInversion method) {
  if (a == b || a < 0 || b < 0 || a > 2 || b > 2)
    throw std::invalid_argument("pair_angle needs two distinct voltages 0..2");
  const PairRow ra = pair_row(p, e, V, a), rb = pair_row(p, e, V, b);
  Eigen::Matrix2d M;
  M << ra.coeff, rb.coeff;
  const Eigen::Vector2d rhs(ra.rhs, rb.rhs);
  const Eigen::Vector2d XY = M.partialPivLu().solve(rhs);
  const double X = XY(0), Y = XY(1);

  if (method == PairInversion::Atan2)
    return {wrap_axis_deg(rad2deg(0.5 * std::atan2(Y, X))), std::hypot(X, Y)};

  // Paper §2.2: arctan gives θ in (−45°, 45°); the sign of the implied d extends it to 180°.
  double theta = 0.5 * std::atan(Y / X);
  double d = X * std::cos(2.0 * theta) + Y * std::sin(2.0 * theta);
  if (d < 0.0) {
    theta += 0.5 * std::numbers::pi;
    d = -d;
  }
  return {wrap_axis_deg(rad2deg(theta)), d};
}

int section_of(double theta_deg) {
  // A NaN cast to int is undefined behaviour; refuse it before the cast.
  if (!std::isfinite(theta_deg))
    throw std::invalid_argument("section_of: the angle is not a finite number");
  const int s = static_cast<int>(std::floor((wrap_axis_deg(theta_deg) + 15.0) / 30.0));
  return s % 6;
}

int bad_voltage_of(int section) {
  static constexpr int kBad[6] = {0, 2, 1, 0, 2, 1};
  if (section < 0 || section > 5) throw std::out_of_range("bad_voltage_of: a section is 0..5");
  return kBad[section];
}

SensorAngles sensor_angles(const CalibrationParams& p, const Electronics& e,
                           const std::array<double, 3>& V, PairInversion method) {
  SensorAngles s;
  s.theta12 = pair_angle(p, e, V, 0, 1, method);
  s.theta13 = pair_angle(p, e, V, 0, 2, method);
  s.theta23 = pair_angle(p, e, V, 1, 2, method);
  s.section = section_of(s.theta12.theta_deg);
  switch (bad_voltage_of(s.section)) {
    case 0: s.theta_sec_deg = s.theta23.theta_deg; break;
    case 1: s.theta_sec_deg = s.theta13.theta_deg; break;
    default: s.theta_sec_deg = s.theta12.theta_deg; break;
  }
  return s;
}

std::string adc_range_problem(const std::array<double, 3>& V) {
  for (int i = 0; i < 3; ++i) {
    const double v = V[static_cast<std::size_t>(i)];
    if (!(std::abs(v) <= kMaxAdcVolts))
      return fmt::format("column 'V{}': {} V is outside any ADC's range (|V| ≤ {} V)", i + 1, v,
                         kMaxAdcVolts);
  }
  return {};
}

MeasuredAngles measured_angles(const CalibrationParams& p, const Electronics& e,
                               const std::array<double, 3>& V, PairInversion method) {
  MeasuredAngles out;
  out.problem = adc_range_problem(V);
  if (!out.problem.empty()) return out;
  for (std::size_t i = 0; i < 3; ++i) {
    const double decades = (V[i] - p.k_mV[i] * 1e-3) / (p.kv[i] * e.volts_per_decade);
    if (!(std::abs(decades) <= kMaxDecades)) {
      out.problem = fmt::format(
          "column 'V{}': {} V is {:.3g} decades of light ratio from the pair's offset at {} V "
          "per decade (kv = {}): no light gives that", i + 1, V[i], decades, e.volts_per_decade,
          p.kv[i]);
      return out;
    }
  }
  const std::string no_angle = fmt::format(
      "V1 = {}, V2 = {}, V3 = {} give no finite angle with these parameters", V[0], V[1], V[2]);
  try {
    out.angles = sensor_angles(p, e, V, method);
  } catch (const std::invalid_argument&) {
    out.problem = no_angle;
    return out;
  }
  const SensorAngles& a = out.angles;
  for (double x : {a.theta12.theta_deg, a.theta13.theta_deg, a.theta23.theta_deg, a.theta_sec_deg,
                   a.theta12.d, a.theta13.d, a.theta23.d})
    if (!std::isfinite(x)) {
      out.problem = no_angle;
      return out;
    }
  // d of the pair the section algorithm used: the one without the section's bad voltage.
  const int bad = bad_voltage_of(a.section);
  out.d = bad == 0 ? a.theta23.d : bad == 1 ? a.theta13.d : a.theta12.d;
  return out;
}

}  // namespace polrig
