// An aerosol's scattering matrix: the table reader, its expansion and δ-M
// (include/polrig/sky/aerosol.h).
#include "polrig/sky/aerosol.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "polrig/units.h"

namespace polrig {

namespace {

constexpr std::array<std::string_view, 7> kColumns = {"theta_deg", "P1", "P2", "P3", "P4", "P5", "P6"};
constexpr double kNormalizationTolerance = 0.01;  // ½∫P1 dcosΘ may be off by rounding, not by a factor
constexpr double kElementSlack = 1e-3;            // |P_i| ≤ P1 up to the printed digits

[[noreturn]] void fail(std::string_view file, int line, int column, const std::string& why) {
  if (column > 0)
    throw PhaseMatrixError(fmt::format("{}:{}: column {} ({}): {}", file, line, column,
                                       kColumns[static_cast<std::size_t>(column - 1)], why));
  throw PhaseMatrixError(fmt::format("{}:{}: {}", file, line, why));
}

// The whitespace-separated fields of a line.
std::vector<std::string_view> fields(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    std::size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != '\r') ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

double number(std::string_view text, std::string_view file, int line, int column) {
  double v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size())
    fail(file, line, column, fmt::format("'{}' is not a number", text));
  if (!std::isfinite(v)) fail(file, line, column, fmt::format("{} is not finite", text));
  return v;
}

// ½∫f(Θ) sinΘ dΘ by the trapezoid rule on the table's angles.
double half_integral(const std::vector<double>& theta_deg, const std::vector<double>& f) {
  double sum = 0;
  for (std::size_t i = 0; i + 1 < theta_deg.size(); ++i) {
    const double t0 = theta_deg[i] * kDeg, t1 = theta_deg[i + 1] * kDeg;
    sum += 0.5 * (t1 - t0) * (f[i] * std::sin(t0) + f[i + 1] * std::sin(t1));
  }
  return sum / 2;
}

// The trapezoid weights in Θ of the table's rows for ∫g(cos Θ) dcos Θ = ∫g sinΘ dΘ.
std::vector<double> trapezoid_weights(const std::vector<double>& theta_deg) {
  std::vector<double> w(theta_deg.size(), 0.0);
  for (std::size_t i = 0; i + 1 < theta_deg.size(); ++i) {
    const double h = (theta_deg[i + 1] - theta_deg[i]) * kDeg;
    w[i] += h / 2 * std::sin(theta_deg[i] * kDeg);
    w[i + 1] += h / 2 * std::sin(theta_deg[i + 1] * kDeg);
  }
  return w;
}

}  // namespace

PhaseMatrixTable parse_phase_matrix(std::string_view text, std::string_view file) {
  PhaseMatrixTable t;
  t.source = std::string(file);
  std::vector<double> P1;
  std::vector<int> lines;
  std::istringstream in{std::string(text)};
  int line_number = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_number;
    const std::vector<std::string_view> f = fields(line);
    if (f.empty() || f[0].starts_with("#")) continue;
    if (f.size() != kColumns.size())
      fail(file, line_number, 0,
           fmt::format("expected {} columns (theta_deg P1 P2 P3 P4 P5 P6), got {}", kColumns.size(), f.size()));
    std::array<double, 7> v{};
    for (int c = 0; c < 7; ++c) v[static_cast<std::size_t>(c)] = number(f[static_cast<std::size_t>(c)], file, line_number, c + 1);
    const double theta = v[0];
    if (t.theta_deg.empty() && theta != 0)
      fail(file, line_number, 1, fmt::format("the table must start at 0 degrees, got {}", theta));
    if (!t.theta_deg.empty() && !(theta > t.theta_deg.back()))
      fail(file, line_number, 1, fmt::format("{} does not rise from the previous row's {}", theta, t.theta_deg.back()));
    if (theta > 180) fail(file, line_number, 1, fmt::format("{} is past 180 degrees", theta));
    if (!(v[1] > 0)) fail(file, line_number, 2, fmt::format("P1 = {} is not positive (it is the phase function)", v[1]));
    for (int c = 3; c <= 7; ++c)
      if (std::abs(v[static_cast<std::size_t>(c - 1)]) > v[1] * (1 + kElementSlack))
        fail(file, line_number, c,
             fmt::format("|{}| exceeds P1 = {} (no scatterer polarizes or depolarizes more than it scatters)",
                         v[static_cast<std::size_t>(c - 1)], v[1]));
    ScatteringElements e;
    e.a1 = v[1], e.b1 = v[2], e.a3 = v[3], e.b2 = v[4], e.a2 = v[5], e.a4 = v[6];
    t.theta_deg.push_back(theta);
    t.elements.push_back(e);
    P1.push_back(v[1]);
    lines.push_back(line_number);
  }
  if (t.theta_deg.size() < 3)
    fail(file, line_number, 0, fmt::format("expected rows from 0 to 180 degrees, got {} row(s)", t.theta_deg.size()));
  if (t.theta_deg.back() != 180)
    fail(file, lines.back(), 1, fmt::format("the table must end at 180 degrees, got {}", t.theta_deg.back()));
  t.normalization_as_read = half_integral(t.theta_deg, P1);
  if (!(std::abs(t.normalization_as_read - 1) <= kNormalizationTolerance))
    throw PhaseMatrixError(fmt::format(
        "{}:{}-{}: column 2 (P1): half the integral of P1 over cos(theta) is {:.6g}, expected 1 within {} "
        "(P normalised so that P1 averages 1 over the sphere)",
        file, lines.front(), lines.back(), t.normalization_as_read, kNormalizationTolerance));
  for (ScatteringElements& e : t.elements) {
    const double s = 1 / t.normalization_as_read;
    e.a1 *= s, e.a2 *= s, e.a3 *= s, e.a4 *= s, e.b1 *= s, e.b2 *= s;
  }
  return t;
}

