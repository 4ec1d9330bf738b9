#pragma once
// An aerosol's scattering matrix: read from a table over the scattering angle, expanded in
// generalized spherical functions, and truncated by δ-M (spec skies.md §2 "Aerosols";
// docs/physics.md §24).
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/sky/phase_matrix.h"

namespace polrig {

// A phase-matrix file that cannot be taken: what() names the file, the line and the column.
struct PhaseMatrixError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The six elements at rising scattering angles from 0° to 180° (docs/formats.md §6.22: rows
// `theta_deg P1 P2 P3 P4 P5 P6` with P = [[P1, P2], [P2, P5]] ⊕ [[P3, P4], [−P4, P6]], IPRT's
// layout), rescaled so that a1 averages exactly 1 over the sphere.
struct PhaseMatrixTable {
  std::string source;                      // the file, for messages
  std::vector<double> theta_deg;           // rising, 0 … 180
  std::vector<ScatteringElements> elements;
  double normalization_as_read = 1;        // ½∫P1 dcosΘ of the file's numbers (trapezoid in Θ)
  // The elements at cos Θ, linear in Θ between rows.
  ScatteringElements at(double cos_theta) const;
};

// The file's table. Throws PhaseMatrixError for a row that is not seven finite numbers, angles
// that do not rise from 0° to 180°, an element larger than P1 (|P_i| ≤ P1 for any scatterer),
// a P1 ≤ 0, or a normalization ½∫P1 dcosΘ more than 1 % from 1.
PhaseMatrixTable parse_phase_matrix(std::string_view text, std::string_view file);
PhaseMatrixTable read_phase_matrix(const std::filesystem::path& path);

// Wigner's d^l_{mn}(x) for l = 0 … l_max (zero below max(|m|, |n|)), x = cos Θ, by the
// three-term recurrence in l (Mishchenko, Travis & Lacis 2002, Eq. B.22); the pairs the
// expansion uses: (0, 0), (0, 2), (2, 2), (2, −2).
std::vector<double> wigner_d(int l_max, int m, int n, double x);

// The expansion of a scattering matrix in generalized spherical functions (de Rooij & van der
// Stap 1984; Hovenier, van der Mee & Domke 2004 §2.8), l = 0 … size − 1:
//   a1 = Σ α1_l d^l_00,   a2 + a3 = Σ (α2 + α3)_l d^l_22,   a2 − a3 = Σ (α2 − α3)_l d^l_{2,−2},
//   a4 = Σ α4_l d^l_00,   b1 = Σ β1_l d^l_02,               b2 = Σ β2_l d^l_02,
// so that α1_0 = 1 for a normalised a1 and α1_1 = 3g (g the asymmetry parameter).
struct PhaseExpansion {
  std::vector<double> alpha1, alpha2, alpha3, alpha4, beta1, beta2;
  int order() const { return static_cast<int>(alpha1.size()) - 1; }
  ScatteringElements at(double cos_theta) const;
};

// The coefficients l ≤ l_max of the table, by its trapezoid rule in Θ (the table's own grid).
PhaseExpansion expand(const PhaseMatrixTable& table, int l_max);

// δ-M (Wiscombe 1977, vector form as Hovenier et al. 2004 §2.8): the fraction f = α1_{L+1}/(2L + 3)
// of the scattering in the forward peak is moved to the direct beam, and the rest, truncated at
// l = L, renormalised: the peak is f·2δ(1 − cos Θ) times the unit matrix, so
// α'_l = (α_l − f(2l + 1))/(1 − f) for α1, α4 and (from l = 2, where d^l_22 starts) α2 and α3,
// α'_l = α_l/(1 − f) for the rest and for β1, β2 (d^l_02(1) = d^l_{2,−2}(1) = 0). The layer then has
// τ' = (1 − ϖf)τ and ϖ' = (1 − f)ϖ/(1 − ϖf). `full` needs the coefficients to L + 1.
struct DeltaM {
  double f = 0;
  PhaseExpansion truncated;  // l = 0 … L
};
DeltaM delta_m(const PhaseExpansion& full, int L);

}  // namespace polrig
