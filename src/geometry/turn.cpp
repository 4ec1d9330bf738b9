#include "polrig/geometry/turn.h"

#include <stdexcept>

#include "polrig/geometry/geometry.h"

namespace polrig {

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
