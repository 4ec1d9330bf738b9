#include "polrig/study/sweep.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstdint>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <type_traits>
#include <limits>
#include <stdexcept>
#include <string>

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "polrig/background_writer.h"
#include "polrig/side_by_side.h"
#include "polrig/threads.h"
#include "polrig/rig/error.h"
#include "polrig/study/rank_failure.h"

namespace polrig {

namespace {
// The real-valued key `path`, or RigError from `fail`: what --grid and a list share.
template <class Fail>
const RigKey* sweepable_key(std::string_view path, const Fail& fail) {
  const RigKey* key = find_rig_key(path);
  if (!key) fail(fmt::format("unknown key '{}' (see docs/formats.md)", path));
  if (key->kind != RigKey::Kind::Real)
    fail(fmt::format("key '{}' is not a single real number and cannot be swept", path));
  return key;
}

// The index of the first of the axis's values the key's own check (or, for a list, finiteness)
// refuses, or count: every value computed, in parallel.
int first_invalid(const GridAxis& axis) {
  const bool listed = axis.values != nullptr;
  if (!axis.key->valid_real && !listed) return axis.count;
  std::atomic<int> first_bad{axis.count};
  tbb::parallel_for(tbb::blocked_range<int>(0, axis.count, 65536), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i != r.end() && i < first_bad.load(std::memory_order_relaxed); ++i) {
      const double v = axis.value(i);
      if ((listed && !std::isfinite(v)) || (axis.key->valid_real && !axis.key->valid_real(v))) {
        int seen = first_bad.load();
        while (i < seen && !first_bad.compare_exchange_weak(seen, i)) {
        }
        return;
      }
    }
  });
  return first_bad;
}
}  // namespace

GridAxis GridAxis::parse(std::string_view arg) {
  const auto fail = [&](const std::string& why) -> GridAxis {
    throw RigError(fmt::format("--grid {}: {}", arg, why));
  };
  const auto eq = arg.find('=');
  if (eq == std::string_view::npos) return fail("expected key=start:stop:count");
  const std::string_view path = arg.substr(0, eq);
  const std::string_view spec = arg.substr(eq + 1);
  GridAxis axis;
  axis.key = sweepable_key(path, fail);
  const auto c1 = spec.find(':');
  const auto c2 = c1 == std::string_view::npos ? c1 : spec.find(':', c1 + 1);
  if (c2 == std::string_view::npos) return fail("expected key=start:stop:count");
  try {
    axis.start = parse_finite_number(spec.substr(0, c1), "start");
    axis.stop = parse_finite_number(spec.substr(c1 + 1, c2 - c1 - 1), "stop");
    const double count = parse_finite_number(spec.substr(c2 + 1), "count");
    if (count < 1 || count != std::floor(count) || count > 1e8)
      throw RigError(fmt::format("count: expected a whole number in [1, 1e8], got '{}'",
                                 spec.substr(c2 + 1)));
    axis.count = static_cast<int>(count);
  } catch (const RigError& e) {
    return fail(e.what());  // parse_finite_number names only the part: "count: expected …"
  }
  if (axis.count == 1 && axis.start != axis.stop)
    return fail("a single point needs start = stop");
  // The first bad value in grid order is named.
  if (const int bad = first_invalid(axis); bad < axis.count)
    return fail(fmt::format("key '{}': expected {}, got {}", path, axis.key->expects, axis.value(bad)));
  return axis;
}

GridAxis GridAxis::list(std::string_view path, std::vector<double> values) {
  const auto fail = [&](const std::string& why) -> GridAxis {
    throw RigError(fmt::format("grid {}: {}", path, why));
  };
  GridAxis axis;
  axis.key = sweepable_key(path, fail);
  if (values.empty() || values.size() > 100'000'000)
    return fail(fmt::format("expected 1 to 1e8 values, got {}", values.size()));
  axis.count = static_cast<int>(values.size());
  axis.start = values.front();
  axis.stop = values.back();
  axis.values = std::make_shared<const std::vector<double>>(std::move(values));
  if (const int bad = first_invalid(axis); bad < axis.count)
    return fail(fmt::format("value {}: expected {}, got {}", bad, axis.key->expects, axis.value(bad)));
  return axis;
}

