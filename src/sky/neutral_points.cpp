// The vector-RT sky's neutral points (include/polrig/sky/neutral_points.h).
#include "polrig/sky/neutral_points.h"

#include <cmath>
#include <functional>
#include <optional>
#include <utility>

#include "polrig/sky/berry_fit.h"
#include "polrig/sky/vector_rt_sky.h"
#include "polrig/units.h"

namespace polrig {

namespace {

// A point of the solar meridian at γ degrees from the sun, upward (over the zenith at
// γ = 90° − h, down to the antisun's horizon at 180° − h): its view elevation and relative azimuth.
struct MeridianView {
  double elevation_deg, phi;
};
MeridianView meridian_view(double sun_el_deg, double gamma_deg) {
  const double e = sun_el_deg + gamma_deg;
  return e <= 90 ? MeridianView{e, 0.0} : MeridianView{180 - e, M_PI};
}

// Q/I of the exact sky at one point of the meridian.
double exact_signed_dop(const VectorRtSettings& s, double sun_el_deg, double gamma_deg) {
  const MeridianView v = meridian_view(sun_el_deg, gamma_deg);
  const DiffuseField f = solve_vector_rt(s, std::sin(sun_el_deg * kDeg), {std::max(std::sin(v.elevation_deg * kDeg), 1e-6)});
  const Eigen::Vector4d x = f.down_at(0, v.phi);
  return x(1) / x(0);
}

// Brent's method (Brent 1973, ch. 4: bisection, secant and inverse quadratic steps) for a root of
// g in [a, b], g(a)·g(b) ≤ 0, to the absolute tolerance tol.
double brent_root(const std::function<double(double)>& g, double a, double b, double tol) {
  double fa = g(a), fb = g(b);
  if (fa == 0) return a;
  if (fb == 0) return b;
  double c = a, fc = fa, d = b - a, e = d;
  for (int it = 0; it < 100; ++it) {
    if ((fb > 0) == (fc > 0)) c = a, fc = fa, d = e = b - a;
    if (std::abs(fc) < std::abs(fb)) a = b, b = c, c = a, fa = fb, fb = fc, fc = fa;
    const double m = 0.5 * (c - b), t = 2e-16 * std::abs(b) + 0.5 * tol;
    if (std::abs(m) <= t || fb == 0) return b;
    if (std::abs(e) >= t && std::abs(fa) > std::abs(fb)) {
      double p, q, r;
      const double s = fb / fa;
      if (a == c) {
        p = 2 * m * s, q = 1 - s;
      } else {
        q = fa / fc, r = fb / fc;
        p = s * (2 * m * q * (q - r) - (b - a) * (r - 1)), q = (q - 1) * (r - 1) * (s - 1);
      }
      if (p > 0) q = -q; else p = -p;
      if (2 * p < std::min(3 * m * q - std::abs(t * q), std::abs(e * q))) {
        e = d, d = p / q;
      } else {
        d = m, e = m;
      }
    } else {
      d = m, e = m;
    }
    a = b, fa = fb;
    b += std::abs(d) > t ? d : (m > 0 ? t : -t);
    fb = g(b);
  }
  return b;
}

// A sign change of g between a and b, found in ten equal steps (exact solves): two bracketing
// points, the first from a; empty if g keeps its sign at all of them.
std::optional<std::pair<double, double>> exact_bracket(const std::function<double(double)>& g, double a, double b) {
  constexpr int kSteps = 10;
  double x0 = a, g0 = g(a);
  for (int k = 1; k <= kSteps; ++k) {
    const double x1 = a + (b - a) * k / kSteps, g1 = g(x1);
    if ((g0 > 0) != (g1 > 0)) return std::make_pair(x0, x1);
    x0 = x1, g0 = g1;
  }
  return std::nullopt;
}

}  // namespace

NeutralPoints vector_rt_neutral_points(const VectorRtSettings& s, double h) {
  const SunField field = vector_rt_sky(s)->for_sun(h);  // throws for a sun it refuses
  const auto coarse = [&](double gamma) {
    const MeridianView v = meridian_view(h, gamma);
    const Eigen::Vector3d x = field.stokes(std::sin(v.elevation_deg * kDeg), v.phi);
    return x(1) / x(0);
  };
  const auto exact = [&](double gamma) { return exact_signed_dop(s, h, gamma); };
  // The first sign change of Q/I walking from `from` towards `to` in 0.1° steps, refined.
  const auto first_zero = [&](double from, double to) -> std::optional<double> {
    const double step = from < to ? 0.1 : -0.1;
    double g0 = from, q0 = coarse(from);
    for (double g1 = from + step; step > 0 ? g1 <= to + 1e-9 : g1 >= to - 1e-9; g1 += step) {
      const double q1 = coarse(g1);
      if ((q0 > 0) != (q1 > 0)) {
        // The exact zero may sit a hair off the interpolated one: look for it a step either way.
        double a = g0 - step, b = g1 + step;
        if (step > 0 ? a < from : a > from) a = from;
        if (step > 0 ? b > to : b < to) b = to;
        if (const std::optional<std::pair<double, double>> bracket = exact_bracket(exact, a, b))
          return brent_root(exact, bracket->first, bracket->second, 1e-4);
        // No exact sign change there: the interpolated sky's was its own error; walk on.
      }
      g0 = g1, q0 = q1;
    }
    return std::nullopt;
  };
  NeutralPoints p;
  p.sun_el_deg = h;
  // Near the sun the sky is negatively polarized (Q > 0) between Brewster and Babinet; start a
  // little off the sun, where Q's sign is already that of the band.
  constexpr double kOffSun = 0.5;
  if (coarse(kOffSun) > 0) p.babinet_deg = first_zero(kOffSun, 180 - h);
  if (h > kOffSun && coarse(-kOffSun) > 0) p.brewster_deg = first_zero(-kOffSun, -h);
  if (p.brewster_deg) p.brewster_deg = -*p.brewster_deg;
  // Arago: Q > 0 at the antisun's horizon means the negative band rises above it.
  if (coarse(180 - h) > 0) {
    if (const std::optional<double> g = first_zero(180 - h, 0)) p.arago_deg = 180 - *g;
  }
  return p;
}

NeutralPoints sky_neutral_points(const SkyModel& model, double h) {
  switch (model.kind) {
    case SkyKind::VectorRt:
      return vector_rt_neutral_points(model.vector_rt->settings(), h);
    case SkyKind::Berry: {
      const BerryDistances d = berry_distances(model.berry, h);
      NeutralPoints p;
      p.sun_el_deg = h;
      p.babinet_deg = d.babinet_deg;
      if (h - d.brewster_deg >= 0) p.brewster_deg = d.brewster_deg;
      else p.arago_deg = d.brewster_deg;
      return p;
    }
    case SkyKind::SingleScattering:
      break;
  }
  return {h, {}, {}, {}};  // single scattering: Q < 0 everywhere off the sun's line
}

}  // namespace polrig
