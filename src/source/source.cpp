#include "polrig/source/source.h"

#include <vector>

#include "polrig/vector_log.h"

namespace polrig {

void Source::prepare(const Progress&) const {}

std::array<double, 6> Source::ideal_irradiance(const SourceView& rig, const SourcePose& pose) const {
  Eccentricity coaxial = rig.eccentricity;  // port and sensor on the table's axis
  coaxial.L_IS = 0;
  coaxial.L_S = 0;
  const int S = shifts();
  std::vector<double> E(static_cast<std::size_t>(6 * S));
  irradiance({rig.sensor, coaxial, rig.settings}, pose, E);
  std::array<double, 6> mean{};
  for (std::size_t m = 0; m < 6; ++m) {
    double sum = 0;
    for (int k = 0; k < S; ++k) sum += E[static_cast<std::size_t>(k) * 6 + m];
    mean[m] = sum / static_cast<double>(S);
  }
  return mean;
}

void Source::irradiance_over_turn(const SourceView& rig, const CsTurn& turn, std::span<double> E,
                                  const Progress& progress) const {
  const int n = turn.steps(), S = shifts();
  std::vector<double> e(static_cast<std::size_t>(6 * S));
  for (int k = 0; k < n; ++k) {
    irradiance(rig, {turn.theta_R_deg(k), 0.0}, e);
    for (int j = 0; j < 6 * S; ++j) E[static_cast<std::size_t>(j * n + k)] = e[static_cast<std::size_t>(j)];
    progress.advance(6);
  }
}

void pair_log_ratios(const double* E, int n, double* out) {
  for (int i = 0; i < 3; ++i) {
    const double* Ej = E + pair_j(i) * n;
    const double* Eh = E + pair_h(i) * n;
    double* r = out + i * n;
    for (int k = 0; k < n; ++k) r[k] = Ej[k] / Eh[k];
  }
  log_array(out, out, static_cast<std::size_t>(3 * n));
}

void Source::log_ratio_over_turn(const SourceView& rig, const CsTurn& turn, std::span<double> out) const {
  const int n = turn.steps();
  std::vector<double> E(static_cast<std::size_t>(6 * shifts() * n));
  irradiance_over_turn(rig, turn, E);
  pair_log_ratios(E.data(), n, out.data());
}

std::unique_ptr<const LightAlongViews> Source::light_along_views(const SourceView&, const SourcePose&) const {
  throw std::logic_error(std::string("the ") + std::string(kind()) +
                         " source gives no light along views (it lacks kStokesAlongViews)");
}

double Source::eq6_log_ratio(const SourceView&, int) const {
  throw std::logic_error("Eq. 6's closed form belongs to the cos⁴ source only");
}

std::array<double, 3> Source::eq6_log_ratios(const SourceView& rig) const {
  return {eq6_log_ratio(rig, 0), eq6_log_ratio(rig, 1), eq6_log_ratio(rig, 2)};
}

}  // namespace polrig
