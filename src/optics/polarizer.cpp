#include "polrig/optics/polarizer.h"

#include <cmath>

#include "polrig/units.h"

namespace polrig {

MuellerMatrix linear_polarizer(double tau_M, double tau_m, double axis_deg) {
  const double a = 0.5 * (tau_M + tau_m), b = 0.5 * (tau_M - tau_m), c = std::sqrt(tau_M * tau_m);
  const double C = std::cos(2 * deg2rad(axis_deg)), S = std::sin(2 * deg2rad(axis_deg));
  // Diattenuator along x (a, b; b, a; c; c), rotated to the axis: R(−ψ)·M·R(ψ).
  MuellerMatrix m;
  m << a, b * C, b * S, 0,
       b * C, a * C * C + c * S * S, (a - c) * C * S, 0,
       b * S, (a - c) * C * S, a * S * S + c * C * C, 0,
       0, 0, 0, c;
  return m;
}

MuellerMatrix frame_rotation(double deg) {
  const double C = std::cos(2 * deg2rad(deg)), S = std::sin(2 * deg2rad(deg));
  MuellerMatrix r = MuellerMatrix::Identity();
  r(1, 1) = C;
  r(1, 2) = S;
  r(2, 1) = -S;
  r(2, 2) = C;
  return r;
}

Stokes unpolarized(double S0) { return Stokes(S0, 0, 0, 0); }

Stokes linearly_polarized(double S0, double d, double angle_deg) {
  return Stokes(S0, S0 * d * std::cos(2 * deg2rad(angle_deg)), S0 * d * std::sin(2 * deg2rad(angle_deg)), 0);
}

}  // namespace polrig