double round_to_15_digits(double v) {
  static constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                      1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                      1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  const auto by_text = [](double x) { return std::strtod(fmt::format("{:.15g}", x).c_str(), nullptr); };
  if (v == 0.0 || !std::isfinite(v)) return v;
  const double a = std::abs(v);
  const int binary_exponent = static_cast<int>((std::bit_cast<std::uint64_t>(a) >> 52) & 0x7ff) - 1023;
  int e = (binary_exponent * 78913) >> 18;  // ≈ floor(log10 a), corrected below
  for (int tries = 0; tries < 3; ++tries) {
    // a·10^k in [1e14, 1e15): its integer part holds the 15 digits. 10^k is exact for k ≤ 22,
    // and the product is kept exactly as hi + lo (Dekker's product).
    const int k = 14 - e;
    if (k < 0 || k > 22) return by_text(v);
    const double s = kPow10[k];
    const double hi = a * s;
    const auto split = [](double x, double& h, double& l) {
      const double c = 134217729.0 * x;  // 2^27 + 1
      h = c - (c - x);
      l = x - h;
    };
    double ah, al, sh, sl;
    split(a, ah, al);
    split(s, sh, sl);
    const double lo = ((ah * sh - hi) + ah * sl + al * sh) + al * sl;
    if (hi < 1e14 || (hi == 1e14 && lo < 0)) {
      --e;
      continue;
    }
    if (hi > 1e15 || (hi == 1e15 && lo >= 0)) {
      ++e;
      continue;
    }
    // Round hi + lo to an integer, halves to even (as {fmt} does); hi − floor(hi) is exact.
    const auto whole = static_cast<std::int64_t>(hi);  // hi < 2^50: truncation is floor
    const double above_half = (hi - static_cast<double>(whole)) - 0.5;
    std::int64_t m = whole;
    if (above_half > -lo || (above_half == -lo && (whole & 1) != 0)) m = whole + 1;
    return std::copysign(static_cast<double>(m) / s, v);  // correctly rounded, as strtod gives
  }
  return by_text(v);
}

double GridAxis::value(int index) const {
  if (values) return (*values)[static_cast<std::size_t>(index)];
  if (count == 1) return start;
  if (index == count - 1) return stop;  // exact end point
  // Weighted form, exact at both ends; then rounded to 15 significant digits, so that a decimal
  // grid such as 0.05:0.95:19 gives 0.15 and not 0.15000000000000002.
  const double n = count - 1;
  return round_to_15_digits((start * (n - index) + stop * index) / n);
}

std::string GridAxis::text() const {
  if (values) return fmt::format("{}=[{} … {}] ({} values)", key->path, start, stop, count);
  return fmt::format("{}={}:{}:{}", key->path, start, stop, count);
}

std::size_t grid_points(const std::vector<GridAxis>& axes) {
  std::size_t total = 1;
  for (const GridAxis& a : axes) total *= static_cast<std::size_t>(a.count);
  return total;
}

std::vector<int> grid_indices(const std::vector<GridAxis>& axes, std::size_t p) {
  std::vector<int> idx(axes.size());
  for (std::size_t a = axes.size(); a-- > 0;) {
    idx[a] = static_cast<int>(p % static_cast<std::size_t>(axes[a].count));
    p /= static_cast<std::size_t>(axes[a].count);
  }
  return idx;
}

