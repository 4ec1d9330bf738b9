#pragma once
// The accuracy limit that the ADC alone sets (spec §2, paper §2.4 and Fig. 6): an ideal sensor
// (theory parameters, uniform light, no noise) whose voltages pass through Eq. 3.
#include <array>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/device/electronics.h"
#include "polrig/progress.h"

namespace polrig {

// `polrig study adc`'s defaults: the degrees of polarization (`--d`) and the θ step (`--step`).
inline constexpr std::string_view kDefaultAdcD = "0.05:0.95:19";
inline constexpr double kDefaultAdcStep = 0.1;  // deg
inline constexpr double kMinAdcStep = 1e-4, kMaxAdcStep = 10.0;  // deg
// The most values of d one study takes, and the most θ steps over all of them (d values × 180° /
// step): 2e9 steps take about 10 minutes on one core.
inline constexpr int kMaxAdcD = 1'000'000;
inline constexpr double kMaxAdcSteps = 2e9;

// `--d`'s text: "a,b,c" (each a finite number) or "start:stop:count" (read as `--grid
// device.d=start:stop:count`), every value in (0, 1), at most kMaxAdcD of them. Throws RigError
// "--d TEXT: why".
std::vector<double> parse_d_list(std::string_view text);
// What is wrong with degrees of polarization given as values: "element 1 is 1; expected
// degrees of polarization in (0, 1)", or "expected at least one degree of polarization";
// nullopt when every one is in (0, 1).
std::optional<std::string> d_values_problem(std::span<const double> ds);

struct AdcLimit {
  double d;
  double vmax_mV;    // largest pair voltage over θ (unquantized)
  double limit_deg;  // max |θ12 − θ| over θ ∈ [0°, 180°) in `step_deg` steps, quantized voltages
};

AdcLimit adc_accuracy_limit(double d, const Electronics& e,
                            const std::array<double, 6>& film_axis_deg, double step_deg = kDefaultAdcStep);

// What is wrong with a study of `d_count` values of d at `step_deg`: more than kMaxAdcSteps θ
// steps in all ("… 1.8e+11 θ steps; at most 2e+09: fewer values of d or a larger step").
std::optional<std::string> adc_work_problem(std::size_t d_count, double step_deg);

// adc_accuracy_limit for each of `ds`, in order (in parallel; the same values for any thread
// count). Reports the stage "study adc: values of d".
std::vector<AdcLimit> adc_accuracy_limits(std::span<const double> ds, const Electronics& e,
                                          const std::array<double, 6>& film_axis_deg,
                                          double step_deg = kDefaultAdcStep,
                                          const Progress& progress = {});

// The θ12 error curve behind one limit (paper Fig. 5): θ and θ12 − θ in degrees.
struct AdcErrorCurve {
  std::vector<double> theta_deg, error_deg;
};
AdcErrorCurve adc_error_curve(double d, const Electronics& e,
                              const std::array<double, 6>& film_axis_deg, double step_deg = kDefaultAdcStep);

}  // namespace polrig
