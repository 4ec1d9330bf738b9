#pragma once
// A study's failure on one rank, carried to every rank by Ranks::first_failure (text) and thrown
// there as the same kind of error one process alone would throw (RigError: exit 2,
// CalibrationError: exit 3, a std::logic_error (a programming error) as one, anything else a
// std::runtime_error), with the same message.
#include <exception>
#include <stdexcept>
#include <string>

#include "polrig/calib/fit.h"
#include "polrig/rig/error.h"

namespace polrig {

inline std::string rank_failure_text(const std::exception& e) {
  const char kind = dynamic_cast<const RigError*>(&e)           ? 'R'
                    : dynamic_cast<const CalibrationError*>(&e) ? 'C'
                    : dynamic_cast<const std::logic_error*>(&e) ? 'L'
                                                                : 'E';
  return kind + std::string(e.what());
}

[[noreturn]] inline void throw_rank_failure(const std::string& text) {
  const std::string message = text.empty() ? text : text.substr(1);
  if (!text.empty() && text[0] == 'R') throw RigError(message);
  if (!text.empty() && text[0] == 'C') throw CalibrationError(message);
  if (!text.empty() && text[0] == 'L') throw std::logic_error(message);
  throw std::runtime_error(message);
}

}  // namespace polrig
