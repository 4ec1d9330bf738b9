#pragma once
// The central-symmetry (CS) study (spec §3; Wang et al. 2019 §3.2, Figs. 8–12).
//
// Over a full turn of the table, ΔV_br(θ_R) = V − V_ideal is the voltage deviation that the
// rig's eccentricity causes (Eq. 5, through the rig's amplifiers; V_ideal: sim/simulate.h's
// ideal_irradiance: the source's uniform level, or the coaxial rig's voltages), and the CS average is
// ΔV_mr(θ_R) = [ΔV_br(θ_R) + ΔV_br(θ_R + 180°)]/2. BSD and ASD are the population standard
// deviations of ΔV_br and ΔV_mr over the turn; the expectations are their means.
// Noise and the ADC do not enter: this is the deterministic bias the calibration must absorb.
#include <array>
#include <vector>

#include "polrig/geometry/turn.h"
#include "polrig/progress.h"
#include "polrig/rig/rig.h"

namespace polrig {

struct CsPairSummary {
  double bsd_mV = 0, asd_mV = 0;
  double mean_br_mV = 0, mean_mr_mV = 0;
  double eq6_mV = 0;  // Eq. 6's CS constant, through the pair's amplifier gain kv_i (NaN without a closed form)
  // A source with several shifts: the figures are those of the curves averaged over the shifts,
  // and these are the standard errors of the per-shift figures (0 for cos4). The per-pose
  // sampling noise that remains in the averaged curves is not in them (docs/validation.md).
  double bsd_se_mV = 0, asd_se_mV = 0, mean_br_se_mV = 0, mean_mr_se_mV = 0;
};
using CsSummary = std::array<CsPairSummary, 3>;

// Deviations below this are rounding (a centred rig's are ~1e-14 mV): ratios over them are NaN.
inline constexpr double kCsRounding_mV = 1e-9;
// A sweep's ratios (sweep.csv), in %: ASD/BSD, and Eq. 6's deviation from the expectation
// after CS, (eq6 − mean_mr)/mean_mr; NaN where the denominator is below kCsRounding_mV.
double asd_bsd_pct(const CsPairSummary& s);
double eq6_dev_pct(const CsPairSummary& s);

struct CsStudy {
  // What the rig's source can do (Source::flags): reports choose their columns from them.
  bool standard_errors = false;  // per-value standard errors (several shifts)
  bool coaxial_reference = false;  // ΔV refers to the coaxial rig (no uniform reference)
  bool eq6 = true;               // Eq. 6's closed form exists (else eq6_mV is NaN)
  std::vector<double> theta_R_deg;
  std::array<std::vector<double>, 3> dv_br_V, dv_mr_V;  // per pair, per table angle
  std::array<std::vector<double>, 3> dv_br_se_V, dv_mr_se_V;  // their standard errors
  CsSummary summary;
  // coaxial_reference: the coaxial rig's own deviations from the nominal model's uniform light
  // (the port's radiance pattern and the films' obliquity as a sensor on the axis sees them
  // turn); no eccentricity in them, and CS does not remove their second harmonic.
  CsSummary coaxial{};
};

// Reports the source's preparation (a traced sphere solve) and the poses to `progress`.
CsStudy cs_study(const Rig& rig, const CsTurn& turn, const Progress& progress = {});

// The summary alone, for sweeps. `scratch` is reused between calls to avoid allocation.
CsSummary cs_summary(const Rig& rig, const CsTurn& turn, std::vector<double>& scratch);

// Eq. 6 (where the source has it, Source::kClosedFormEq6; else NaN): ΔV_mr ≈ 2·kv_i·v_dec·log10[(L_o² + L_Rh² + L_IS²)/(L_o² + L_Rj² + L_IS²)], with
// L_Rm = |O_R P_m| (fixed during the turn). For kv = 1 and v_dec = 0.5 V this is the paper's
// log10[(L_o² + L_R2² + L_IS²)/(L_o² + L_R1² + L_IS²)] for pair 1.
double eq6_constant_V(const Rig& rig, int pair);

}  // namespace polrig
