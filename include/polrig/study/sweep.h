#pragma once
// Sweeps of the CS study over a grid of rig keys (paper Figs. 10–12).
#include <cstddef>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/ranks.h"
#include "polrig/rig/keys.h"
#include "polrig/study/cs.h"

namespace polrig {

// One axis of a sweep's grid: either `--grid key=start:stop:count`, count values linearly
// spaced, both ends included (computed on demand, never stored), or an explicit list of values
// (shared, so that the axis stays a cheap value type). start and stop are the first and last value.
struct GridAxis {
  const RigKey* key = nullptr;  // a real-valued rig key
  double start = 0, stop = 0;
  int count = 1;
  std::shared_ptr<const std::vector<double>> values;  // the explicit values; null for start:stop:count

  // Throws RigError naming the argument, also when a value is outside the key's range (each
  // value is computed and given to the key's own check).
  static GridAxis parse(std::string_view arg);
  // The explicit values of `key` in this order (1 to 1e8 of them). Throws RigError naming the
  // key, and the index and value of the first value the key's own check refuses (NaN included).
  static GridAxis list(std::string_view key, std::vector<double> values);
  double value(int index) const;
  std::string text() const;  // "key=start:stop:count", or "key=[first … last] (count values)"
};

// v rounded to 15 significant decimal digits: the double nearest to {fmt}'s "{:.15g}" of v,
// computed without text (exactly, for |v| in [1e-8, 1e15); by formatting outside).
double round_to_15_digits(double v);

// The grid of the axes in row-major order (the last axis varies fastest).
std::size_t grid_points(const std::vector<GridAxis>& axes);
std::vector<int> grid_indices(const std::vector<GridAxis>& axes, std::size_t point);

// A whole sweep in memory, for small grids (tests, benchmarks). Commands stream instead.
struct SweepResult {
  std::vector<GridAxis> axes;
  std::vector<CsSummary> summaries;  // grid order
  std::size_t points() const { return summaries.size(); }
  std::vector<int> indices(std::size_t p) const { return grid_indices(axes, p); }
};

using SweepProgress = std::function<void(std::size_t done, std::size_t total)>;
// Receives the summaries of grid points first, first + 1, …, in grid order, a block at a time.
using SweepSink = std::function<void(std::size_t first, std::span<const CsSummary> block)>;

// The sweep's blocks: points [b·size, (b+1)·size) form block b, the last one shorter. A pure
// function of the grid's size (never of threads or ranks): blocks are the unit of computation,
// of output, and of resuming an interrupted sweep.
std::size_t sweep_block_size(std::size_t total_points);

struct SweepOptions {
  // Resuming: the points before first_point are done and not computed again. A block boundary
  // (a multiple of sweep_block_size), or the grid's size.
  std::size_t first_point = 0;
  // The processes that share the work (docs/scale.md): every block is cut into one contiguous
  // shard per rank, and rank 0 gathers the shards; `sink` and `progress` are called on rank 0
  // only, with every block in grid order. Every rank must call sweep() with the same arguments
  // (and first_point). An error on any rank is thrown on every rank: that of the lowest failing
  // rank, which holds the first bad point in grid order. Null: this process alone.
  const Ranks* ranks = nullptr;
};

// The checks that need no computation: the grid's size, what a traced rig cannot sweep, and the
// rig's cross-key rules (check_rig) at every corner of the grid. Throws RigError.
void check_grid(const Rig& base, const std::vector<GridAxis>& axes);

// Runs the CS study at every grid point, in blocks computed in parallel and handed to `sink` in
// grid order, so memory does not grow with the grid. check_grid first; each point is checked
// against check_rig before it is computed, and the first bad point (in grid order) throws
// RigError naming it. Results do not depend on the thread count.
void sweep(const Rig& base, const std::vector<GridAxis>& axes, const CsTurn& turn,
           const SweepSink& sink, const SweepProgress& progress = {}, const SweepOptions& options = {});
SweepResult sweep(const Rig& base, const std::vector<GridAxis>& axes, const CsTurn& turn,
                  const SweepProgress& progress = {});
// The sweep as `polrig sweep` and Rig.sweep run it: prepares the rig's light (a traced light
// reports its own stages), then reports the stage "sweep: grid points" on `progress`.
void sweep(const Rig& base, const std::vector<GridAxis>& axes, const CsTurn& turn,
           const SweepSink& sink, const Progress& progress, const SweepOptions& options = {});

// The swept keys the CS study does not read, in axis order: every point along such an axis
// repeats the same result (the CLI notes it, Python warns).
std::vector<const RigKey*> axes_the_cs_study_ignores(const std::vector<GridAxis>& axes);

}  // namespace polrig
