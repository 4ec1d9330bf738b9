// The single-scattering Rayleigh sky (spec sky-and-compasses.md §1.2).
#include "polrig/sky/rayleigh.h"
#include "polrig/sky/berry.h"
#include "polrig/sky/berry_fit.h"
#include "polrig/sky/vector_rt_sky.h"
#include "polrig/units.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace polrig {

std::string_view sky_radiance_name(SkyRadiance r) {
  switch (r) {
    case SkyRadiance::Uniform: return "uniform";
    case SkyRadiance::Rayleigh: return "rayleigh";
    case SkyRadiance::CieClear: return "cie-clear";
  }
  return "?";
}

std::optional<SkyRadiance> parse_sky_radiance(std::string_view name) {
  for (const SkyRadiance r : {SkyRadiance::Uniform, SkyRadiance::Rayleigh, SkyRadiance::CieClear})
    if (sky_radiance_name(r) == name) return r;
  return std::nullopt;
}

std::string_view sky_kind_name(SkyKind k) {
  switch (k) {
    case SkyKind::SingleScattering: return "single-scattering";
    case SkyKind::VectorRt: return "vector-rt";
    case SkyKind::Berry: return "berry";
  }
  return "?";
}

std::optional<SkyKind> parse_sky_kind(std::string_view name) {
  for (const SkyKind k : {SkyKind::SingleScattering, SkyKind::VectorRt, SkyKind::Berry})
    if (sky_kind_name(k) == name) return k;
  return std::nullopt;
}

namespace {

// CIE S 011/E:2003 type 12 (see rayleigh.h).
constexpr double kCieA = -1, kCieB = -0.32, kCieC = 10, kCieD = -3, kCieE = 0.45;

double cie_gradation(double cos_Z) {
  return cos_Z <= 0 ? 1.0 : 1 + kCieA * std::exp(kCieB / cos_Z);
}
double cie_indicatrix(double gamma, double cos_gamma) {
  return 1 + kCieC * (std::exp(kCieD * gamma) - std::exp(kCieD * M_PI / 2)) +
         kCieE * cos_gamma * cos_gamma;
}

double relative_radiance(SkyRadiance model, const Vec3& s, const Vec3& v, double cos_gamma,
                         double sin_gamma) {
  switch (model) {
    case SkyRadiance::Uniform:
      return 1;
    case SkyRadiance::Rayleigh:
      return (1 + cos_gamma * cos_gamma) / (1 + s[2] * s[2]);
    case SkyRadiance::CieClear: {
      const double gamma = std::atan2(sin_gamma, cos_gamma);
      const double sun_zenith = std::acos(std::clamp(s[2], -1.0, 1.0));
      return cie_indicatrix(gamma, cos_gamma) * cie_gradation(v[2]) /
             (cie_indicatrix(sun_zenith, s[2]) * cie_gradation(1));
    }
  }
  return 1;
}

}  // namespace

double MaxDegree::at(double sun_elevation_deg) const {
  if (table.empty()) return constant;
  if (sun_elevation_deg <= table.front().first) return table.front().second;
  if (sun_elevation_deg >= table.back().first) return table.back().second;
  const auto hi = std::upper_bound(table.begin(), table.end(), sun_elevation_deg,
                                   [](double h, const auto& row) { return h < row.first; });
  const auto lo = hi - 1;
  const double f = (sun_elevation_deg - lo->first) / (hi->first - lo->first);
  return lo->second + f * (hi->second - lo->second);
}

double min_sun_elevation_deg(const SkyModel& model) {
  const bool fitted = model.kind == SkyKind::Berry && (!model.berry.babinet_deg || !model.berry.brewster_deg);
  if (model.kind == SkyKind::VectorRt && model.vector_rt) return model.vector_rt->lowest_sun_elevation_deg();
  return model.kind == SkyKind::VectorRt || fitted ? VectorRtSky::kMinSunElevationDeg : -90.0;
}

void check_sky_model(const SkyModel& model) {
  auto check_p = [](double p, const std::string& where) {
    if (!(p > 0 && p <= 1))
      throw std::invalid_argument(fmt::format("P_max {}{} is outside (0, 1]", p, where));
  };
  if (model.P_max.table.empty()) check_p(model.P_max.constant, "");
  for (std::size_t i = 0; i < model.P_max.table.size(); ++i) {
    const auto& [h, p] = model.P_max.table[i];
    if (!(std::abs(h) <= 90))
      throw std::invalid_argument(fmt::format(
          "P_max table row {}: sun elevation {}° is outside [-90°, 90°]", i + 1, h));
    check_p(p, fmt::format(" (P_max table row {})", i + 1));
    if (i > 0 && !(h > model.P_max.table[i - 1].first))
      throw std::invalid_argument(fmt::format(
          "P_max table row {}: sun elevation {}° does not rise from the row before ({}°)", i + 1, h,
          model.P_max.table[i - 1].first));
  }
}

void meridian_frame(const Vec3& v, Vec3& e_theta, Vec3& e_phi) {
  const double rho = std::hypot(v[0], v[1]);
  const double cos_phi = rho > 0 ? v[0] / rho : 1, sin_phi = rho > 0 ? v[1] / rho : 0;
  e_theta = {v[2] * cos_phi, v[2] * sin_phi, -rho};
  e_phi = {-sin_phi, cos_phi, 0};
}

namespace {
std::pair<double, double> azimuth_cos_sin(const Vec3& v);
}  // namespace

