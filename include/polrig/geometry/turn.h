#pragma once
// One full turn of the table in equal steps (the CS study's turn, spec §3).
#include <optional>
#include <string>
#include <vector>

namespace polrig {

inline constexpr int kDefaultCsSteps = 360;     // table angles per turn of a CS study: 1° apart
inline constexpr int kMaxCsSteps = 3600000;     // 0.0001° apart

// What is wrong with `steps` as the table angles per turn of a CS study (`--steps`, steps=):
// "expected an even number of table angles per turn in [2, 3600000]"; nullopt when valid.
std::optional<std::string> cs_steps_problem(long long steps);

// The table angles of one full turn, k·360°/steps, and their rotations: computed once and
// shared by every rig of a sweep.
class CsTurn {
 public:
  explicit CsTurn(int steps_per_turn = kDefaultCsSteps);  // steps must be even: θ_R + 180° is a step
  int steps() const { return static_cast<int>(cos_.size()); }
  double theta_R_deg(int k) const { return 360.0 * k / steps(); }
  // cos θ_R and sin θ_R of every step, as separate arrays so loops over them vectorize.
  const double* cos_theta() const { return cos_.data(); }
  const double* sin_theta() const { return sin_.data(); }

 private:
  std::vector<double> cos_, sin_;
};

}  // namespace polrig