PhaseMatrixTable read_phase_matrix(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw PhaseMatrixError(fmt::format("{}: cannot open the phase-matrix file", path.string()));
  std::stringstream buf;
  buf << in.rdbuf();
  return parse_phase_matrix(buf.str(), path.string());
}

ScatteringElements PhaseMatrixTable::at(double cos_theta) const {
  const double theta = std::acos(std::clamp(cos_theta, -1.0, 1.0)) / kDeg;
  const std::size_t n = theta_deg.size();
  std::size_t j = static_cast<std::size_t>(std::upper_bound(theta_deg.begin(), theta_deg.end(), theta) - theta_deg.begin());
  j = std::clamp<std::size_t>(j, 1, n - 1);
  const double t = (theta - theta_deg[j - 1]) / (theta_deg[j] - theta_deg[j - 1]);
  const ScatteringElements& p = elements[j - 1];
  const ScatteringElements& q = elements[j];
  const auto mix = [t](double a, double b) { return a + t * (b - a); };
  return {mix(p.a1, q.a1), mix(p.a2, q.a2), mix(p.a3, q.a3), mix(p.a4, q.a4), mix(p.b1, q.b1), mix(p.b2, q.b2)};
}

std::vector<double> wigner_d(int l_max, int m, int n, double x) {
  std::vector<double> d(static_cast<std::size_t>(l_max) + 1, 0.0);
  const int l0 = std::max(std::abs(m), std::abs(n));
  if (l_max < l0) return d;
  // d^{l0}_{mn}: the pairs the expansion uses.
  double start = 0;
  if (m == 0 && n == 0) start = 1;
  else if (m == 0 && n == 2) start = std::sqrt(6.0) / 4 * (1 - x * x);
  else if (m == 2 && n == 2) start = (1 + x) * (1 + x) / 4;
  else if (m == 2 && n == -2) start = (1 - x) * (1 - x) / 4;
  else throw std::invalid_argument(fmt::format("wigner_d: the pair ({}, {}) is not one the expansion uses", m, n));
  d[static_cast<std::size_t>(l0)] = start;
  if (l0 == 0 && l_max >= 1) d[1] = x;
  const int first = l0 == 0 ? 1 : l0;
  const double mm = m * m, nn = n * n;
  for (int l = first; l < l_max; ++l) {
    const double lp = l + 1.0;
    const double prev = l > l0 ? d[static_cast<std::size_t>(l - 1)] : 0.0;
    d[static_cast<std::size_t>(l + 1)] =
        ((2 * l + 1) * (l * lp * x - m * n) * d[static_cast<std::size_t>(l)] -
         lp * std::sqrt((l * l - mm) * (l * l - nn)) * prev) /
        (l * std::sqrt((lp * lp - mm) * (lp * lp - nn)));
  }
  return d;
}

