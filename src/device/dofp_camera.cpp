#include "polrig/device/dofp_camera.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/random.h"
#include "polrig/units.h"

namespace polrig {

double focal_px(const DofpCameraSpec& spec) { return spec.focal_mm / spec.pixel_um * 1000.0; }

double fov_x_deg(const DofpCameraSpec& spec) {
  return rad2deg(2.0 * std::atan(0.5 * spec.width_px / focal_px(spec)));
}

double fov_y_deg(const DofpCameraSpec& spec) {
  return rad2deg(2.0 * std::atan(0.5 * spec.height_px / focal_px(spec)));
}

Vec3 pixel_view(const DofpCameraSpec& spec, int col, int row) {
  const double x = col + 0.5 - 0.5 * spec.width_px, y = row + 0.5 - 0.5 * spec.height_px;
  return vec3::unit({x, y, focal_px(spec)});
}

namespace {
// (−90°, 90°]
double wrap90(double deg) {
  double a = std::remainder(deg, 180.0);  // [−90°, 90°]
  if (a <= -90.0) a += 180.0;
  return a;
}
}  // namespace

Overlap overlap(std::span<const double> weights, std::span<const double> axes_deg) {
  if (weights.size() != axes_deg.size()) throw std::invalid_argument("overlap: weights and axes differ in number");
  std::complex<double> c{0, 0};
  for (std::size_t q = 0; q < weights.size(); ++q)
    c += weights[q] * std::polar(1.0, 2.0 * deg2rad(axes_deg[q]));
  return {std::abs(c), wrap90(rad2deg(0.5 * std::arg(c)))};
}

double overlap_eps_deg(double alpha_deg, const Overlap& o) { return wrap90(alpha_deg - o.axis_deg); }

namespace {

struct P2 {
  double x, y;
};

// Sutherland–Hodgman: the part of a convex polygon with coordinate `axis` (0: x, 1: y) ≥ lo
// (keep_above) or ≤ hi.
int clip(const P2* in, int n, P2* out, int axis, double bound, bool keep_above) {
  auto coord = [axis](const P2& p) { return axis == 0 ? p.x : p.y; };
  auto inside = [&](const P2& p) { return keep_above ? coord(p) >= bound : coord(p) <= bound; };
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const P2& a = in[i];
    const P2& b = in[(i + 1) % n];
    const bool ia = inside(a), ib = inside(b);
    if (ia) out[m++] = a;
    if (ia != ib) {
      const double t = (bound - coord(a)) / (coord(b) - coord(a));
      out[m++] = {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)};
    }
  }
  return m;
}

double area(const P2* p, int n) {
  double s = 0;
  for (int i = 0; i < n; ++i) {
    const P2& a = p[i];
    const P2& b = p[(i + 1) % n];
    s += a.x * b.y - b.x * a.y;
  }
  return 0.5 * std::abs(s);
}

}  // namespace

Overlap misregistered_overlap(const DofpCameraSpec& spec, int col, int row) {
  const double cx = 0.5 * spec.width_px, cy = 0.5 * spec.height_px;
  const double rot = deg2rad(spec.misregistration_rotation_deg);
  const double c = std::cos(rot), s = std::sin(rot);
  // Pixel coordinates → mosaic coordinates: m = centre + Rot(−rotation)·(p − centre − (dx, dy)).
  auto to_mosaic = [&](double px, double py) {
    const double x = px - cx - spec.misregistration_dx_px, y = py - cy - spec.misregistration_dy_px;
    return P2{cx + c * x + s * y, cy - s * x + c * y};
  };
  const P2 quad[4] = {to_mosaic(col, row), to_mosaic(col + 1, row), to_mosaic(col + 1, row + 1),
                      to_mosaic(col, row + 1)};
  double x0 = quad[0].x, x1 = x0, y0 = quad[0].y, y1 = y0;
  for (const P2& p : quad) x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
  double w[4] = {0, 0, 0, 0};  // area of the pixel under each mosaic position
  for (int r = static_cast<int>(std::floor(y0)); r <= static_cast<int>(std::floor(y1)); ++r)
    for (int q = static_cast<int>(std::floor(x0)); q <= static_cast<int>(std::floor(x1)); ++q) {
      P2 a[8], b[8];
      int n = clip(quad, 4, a, 0, q, true);
      n = clip(a, n, b, 0, q + 1, false);
      n = clip(b, n, a, 1, r, true);
      n = clip(a, n, b, 1, r + 1, false);
      if (n >= 3) w[mosaic_position(q, r)] += area(b, n);
    }
  const double total = w[0] + w[1] + w[2] + w[3];  // 1 up to rounding: a rotation keeps areas
  double axes[4];
  for (int j = 0; j < 4; ++j) {
    w[j] /= total;
    axes[j] = spec.mosaic_deg[static_cast<std::size_t>(j)] + spec.misregistration_rotation_deg;
  }
  return overlap(w, axes);
}

