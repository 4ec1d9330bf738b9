#include "polrig/study/adc_limit.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "polrig/calib/angles.h"
#include "polrig/device/sensor.h"
#include "polrig/rig/error.h"
#include "polrig/study/sweep.h"
#include "polrig/units.h"

namespace polrig {

AdcErrorCurve adc_error_curve(double d, const Electronics& e,
                              const std::array<double, 6>& film_axis_deg, double step_deg) {
  const CalibrationParams theory = CalibrationParams::theory(film_axis_deg);
  const std::array<double, 6> uniform{1, 1, 1, 1, 1, 1};
  AdcErrorCurve curve;
  const int n = static_cast<int>(std::llround(180.0 / step_deg));
  for (int k = 0; k < n; ++k) {
    const double theta = k * step_deg;
    std::array<double, 3> V = pair_voltages(theory, e, uniform, theta, d);
    for (double& v : V) v = adc_quantize(v, e);
    const PairAngle t12 = pair_angle(theory, e, V, 0, 1);
    curve.theta_deg.push_back(theta);
    curve.error_deg.push_back(axis_difference_deg(t12.theta_deg, theta));
  }
  return curve;
}

AdcLimit adc_accuracy_limit(double d, const Electronics& e,
                            const std::array<double, 6>& film_axis_deg, double step_deg) {
  const AdcErrorCurve curve = adc_error_curve(d, e, film_axis_deg, step_deg);
  const CalibrationParams theory = CalibrationParams::theory(film_axis_deg);
  const std::array<double, 6> uniform{1, 1, 1, 1, 1, 1};
  double vmax = 0.0, limit = 0.0;
  for (std::size_t k = 0; k < curve.theta_deg.size(); ++k) {
    for (double v : pair_voltages(theory, e, uniform, curve.theta_deg[k], d))
      vmax = std::max(vmax, std::abs(v));
    limit = std::max(limit, std::abs(curve.error_deg[k]));
  }
  return {d, vmax * 1e3, limit};
}

std::optional<std::string> adc_work_problem(std::size_t d_count, double step_deg) {
  const double steps = static_cast<double>(d_count) * std::llround(180.0 / step_deg);
  if (steps <= kMaxAdcSteps) return std::nullopt;
  return fmt::format("{} values of d at a {}° step are {:.3g} θ steps; at most {:.3g}: fewer values of d or a "
                     "larger step", d_count, step_deg, steps, kMaxAdcSteps);
}

std::vector<AdcLimit> adc_accuracy_limits(std::span<const double> ds, const Electronics& e,
                                          const std::array<double, 6>& film_axis_deg,
                                          double step_deg, const Progress& progress) {
  std::vector<AdcLimit> limits(ds.size());
  progress.begin("study adc: values of d", static_cast<long long>(ds.size()));
  tbb::parallel_for(std::size_t{0}, ds.size(), [&](std::size_t i) {
    limits[i] = adc_accuracy_limit(ds[i], e, film_axis_deg, step_deg);
    progress.advance();
  });
  progress.finish();
  return limits;
}

namespace {
bool is_degree_of_polarization(double d) { return d > 0.0 && d < 1.0; }
}  // namespace

std::vector<double> parse_d_list(std::string_view text) {
  const auto fail = [&](const std::string& why) -> std::vector<double> {
    throw RigError(fmt::format("--d {}: {}", text, why));
  };
  std::vector<double> ds;
  if (text.find(':') != std::string_view::npos) {
    if (std::count(text.begin(), text.end(), ':') != 2)
      return fail("expected a,b,c or start:stop:count");
    GridAxis axis;
    try {
      axis = GridAxis::parse("device.d=" + std::string(text));
    } catch (const RigError& e) {
      const std::string msg = e.what();
      return fail(msg.substr(msg.find(": ") + 2));  // drop the --grid prefix
    }
    if (axis.count > kMaxAdcD)
      return fail(fmt::format("{} values of d; at most {}", axis.count, kMaxAdcD));
    for (int i = 0; i < axis.count; ++i) ds.push_back(axis.value(i));
    return ds;
  }
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t comma = std::min(text.find(',', pos), text.size());
    double d = 0;
    try {
      d = parse_finite_number(text.substr(pos, comma - pos), "value");
    } catch (const RigError& e) {
      return fail(e.what());
    }
    if (!is_degree_of_polarization(d))
      return fail(fmt::format("expected degrees of polarization in (0, 1), got {}", d));
    ds.push_back(d);
    if (ds.size() > static_cast<std::size_t>(kMaxAdcD))
      return fail(fmt::format("more than {} values of d", kMaxAdcD));
    pos = comma + 1;
  }
  return ds;
}

std::optional<std::string> d_values_problem(std::span<const double> ds) {
  for (std::size_t i = 0; i < ds.size(); ++i)
    if (!is_degree_of_polarization(ds[i]))
      return fmt::format("element {} is {}; expected degrees of polarization in (0, 1)", i, ds[i]);
  if (ds.empty()) return "expected at least one degree of polarization";
  return std::nullopt;
}

}  // namespace polrig
