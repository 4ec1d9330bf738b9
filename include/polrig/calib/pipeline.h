#pragma once
// The paper's calibration (Wang et al. 2019 §4, Fig. 14): preprocessing, least squares,
// decoupling, and the accuracy of the result, for the three calibration types.
#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/calib/fit.h"
#include "polrig/calib/preprocess.h"

namespace polrig {

enum class CalibrationMethod {
  Section,                       // type 1: the raw stops, section algorithm only
  CentralSymmetry,               // type 2: CS points + section
  CentralSymmetryNoncontinuous,  // type 3: CS points, noncontinuous selection + section
  Noncontinuous                  // outdoors (§5.1): the raw stops, noncontinuous selection + section
};
std::string_view method_name(CalibrationMethod m);  // "section", "cs", "cs-nc", "nc"
std::optional<CalibrationMethod> parse_method(std::string_view name);
// Whether the method fits the raw stops (section, nc) rather than CS points. A CS point averages
// two stops half a turn apart, taken at two times: only the raw-stop methods take per-stop drift
// corrections or a light that changes during the run (the sky).
bool uses_raw_stops(CalibrationMethod m);
// The paper's three indoor calibration types (Fig. 14), as `--method all` and the studies run them.
inline constexpr std::array<CalibrationMethod, 3> kAllMethods{
    CalibrationMethod::Section, CalibrationMethod::CentralSymmetry,
    CalibrationMethod::CentralSymmetryNoncontinuous};

// Per-stop corrections for a light that changes during the run (the sky: spec
// sky-and-compasses.md §1.4), one entry per stop in the order of the stops given to calibrate():
// the reference angle of stop k becomes θ_R,k + dtheta_deg[k] (sensor frame, docs/physics.md §1),
// and the fitted model sees d·d_ratio[k] (Eq. 15's c_m·d_ratio[k]). Empty vectors: none (a
// constant source; results bit-identical to a calibration without corrections). Only the
// methods on raw stops (section, nc) take them: a CS point mixes two times.
struct StopCorrections {
  std::vector<double> dtheta_deg;
  std::vector<double> d_ratio;
  std::string source;  // how they were made, for params.yaml ("per-stop: …"); "" without them
  bool empty() const { return dtheta_deg.empty() && d_ratio.empty(); }
};

struct CalibrationOptions {
  CalibrationMethod method = CalibrationMethod::CentralSymmetryNoncontinuous;
  std::optional<double> d_a;  // the rig's stated d; without it, max_m c_m (best film ideal)
  std::string d_a_source = "given";  // where d_a came from, for params.yaml
  NoncontinuousRule noncontinuous;
  std::array<double, 6> film_axis_deg = kWang2019FilmAxesDeg;  // for the nominal start
  double volts_per_decade = 0.5;
  FitOptions fit;
  StopCorrections corrections;
};

// A point at which a calibration is judged: the reference angle (the table angle) and the
// voltages there (a raw stop, or a CS point).
struct EvalPoint {
  double theta_ref_deg;
  std::array<double, 3> V;
  double d_ratio = 1.0;  // d at this point over d at the first stop (StopCorrections)
};

// θ12, θ13, θ23 and θ_sec minus the reference angle, each wrapped into [−90°, 90°).
struct AngleErrors {
  double theta_ref_deg;
  double e12_deg, e13_deg, e23_deg, esec_deg;
  int section;
  double d;  // the degree of polarization θ_sec's pair implies (scale set by d_a)
};

struct AngleAccuracy {
  double max_deg = 0, min_deg = 0;
  double accuracy_deg() const { return 0.5 * (max_deg - min_deg); }  // paper §4.5: ±half range
};
enum AngleIndex { kTheta12 = 0, kTheta13 = 1, kTheta23 = 2, kThetaSec = 3 };

struct CalibrationResult {
  CalibrationMethod method;
  FitResult fit;
  double d_a = 0;
  std::string d_a_source;            // "given" or how it was chosen
  std::string drift;                 // StopCorrections::source ("" without corrections)
  CalibrationParams params;          // decoupled with d_a
  CalibrationParams standard_error;  // kd's from c's: se(c_m)/d_a
  std::vector<EvalPoint> points;     // raw stops (type 1) or CS points (types 2, 3)
  std::vector<std::vector<bool>> fitted;  // fitted[i][n]: V_{i+1} of point n entered the fit
  std::vector<AngleErrors> errors;   // at every point
  std::array<AngleAccuracy, 4> accuracy;  // θ12, θ13, θ23, θ_sec
  bool usable() const { return fit.summary.usable(); }
};

// Runs one calibration type on the stops. A fit that fails is data: the result's fit.summary
// says why (too few points, no convergence, outside Eq. 15's domain, rank deficient, d too
// small), and only when fit.summary.usable() are params, errors and accuracy filled in.
// Throws CalibrationError when the stops cannot form the points at all (unpaired CS stops) or
// the decoupling d_a is outside (0, 1).
CalibrationResult calibrate(const std::vector<StopVoltages>& stops,
                            const CalibrationOptions& options);

std::vector<AngleErrors> angle_errors(const CalibrationParams& p, double volts_per_decade,
                                      const std::vector<EvalPoint>& points);
std::array<AngleAccuracy, 4> accuracy_of(const std::vector<AngleErrors>& errors);

// The replacement analysis (§4.6, Fig. 21): the θ_sec accuracy with each subset of
// {α, k, kv, kd} put back to its theory value, for all 16 subsets.
struct Replacement {
  std::string label;  // "none", "α", "k-kv", …, "α-k-kv-kd"
  unsigned mask;      // bit 0 α, bit 1 k, bit 2 kv, bit 3 kd
  double accuracy_deg;
};
std::vector<Replacement> replacement_analysis(const CalibrationParams& calibrated,
                                              const CalibrationParams& theory,
                                              double volts_per_decade,
                                              const std::vector<EvalPoint>& points);

}  // namespace polrig