ScatteringElements PhaseExpansion::at(double x) const {
  const int L = order();
  const std::vector<double> d00 = wigner_d(L, 0, 0, x), d02 = wigner_d(L, 0, 2, x), d22 = wigner_d(L, 2, 2, x),
                            d2m2 = wigner_d(L, 2, -2, x);
  double a1 = 0, a4 = 0, plus = 0, minus = 0, b1 = 0, b2 = 0;
  for (std::size_t l = 0; l < alpha1.size(); ++l) {
    a1 += alpha1[l] * d00[l];
    a4 += alpha4[l] * d00[l];
    plus += (alpha2[l] + alpha3[l]) * d22[l];
    minus += (alpha2[l] - alpha3[l]) * d2m2[l];
    b1 += beta1[l] * d02[l];
    b2 += beta2[l] * d02[l];
  }
  return {a1, (plus + minus) / 2, (plus - minus) / 2, a4, b1, b2};
}

PhaseExpansion expand(const PhaseMatrixTable& table, int l_max) {
  const std::vector<double> w = trapezoid_weights(table.theta_deg);
  PhaseExpansion e;
  for (auto* c : {&e.alpha1, &e.alpha2, &e.alpha3, &e.alpha4, &e.beta1, &e.beta2}) c->assign(static_cast<std::size_t>(l_max) + 1, 0.0);
  std::vector<double> plus(e.alpha1.size(), 0.0), minus(e.alpha1.size(), 0.0);
  for (std::size_t i = 0; i < w.size(); ++i) {
    const double x = std::cos(table.theta_deg[i] * kDeg);
    const ScatteringElements& p = table.elements[i];
    const std::vector<double> d00 = wigner_d(l_max, 0, 0, x), d02 = wigner_d(l_max, 0, 2, x),
                              d22 = wigner_d(l_max, 2, 2, x), d2m2 = wigner_d(l_max, 2, -2, x);
    for (std::size_t l = 0; l <= static_cast<std::size_t>(l_max); ++l) {
      const double k = (2.0 * static_cast<double>(l) + 1) / 2 * w[i];
      e.alpha1[l] += k * p.a1 * d00[l];
      e.alpha4[l] += k * p.a4 * d00[l];
      plus[l] += k * (p.a2 + p.a3) * d22[l];
      minus[l] += k * (p.a2 - p.a3) * d2m2[l];
      e.beta1[l] += k * p.b1 * d02[l];
      e.beta2[l] += k * p.b2 * d02[l];
    }
  }
  for (std::size_t l = 0; l < plus.size(); ++l) e.alpha2[l] = (plus[l] + minus[l]) / 2, e.alpha3[l] = (plus[l] - minus[l]) / 2;
  return e;
}

DeltaM delta_m(const PhaseExpansion& full, int L) {
  if (full.order() < L + 1)
    throw std::invalid_argument(fmt::format("delta_m: the expansion has order {}, truncation at {} needs {}",
                                            full.order(), L, L + 1));
  DeltaM out;
  const auto Lp = static_cast<std::size_t>(L) + 1;
  out.f = full.alpha1[Lp] / (2.0 * L + 3);
  const double scale = 1 / (1 - out.f);
  PhaseExpansion& t = out.truncated;
  for (std::size_t l = 0; l < Lp; ++l) {
    const double peak = out.f * (2.0 * static_cast<double>(l) + 1);
    // a2 = a3 = a1 in the peak; a2 + a3 lives on d^l_22 from l = 2 (d^l_22(1) = 1 there).
    const double plus = full.alpha2[l] + full.alpha3[l] - (l >= 2 ? 2 * peak : 0.0);
    const double minus = full.alpha2[l] - full.alpha3[l];
    t.alpha1.push_back((full.alpha1[l] - peak) * scale);
    t.alpha4.push_back((full.alpha4[l] - peak) * scale);
    t.alpha2.push_back((plus + minus) / 2 * scale);
    t.alpha3.push_back((plus - minus) / 2 * scale);
    t.beta1.push_back(full.beta1[l] * scale);
    t.beta2.push_back(full.beta2[l] * scale);
  }
  return out;
}

}  // namespace polrig