namespace {
Rig rig_at(const Rig& base, const std::vector<GridAxis>& axes, const std::vector<int>& idx) {
  Rig rig = base;
  for (std::size_t a = 0; a < axes.size(); ++a) axes[a].key->real(rig) = axes[a].value(idx[a]);
  return rig;
}

RigError point_error(const std::vector<GridAxis>& axes, const std::vector<int>& idx,
                     const RigProblem& problem) {
  std::string where;
  for (std::size_t a = 0; a < axes.size(); ++a)
    where += fmt::format("{}{}={}", a ? ", " : "", axes[a].key->path, axes[a].value(idx[a]));
  return RigError(fmt::format("--grid point ({}): key '{}': {}", where, problem.path, problem.message));
}
}  // namespace

void check_grid(const Rig& base, const std::vector<GridAxis>& axes) {
  require_instrument(base, Instrument::kPairVoltages, "sweep");
  double points = 1;
  for (const GridAxis& a : axes) points *= a.count;
  if (points > 1e9)
    throw RigError(fmt::format("--grid: {:.3g} grid points; at most 1e9 (a summary row each)", points));
  // A key the rig's source or instrument does not read is refused (RigKey::sources,
  // RigKey::instruments), and so is device.d when the source sets the light's d itself (the
  // traced port film): a swept value would be unused.
  for (const GridAxis& a : axes) {
    if (!a.key->read_by_instrument(base.device_kind))
      throw RigError(fmt::format("--grid {}: device.kind {} does not read '{}' (only device.kind {} "
                                 "does); it cannot be swept", a.text(), base.device_kind, a.key->path, a.key->instruments));
    if (!a.key->read_by_source(base.source.model))
      throw RigError(fmt::format("--grid {}: source.model {} does not read '{}' (only source.model {} "
                                 "does); it cannot be swept", a.text(), base.source.model, a.key->path, a.key->sources));
    if (a.key->path == "device.d" && base.light->rig_degree_of_polarization(base.source_view()))
      throw RigError(fmt::format("--grid {}: source.model {} sets the light's d itself; 'device.d' "
                                 "cannot be swept", a.text(), base.source.model));
  }
  // The corners: the cross-key rules are monotone in each key, so a grid that breaks one
  // usually does at a corner, and is stopped before any computation. sweep() checks every point.
  std::size_t varying = 0;
  for (const GridAxis& a : axes) varying += a.count > 1;
  if (varying > 12) return;
  for (std::size_t corner = 0; corner < (std::size_t{1} << varying); ++corner) {
    std::vector<int> idx(axes.size(), 0);
    std::size_t bit = 0;
    for (std::size_t a = 0; a < axes.size(); ++a)
      if (axes[a].count > 1 && ((corner >> bit++) & 1u)) idx[a] = axes[a].count - 1;
    if (auto problem = check_rig(rig_at(base, axes, idx))) throw point_error(axes, idx, *problem);
  }
}