DofpTruth make_dofp_truth(const DofpCameraSpec& spec, std::uint64_t seed) {
  if (spec.width_px <= 0 || spec.height_px <= 0 || spec.width_px % 2 || spec.height_px % 2)
    throw std::invalid_argument(fmt::format("the camera's size {} × {} px must be positive and even",
                                            spec.width_px, spec.height_px));
  for (std::size_t j = 0; j < 4; ++j)
    if (!(std::isfinite(spec.mosaic_gain[j]) && spec.mosaic_gain[j] > 0))
      throw std::invalid_argument(fmt::format("the mosaic gain of position {} is {}; it must be finite and > 0",
                                              j, spec.mosaic_gain[j]));
  const bool misregistered = spec.misregistration_dx_px != 0 || spec.misregistration_dy_px != 0 ||
                             spec.misregistration_rotation_deg != 0;
  const double D = (spec.extinction_ratio - 1.0) / (spec.extinction_ratio + 1.0);
  DofpTruth t;
  t.width = spec.width_px, t.height = spec.height_px;
  const std::size_t n = static_cast<std::size_t>(t.width) * static_cast<std::size_t>(t.height);
  t.K.resize(n), t.b.resize(n), t.k.resize(n), t.eps_deg.resize(n), t.alpha_deg.resize(n);
  for (int row = 0; row < t.height; ++row)
    for (int col = 0; col < t.width; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * static_cast<std::size_t>(t.width) + static_cast<std::size_t>(col);
      const std::size_t j = static_cast<std::size_t>(mosaic_position(col, row));
      auto z = [&](std::uint64_t parameter) { return standard_normal(seed, i, parameter, 0); };
      const double alpha = spec.mosaic_deg[j];
      double k = spec.k[j], eps = spec.eps_deg[j];
      if (misregistered) {
        const Overlap o = misregistered_overlap(spec, col, row);
        k = o.k, eps = overlap_eps_deg(alpha, o);
      }
      if (spec.k_spread != 0) k += spec.k_spread * z(2);
      if (spec.eps_spread_deg != 0) eps += spec.eps_spread_deg * z(3);
      const double K = spec.gain_DN * spec.mosaic_gain[j] *
                       (1.0 + (spec.gain_spread != 0 ? spec.gain_spread * z(0) : 0.0));
      if (!(K > 0))
        throw std::invalid_argument(fmt::format(
            "the gain spread {} gives pixel ({}, {}) a gain K = {} DN ≤ 0", spec.gain_spread, col, row, K));
      t.K[i] = K;
      t.b[i] = spec.offset_DN + (spec.offset_spread_DN != 0 ? spec.offset_spread_DN * z(1) : 0.0);
      t.k[i] = std::clamp(k, 0.0, 1.0) * D;
      t.eps_deg[i] = eps;
      t.alpha_deg[i] = alpha;
    }
  return t;
}

double eq18_DN(double K, double b, double k, double eps_deg, double alpha_deg, double I, double d,
               double phi_deg) {
  return 0.5 * K * I * (1.0 + k * d * std::cos(2.0 * deg2rad(phi_deg - (alpha_deg - eps_deg)))) + b;
}

