#pragma once
// "Did you mean …?" for a mistyped name: the known name nearest to what was typed.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace polrig {

// The edit distance between a and b counting insertions, deletions, substitutions and swaps of
// two neighbours, each as one (optimal string alignment).
std::size_t edit_distance(std::string_view a, std::string_view b);

// The name in `known` nearest to `typed`, if it is near enough to be a typo: at most 1 edit for
// names of up to 4 characters, 2 up to 8, 3 beyond (a rig key path's section does not widen it).
// Ties go to the first.
std::optional<std::string> nearest_name(std::string_view typed, const std::vector<std::string>& known);

// " (did you mean 'NAME'?)" for the nearest name, or "" when none is near.
std::string did_you_mean(std::string_view typed, const std::vector<std::string>& known);

}  // namespace polrig