namespace {
// The CS summaries of grid points [begin, end) into out[0 … end − begin), one after another, or
// the index of the first point that breaks a rule of check_rig (nothing after it computed). One
// rig stepped through the grid in row-major order, setting only the keys whose index changed (in
// axis order, as rig_at does): no copy of the rig (and of its shared light) and no allocation per
// point.
std::optional<std::size_t> compute_points(const Rig& base, const std::vector<GridAxis>& axes,
                                          const CsTurn& turn, std::size_t begin, std::size_t end,
                                          CsSummary* out, std::vector<double>& scratch) {
  if (begin == end) return std::nullopt;
  std::vector<int> idx = grid_indices(axes, begin);
  Rig rig = rig_at(base, axes, idx);
  for (std::size_t p = begin; p != end; ++p) {
    if (p != begin) {
      std::size_t a = axes.size();
      while (a-- > 0 && ++idx[a] == axes[a].count) idx[a] = 0;
      for (; a < axes.size(); ++a) axes[a].key->real(rig) = axes[a].value(idx[a]);
    }
    if (check_rig(rig)) return p;
    out[p - begin] = cs_summary(rig, turn, scratch);
  }
  return std::nullopt;
}

[[noreturn]] void throw_point_error(const Rig& base, const std::vector<GridAxis>& axes, std::size_t point) {
  const std::vector<int> idx = grid_indices(axes, point);
  throw point_error(axes, idx, *check_rig(rig_at(base, axes, idx)));
}

// compute_points in parallel (one rank's shard of a block). Throws RigError naming the first
// point (in grid order) that breaks a rule of check_rig; nothing else is then meaningful in `out`.
void compute_block(const Rig& base, const std::vector<GridAxis>& axes, const CsTurn& turn,
                   std::size_t begin, std::size_t end, CsSummary* out,
                   tbb::enumerable_thread_specific<std::vector<double>>& scratch) {
  const std::size_t none = std::numeric_limits<std::size_t>::max();
  std::atomic<std::size_t> first_bad{none};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end, 256),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      const auto bad = compute_points(base, axes, turn, r.begin(), r.end(),
                                                      out + (r.begin() - begin), scratch.local());
                      if (!bad) return;
                      std::size_t seen = first_bad.load();
                      while (*bad < seen && !first_bad.compare_exchange_weak(seen, *bad)) {
                      }
                    });
  if (first_bad != none) throw_point_error(base, axes, first_bad);
}
}  // namespace

std::size_t sweep_block_size(std::size_t total_points) {
  return std::clamp<std::size_t>(total_points / 100, 4096, 32768);
}


namespace {

// One process: the points in pieces side by side (side_by_side.h), across the blocks' bounds, so
// that no core waits for a block's last piece; each block, once whole, handed to the sink on a
// writer thread (BackgroundWriter) while TBB's threads go on computing: a write that waits for the
// disk leaves no core idle. Pieces of at most 256 points, at least eight a thread in a block (a
// traced rig's grid of a few hundred points, one block, is shared too); at most a block of them
// in flight beside the block being assembled and the one being written: memory for three blocks.
// The sink sees every block once, in grid order, one call at a time. An error is the first in
// grid order: a failed write (said when the next block is handed on, or at the end) before a bad
// point after it.
void sweep_alone(const Rig& base, const std::vector<GridAxis>& axes, const CsTurn& turn, const SweepSink& sink,
                 const SweepProgress& progress, std::size_t first_point, std::size_t block) {
  const std::size_t total = grid_points(axes);
  if (first_point == total) return;
  block = std::min(block, total);
  const auto threads = static_cast<std::size_t>(usable_threads());
  const std::size_t piece = std::clamp<std::size_t>((block + 8 * threads - 1) / (8 * threads), 1, 256);
  const std::size_t pieces_per_block = (block + piece - 1) / piece;
  const std::size_t blocks = (total - first_point + block - 1) / block;
  struct Piece {
    std::size_t index;
    std::vector<CsSummary> summaries;
    std::optional<std::size_t> bad;  // the first point breaking a rule (said in grid order)
  };
  struct PieceBounds {
    std::size_t block_begin, block_end, begin, end;
  };
  // The points of piece i: its block's, from the piece's start (empty past a last, short block)
  const auto bounds = [&](std::size_t i) {
    PieceBounds b;
    b.block_begin = first_point + i / pieces_per_block * block;
    b.block_end = std::min(total, b.block_begin + block);
    b.begin = std::min(b.block_end, b.block_begin + i % pieces_per_block * piece);
    b.end = std::min(b.block_end, b.begin + piece);
    return b;
  };
  tbb::enumerable_thread_specific<std::vector<double>> scratch;
  // Block b is assembled in buffers[b % 2] while block b − 1 is written from the other: the
  // collect of block b's last piece hands it on only once block b − 1's write is done, before
  // any piece of block b + 1 is collected into that buffer.
  std::array<std::vector<CsSummary>, 2> buffers;
  for (std::vector<CsSummary>& b : buffers) b.resize(block);
  BackgroundWriter writer;
  try {
    side_by_side_in_order(
        blocks * pieces_per_block,
        [&](std::size_t i) {
          const PieceBounds b = bounds(i);
          Piece p{i, std::vector<CsSummary>(b.end - b.begin), std::nullopt};
          p.bad = compute_points(base, axes, turn, b.begin, b.end, p.summaries.data(), scratch.local());
          return p;
        },
        [&](Piece p) {
          if (p.bad) {
            writer.finish();  // a failed write of an earlier block is said first
            throw_point_error(base, axes, *p.bad);
          }
          const PieceBounds b = bounds(p.index);
          std::vector<CsSummary>& assembled = buffers[p.index / pieces_per_block % 2];
          std::copy(p.summaries.begin(), p.summaries.end(), assembled.begin() + (b.begin - b.block_begin));
          if (p.index % pieces_per_block != pieces_per_block - 1) return;
          // submit() waits for block b − 1's write, throwing its failure
          writer.submit([&sink, &progress, &assembled, first = b.block_begin, last = b.block_end, total] {
            sink(first, std::span<const CsSummary>(assembled.data(), last - first));
            if (progress) progress(last, total);
          });
        },
        pieces_per_block + 1);
  } catch (...) {
    writer.finish();  // any error of a later piece: a failed write before it is said first
    throw;
  }
  writer.finish();
}

}  // namespace