double normal_quantile(double p) {
  // Wichura, M. J. (1988), Algorithm AS 241, Appl. Statist. 37(3):477–484 (PPND16).
  const double q = p - 0.5;
  if (std::abs(q) <= 0.425) {
    const double r = 0.180625 - q * q;
    return q *
           (((((((2.5090809287301226727e+3 * r + 3.3430575583588128105e+4) * r + 6.7265770927008700853e+4) * r +
                4.5921953931549871457e+4) * r + 1.3731693765509461125e+4) * r + 1.9715909503065514427e+3) * r +
             1.3314166789178437745e+2) * r + 3.3871328727963666080e0) /
           (((((((5.2264952788528545610e+3 * r + 2.8729085735721942674e+4) * r + 3.9307895800092710610e+4) * r +
                2.1213794301586595867e+4) * r + 5.3941960214247511077e+3) * r + 6.8718700749205790830e+2) * r +
             4.2313330701600911252e+1) * r + 1.0);
  }
  double r = std::sqrt(-std::log(q < 0 ? p : 1.0 - p));
  double x;
  if (r <= 5.0) {
    r -= 1.6;
    x = (((((((7.74545014278341407640e-4 * r + 2.27238449892691845833e-2) * r + 2.41780725177450611770e-1) * r +
             1.27045825245236838258e0) * r + 3.64784832476320460504e0) * r + 5.76949722146069140550e0) * r +
          4.63033784615654529590e0) * r + 1.42343711074968357734e0) /
        (((((((1.05075007164441684324e-9 * r + 5.47593808499534494600e-4) * r + 1.51986665636164571966e-2) * r +
             1.48103976427480074590e-1) * r + 6.89767334985100004550e-1) * r + 1.67638483018380384940e0) * r +
          2.05319162663775882187e0) * r + 1.0);
  } else {
    r -= 5.0;
    x = (((((((2.01033439929228813265e-7 * r + 2.71155556874348757815e-5) * r + 1.24266094738807843860e-3) * r +
             2.65321895265761230930e-2) * r + 2.96560571828504891230e-1) * r + 1.78482653991729133580e0) * r +
          5.46378491116411436990e0) * r + 6.65790464350110377720e0) /
        (((((((2.04426310338993978564e-15 * r + 1.42151175831644588870e-7) * r + 1.84631831751005468180e-5) * r +
             7.86869131145613259100e-4) * r + 1.48753612908506148525e-2) * r + 1.36929880922735805310e-1) * r +
          5.99832206555887937690e-1) * r + 1.0);
  }
  return q < 0 ? -x : x;
}

namespace {
// Open (0, 1): (k + ½)·2⁻⁵², k the top 52 bits, every value exact and never 0 or 1.
double open_unit(std::uint64_t bits) { return (static_cast<double>(bits >> 12) + 0.5) * 0x1.0p-52; }

// Φ⁻¹ at the ends of 4096 intervals of u. The outer 64 at each end (u < 1/64, 3 % of the draws),
// where the quantile curves too much for the linear interpolation to keep its error under 2e-5,
// are computed exactly (DofpExposure::deviate).
constexpr int kQuantileIntervals = 4096;
const std::vector<double>& quantile_table() {
  static const std::vector<double> table = [] {
    std::vector<double> t(kQuantileIntervals + 1);
    for (int k = 1; k < kQuantileIntervals; ++k) t[static_cast<std::size_t>(k)] = normal_quantile(double(k) / kQuantileIntervals);
    return t;
  }();
  return table;
}
}  // namespace

DofpExposure::DofpExposure(const DofpCameraSpec& spec, std::uint64_t seed, std::uint64_t stop, std::uint64_t frame)
    : noise_(spec.noise),
      electrons_per_DN_(spec.electrons_per_DN),
      read2_(spec.read_noise_DN * spec.read_noise_DN),
      read_(spec.read_noise_DN),
      top_(std::ldexp(1.0, spec.adc_bits) - 1.0),
      table_(quantile_table().data()) {
  using detail::splitmix64;
  prefix_ = splitmix64(splitmix64(seed ^ stop) ^ (frame + 0x632BE59BD9B4E019ull));
}

double DofpExposure::few_electrons(double s, double b_DN, std::uint64_t h) const {
  const double lambda = s * electrons_per_DN_;
  const double u = open_unit(detail::splitmix64(h ^ 0xA24BAED4963EE407ull));
  double p = std::exp(-lambda), F = p;
  int count = 0;
  while (u > F && count < 1000) {
    ++count;
    p *= lambda / count;
    F += p;
  }
  return b_DN + count / electrons_per_DN_ + read_ * deviate(h);
}

double noise_deviate(double u) {
  const std::vector<double>& T = quantile_table();
  const double x = u * kQuantileIntervals;
  const int k = static_cast<int>(x);
  if (k < 64 || k >= kQuantileIntervals - 64) return normal_quantile(u);
  const std::size_t i = static_cast<std::size_t>(k);
  return T[i] + (x - k) * (T[i + 1] - T[i]);
}

std::uint16_t expose_DN(const DofpCameraSpec& spec, double f_DN, double b_DN, std::uint64_t seed,
                        std::uint64_t stop, std::uint64_t frame, std::uint64_t pixel) {
  return DofpExposure(spec, seed, stop, frame)(f_DN, b_DN, pixel);
}

}  // namespace polrig
