#pragma once
// Sweeps of the CS study over a grid of rig keys (paper Figs. 10–12).
#include <cstddef>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/rig/keys.h"
#include "polrig/study/cs.h"

namespace polrig {

// One `--grid key=start:stop:count`: count values linearly spaced, both ends included.
struct GridAxis {
  const RigKey* key = nullptr;  // a real-valued rig key
  double start = 0, stop = 0;
  int count = 1;

  static GridAxis parse(std::string_view arg);  // throws RigError naming the argument
  double value(int index) const;
  std::string text() const;
};

struct SweepResult {
  std::vector<GridAxis> axes;
  // Grid points in row-major order: the last axis varies fastest.
  std::vector<CsSummary> summaries;
  std::size_t points() const { return summaries.size(); }
  // The index of each axis at grid point p.
  std::vector<int> indices(std::size_t p) const;
};

using SweepProgress = std::function<void(std::size_t done, std::size_t total)>;

// Checks every grid point against the rig's rules; throws RigError naming the first bad point.
void check_grid(const Rig& base, const std::vector<GridAxis>& axes);

// Checks the grid (check_grid), then runs the CS study at each point in parallel. Results do not
// depend on the thread count.
SweepResult sweep(const Rig& base, const std::vector<GridAxis>& axes, const CsTurn& turn,
                  const SweepProgress& progress = {});

}  // namespace polrig