void sweep(const Rig& base, const std::vector<GridAxis>& axes, const CsTurn& turn,
           const SweepSink& sink, const SweepProgress& progress, const SweepOptions& options) {
  check_grid(base, axes);
  const std::size_t total = grid_points(axes);
  // Blocks in turn, each in parallel: bounded memory, and progress between them.
  const std::size_t block = sweep_block_size(total);
  if (options.first_point > total || (options.first_point % block != 0 && options.first_point != total))
    throw std::invalid_argument(fmt::format("sweep: resuming at point {}, not a block boundary "
                                            "(blocks of {} of {} points)", options.first_point, block, total));
  const Ranks& ranks = options.ranks ? *options.ranks : this_process_only();
  if (ranks.size() == 1) return sweep_alone(base, axes, turn, sink, progress, options.first_point, block);
  const auto size = static_cast<std::size_t>(ranks.size());
  const auto rank = static_cast<std::size_t>(ranks.rank());
  // Every block is shared: rank k computes the k-th of `size` consecutive shards of its points,
  // and rank 0 gathers the shards in rank order, which is grid order. Blocks stay the unit of
  // output and resuming; shards, not whole blocks, go to the ranks, so that a grid of one block
  // (a traced rig's few hundred points, each two traced turns) is shared too. Every rank runs
  // every block's collectives (also with an empty shard), so none waits forever.
  std::vector<CsSummary> summaries(std::min(block, total) / size + 1);
  tbb::enumerable_thread_specific<std::vector<double>> scratch;
  std::optional<std::string> sink_failure;  // rank 0's, said at the next collective point
  // Rank 0 hands block b to the sink on a writer thread while every rank computes block b + 1: two
  // buffers, the one written and the one gathered next. A failed write is found when the next is
  // submitted (or at the end) and said at the collective point after it.
  std::array<std::vector<CsSummary>, 2> written;
  BackgroundWriter writer;
  std::size_t current = 0;
  const auto note_sink_failure = [&](const std::exception& e) {
    if (!sink_failure) sink_failure = rank_failure_text(e);
  };
  for (std::size_t begin = options.first_point; begin < total; begin += block) {
    const std::size_t end = std::min(total, begin + block);
    const std::size_t mine_begin = begin + (end - begin) * rank / size;
    const std::size_t mine_end = begin + (end - begin) * (rank + 1) / size;
    std::optional<std::string> failure = sink_failure;
    if (!failure && mine_begin < mine_end) {
      try {
        compute_block(base, axes, turn, mine_begin, mine_end, summaries.data(), scratch);
      } catch (const std::exception& e) {
        failure = rank_failure_text(e);
      }
    }
    // Every shard is computed before anything of the block is written: a rank that failed (the
    // lowest, whose bad point comes first in grid order, as one process finds it) stops all. A
    // failed write of an earlier block still being written comes before it in grid order: rank 0
    // waits for that write, and every rank hears its failure first.
    if (const auto first = ranks.first_failure(failure)) {
      std::optional<std::string> write_failure;
      if (rank == 0) try {
          writer.finish();
        } catch (const std::exception& e) {
          write_failure = rank_failure_text(e);
        }
      if (const auto earlier = ranks.first_failure(write_failure)) throw_rank_failure(*earlier);
      throw_rank_failure(*first);
    }
    static_assert(std::is_trivially_copyable_v<CsSummary>, "CsSummary travels between ranks as bytes");
    const std::vector<std::byte> gathered =
        ranks.gather(std::as_bytes(std::span<const CsSummary>(summaries.data(), mine_end - mine_begin)));
    if (rank != 0) continue;
    try {
      if (gathered.size() != (end - begin) * sizeof(CsSummary))
        throw std::logic_error(fmt::format("sweep: gathered {} bytes for {} points", gathered.size(), end - begin));
      std::vector<CsSummary>& block_summaries = written[current];
      block_summaries.resize(end - begin);
      std::memcpy(block_summaries.data(), gathered.data(), gathered.size());
      // submit() waits for block b − 1's write (throwing its failure); block b − 2's buffer is free
      writer.submit([&sink, &progress, &block_summaries, begin, end, total] {
        sink(begin, block_summaries);
        if (progress) progress(end, total);
      });
      current ^= 1;
    } catch (const std::exception& e) {
      note_sink_failure(e);
    }
  }
  if (rank == 0) try {
      writer.finish();
    } catch (const std::exception& e) {
      note_sink_failure(e);
    }
  if (const auto first = ranks.first_failure(sink_failure)) throw_rank_failure(*first);
}