SunSky::SunSky(const Vec3& s, const SkyModel& model)
    : s_(s), P_max_(model.P_max.at(std::asin(std::clamp(s[2], -1.0, 1.0)) / kDeg)), radiance_(model.radiance) {
  if (model.kind == SkyKind::VectorRt) {
    if (!model.vector_rt) throw std::logic_error("a vector-rt sky model without its solved sky");
    field_ = std::make_shared<const SunField>(model.vector_rt->for_sun(std::asin(std::clamp(s[2], -1.0, 1.0)) / kDeg));
    sun_azimuth_ = azimuth_cos_sin(s);
  }
  if (model.kind == SkyKind::Berry) {
    const double h = std::asin(std::clamp(s[2], -1.0, 1.0)) / kDeg;
    berry_ = std::make_shared<const BerryField>(s, berry_distances(model.berry, h));
  }
}

namespace {

// cos and sin of a horizontal direction's math azimuth; (1, 0) straight up or down, as
// meridian_frame takes φ = 0 there.
std::pair<double, double> azimuth_cos_sin(const Vec3& v) {
  const double rho = std::sqrt(v[0] * v[0] + v[1] * v[1]);  // a unit vector's: no overflow to guard (hypot's cost)
  return rho > 0 ? std::pair{v[0] / rho, v[1] / rho} : std::pair{1.0, 0.0};
}

// The vector-RT sky's Stokes vector along v (L/E₀; Q, U in v's meridian frame), at the relative
// azimuth φ = φ_v − φ_sun.
Eigen::Vector3d field_stokes(const SunField& f, const std::pair<double, double>& sun, const Vec3& v) {
  const auto [cv, sv] = azimuth_cos_sin(v);
  return f.stokes(std::clamp(v[2], 0.0, 1.0), cv * sun.first + sv * sun.second, sv * sun.first - cv * sun.second);
}

}  // namespace

std::optional<Stokes> SunSky::absolute_stokes(const Vec3& v) const {
  if (!field_) return std::nullopt;
  const Eigen::Vector3d x = field_stokes(*field_, sun_azimuth_, v);
  return Stokes{x(0), x(1), x(2), 0};
}

SkyRay SunSky::along(const Vec3& v) const {
  SkyRay ray;
  const Vec3 c = vec3::cross(s_, v);
  ray.sin_gamma = vec3::norm(c);
  if (field_) {
    const Eigen::Vector3d x = field_stokes(*field_, sun_azimuth_, v);
    ray.radiance = x(0) / field_->zenith_radiance();
    const double lp = std::sqrt(x(1) * x(1) + x(2) * x(2));
    ray.dop = lp / x(0);
    if (lp > 0) {
      // e = cos χ e_θ + sin χ e_φ with cos 2χ = Q/(LP), sin 2χ = U/(LP), χ ∈ (−90°, 90°]: by the
      // half-angle formulas, from the larger of 1 ± cos 2χ (no cancellation).
      const double c2 = x(1) / lp, s2 = x(2) / lp;
      double cos_chi, sin_chi;
      if (c2 >= 0) {
        cos_chi = std::sqrt(0.5 * (1 + c2)), sin_chi = s2 / (2 * cos_chi);
      } else {
        sin_chi = std::copysign(std::sqrt(0.5 * (1 - c2)), s2), cos_chi = s2 / (2 * sin_chi);
        if (s2 == 0) sin_chi = 1, cos_chi = 0;
      }
      Vec3 e_theta, e_phi;
      meridian_frame(v, e_theta, e_phi);
      ray.e_vector = vec3::add(vec3::mul(e_theta, cos_chi), vec3::mul(e_phi, sin_chi));
    }
    return ray;
  }
  const double cos_gamma = vec3::dot(s_, v);
  if (berry_) {
    const BerryField::Polarization b = berry_->at(v);
    ray.dop = berry_dop(b.w_abs, P_max_);
    ray.radiance = relative_radiance(radiance_, s_, v, cos_gamma, ray.sin_gamma);
    ray.e_vector = b.e_vector;
    return ray;
  }
  const double sin2 = ray.sin_gamma * ray.sin_gamma, cos2 = cos_gamma * cos_gamma;
  // P = P_max·sin²γ/(1 + cos²γ); sin²γ from |s × v|², exact at γ = 0° and 180°.
  ray.dop = P_max_ * sin2 / (1 + cos2);
  ray.radiance = relative_radiance(radiance_, s_, v, cos_gamma, ray.sin_gamma);
  if (ray.sin_gamma > 0) ray.e_vector = vec3::mul(c, 1 / ray.sin_gamma);
  return ray;
}

SkyLight sky_light(const SunSky& sky, const Vec3& v) {
  const SkyRay ray = sky.along(v);
  SkyLight light;
  light.radiance = ray.radiance, light.dop = ray.dop, light.e_vector = ray.e_vector;
  if (vec3::norm(ray.e_vector) > 0) {
    Vec3 e_theta, e_phi;
    meridian_frame(v, e_theta, e_phi);
    double chi = std::atan2(vec3::dot(light.e_vector, e_phi), vec3::dot(light.e_vector, e_theta)) / kDeg;
    chi = std::fmod(chi + 360, 180.0);
    light.aop_deg = chi >= 180 ? 0 : chi;
  }
  return light;
}

SkyLight sky_light(const Vec3& s, const Vec3& v, const SkyModel& model) { return sky_light(SunSky(s, model), v); }

Stokes sky_stokes(const SkyLight& light) {
  const double two_chi = 2 * light.aop_deg * kDeg;
  const double lp = light.radiance * light.dop;
  return {light.radiance, lp * std::cos(two_chi), lp * std::sin(two_chi), 0};
}

}  // namespace polrig
