#include "polrig/geometry/turn.h"

#include <stdexcept>

#include <fmt/format.h>

#include "polrig/geometry/geometry.h"

namespace polrig {

std::optional<std::string> cs_steps_problem(long long steps) {
  if (steps < 2 || steps > kMaxCsSteps || steps % 2 != 0)
    return fmt::format("expected an even number of table angles per turn in [2, {}]", kMaxCsSteps);
  return std::nullopt;
}

CsTurn::CsTurn(int steps_per_turn) {
  if (steps_per_turn < 2 || steps_per_turn % 2 != 0)
    throw std::invalid_argument("a CS turn needs an even number of steps ≥ 2");
  for (int k = 0; k < steps_per_turn; ++k) {
    const TableRotation r = TableRotation::at_deg(360.0 * k / steps_per_turn);
    cos_.push_back(r.c);
    sin_.push_back(r.s);
  }
}

}  // namespace polrig
