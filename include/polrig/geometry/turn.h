#pragma once
// One full turn of the table in equal steps (the CS study's turn, spec §3).
#include <vector>

namespace polrig {

// The table angles of one full turn, k·360°/steps, and their rotations: computed once and
// shared by every rig of a sweep.
class CsTurn {
 public:
  explicit CsTurn(int steps_per_turn = 360);  // steps must be even: θ_R + 180° is a step
  int steps() const { return static_cast<int>(cos_.size()); }
  double theta_R_deg(int k) const { return 360.0 * k / steps(); }
  // cos θ_R and sin θ_R of every step, as separate arrays so loops over them vectorize.
  const double* cos_theta() const { return cos_.data(); }
  const double* sin_theta() const { return sin_.data(); }

 private:
  std::vector<double> cos_, sin_;
};

}  // namespace polrig
