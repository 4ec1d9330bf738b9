#pragma once
// The cos⁴ port as a Source (source.model: cos4): E_m = E_0·cos⁴φ_m at each photodiode
// (source/cos4.h), the light's angle from the port polarizer (θ = θ_R − ψ_P) and its degree the
// rig's device.d. Its ideal irradiance is the uniform E_0, and Eq. 6 holds in closed form.
#include "polrig/source/source.h"

namespace polrig {

class Cos4PortSource final : public Source {
 public:
  std::string_view kind() const override { return "cos4"; }
  unsigned flags() const override { return kClosedFormEq6 | kUniformReference | kStokesAlongViews; }
  // The port fills every view (a camera looking up into it): uniform radiance S0 = E_0, polarized
  // by the port polarizer ψ_P with the rig's device.d; the E-vector along a view is the polarizer's
  // axis (cos ψ_P, sin ψ_P, 0) projected ⊥ the view (an ideal sheet polarizer). A view that does
  // not look up (v_z ≥ 0 in the rig frame) sees no light. The camera's axes at θ_R:
  // X = Rot(θ_R)·x̂, Y = −Rot(θ_R)·ŷ, Z = −ẑ (docs/physics.md §13).
  std::unique_ptr<const LightAlongViews> light_along_views(const SourceView& rig,
                                                           const SourcePose& pose) const override;
  Polarization polarization(const SourceView& rig, const SourcePose& pose) const override;
  void irradiance(const SourceView& rig, const SourcePose& pose, std::span<double> E) const override;
  std::array<double, 6> ideal_irradiance(const SourceView& rig, const SourcePose& pose) const override;
  // cos⁴φ alone (E_0 is the common factor), written over the turn so that it vectorizes.
  void irradiance_over_turn(const SourceView& rig, const CsTurn& turn, std::span<double> E,
                            const Progress& progress = {}) const override;
  // 2·ln(D_h/D_j), D_m = L_o² + L_m²: cos⁴'s ln(E_j/E_h) in closed form (docs/physics.md).
  void log_ratio_over_turn(const SourceView& rig, const CsTurn& turn, std::span<double> out) const override;
  // log10[(L_o² + L_Rh² + L_IS²)/(L_o² + L_Rj² + L_IS²)], L_Rm = |O_R P_m| (fixed during the turn).
  double eq6_log_ratio(const SourceView& rig, int pair) const override;
  // The three from one computation of the photodiode positions (sin and cos of the ring's angles).
  std::array<double, 3> eq6_log_ratios(const SourceView& rig) const override;
};

}  // namespace polrig