SweepResult sweep(const Rig& base, const std::vector<GridAxis>& axes, const CsTurn& turn,
                  const SweepProgress& progress) {
  SweepResult result;
  result.axes = axes;
  sweep(base, axes, turn,
        [&](std::size_t, std::span<const CsSummary> block) {
          result.summaries.insert(result.summaries.end(), block.begin(), block.end());
        },
        progress);
  return result;
}

void sweep(const Rig& base, const std::vector<GridAxis>& axes, const CsTurn& turn,
           const SweepSink& sink, const Progress& progress, const SweepOptions& options) {
  // Every rank prepares the light itself (a traced rig's sphere solve: a pure function of the
  // scene, so every rank holds the same solution); one that fails stops them all.
  const Ranks& ranks = options.ranks ? *options.ranks : this_process_only();
  if (ranks.size() == 1) {
    base.light->prepare(progress);
  } else {
    std::optional<std::string> failure;
    try {
      base.light->prepare(progress);
    } catch (const std::exception& e) {
      failure = rank_failure_text(e);
    }
    if (const auto first = ranks.first_failure(failure)) throw_rank_failure(*first);
  }
  progress.begin("sweep: grid points", static_cast<long long>(grid_points(axes) - std::min(grid_points(axes), options.first_point)));
  std::size_t reported = options.first_point;
  sweep(base, axes, turn, sink, [&](std::size_t done, std::size_t) {
    progress.advance(static_cast<long long>(done - reported));
    reported = done;
  }, options);
  progress.finish();
}

std::vector<const RigKey*> axes_the_cs_study_ignores(const std::vector<GridAxis>& axes) {
  std::vector<const RigKey*> keys;
  for (const GridAxis& a : axes)
    if (!(a.key->studies & RigKey::kCs)) keys.push_back(a.key);
  return keys;
}

}  // namespace polrig
