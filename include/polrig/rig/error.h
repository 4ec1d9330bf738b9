#pragma once
// The error of a bad rig: a rig file, an override, a grid of rig keys or a scene the rig names.
#include <stdexcept>
#include <string_view>

namespace polrig {

// Any problem with a rig file or an override. what() is the complete message for the user.
class RigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Number parsing shared by rig files, --set and --grid: a finite double, or a RigError naming
// `what`.
double parse_finite_number(std::string_view text, std::string_view what);

}  // namespace polrig
