#include "polrig/study/sweep.h"

#include <algorithm>
#include <string>

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "polrig/io/rig_yaml.h"

namespace polrig {

GridAxis GridAxis::parse(std::string_view arg) {
  const auto fail = [&](const std::string& why) -> GridAxis {
    throw RigError(fmt::format("--grid {}: {}", arg, why));
  };
  const auto eq = arg.find('=');
  if (eq == std::string_view::npos) return fail("expected key=start:stop:count");
  const std::string_view path = arg.substr(0, eq);
  const std::string_view spec = arg.substr(eq + 1);
  GridAxis axis;
  axis.key = find_rig_key(path);
  if (!axis.key) return fail(fmt::format("unknown key '{}' (see docs/formats.md)", path));
  if (axis.key->kind != RigKey::Kind::Real)
    return fail(fmt::format("key '{}' is not a single real number and cannot be swept", path));
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
  for (int i = 0; i < axis.count; ++i)
    if (axis.key->valid_real && !axis.key->valid_real(axis.value(i)))
      return fail(fmt::format("key '{}': expected {}, got {}", path, axis.key->expects,
                              axis.value(i)));
  return axis;
}

double GridAxis::value(int index) const {
  if (count == 1) return start;
  if (index == count - 1) return stop;  // exact end point
  // Weighted form, exact at both ends; then rounded to 15 significant digits, so that a decimal
  // grid such as 0.05:0.95:19 gives 0.15 and not 0.15000000000000002.
  const double n = count - 1;
  const double v = (start * (n - index) + stop * index) / n;
  return std::stod(fmt::format("{:.15g}", v));
}

std::string GridAxis::text() const {
  return fmt::format("{}={}:{}:{}", key->path, start, stop, count);
}

std::vector<int> SweepResult::indices(std::size_t p) const {
  std::vector<int> idx(axes.size());
  for (std::size_t a = axes.size(); a-- > 0;) {
    idx[a] = static_cast<int>(p % static_cast<std::size_t>(axes[a].count));
    p /= static_cast<std::size_t>(axes[a].count);
  }
  return idx;
}

namespace {
Rig rig_at(const Rig& base, const SweepResult& r, std::size_t p) {
  Rig rig = base;
  const std::vector<int> idx = r.indices(p);
  for (std::size_t a = 0; a < r.axes.size(); ++a) r.axes[a].key->real(rig) = r.axes[a].value(idx[a]);
  return rig;
}
}  // namespace

void check_grid(const Rig& base, const std::vector<GridAxis>& axes) {
  SweepResult r;
  r.axes = axes;
  double points = 1;
  for (const GridAxis& a : axes) points *= a.count;
  if (points > 1e9)
    throw RigError(fmt::format("--grid: {:.3g} grid points; at most 1e9 (a summary row each)", points));
  std::size_t total = 1;
  for (const GridAxis& a : axes) total *= static_cast<std::size_t>(a.count);
  if (base.source.traced)
    for (const GridAxis& a : axes)
      if (a.key->path == "device.d" || a.key->path == "source.E_0" || a.key->path == "source.polarizer_deg")
        throw RigError(fmt::format("--grid {}: a traced source's light comes from its scene; '{}' "
                                   "cannot be swept", a.text(), a.key->path));
  for (std::size_t p = 0; p < total; ++p) {
    if (auto problem = check_rig(rig_at(base, r, p))) {
      std::string where;
      const std::vector<int> idx = r.indices(p);
      for (std::size_t a = 0; a < axes.size(); ++a)
        where += fmt::format("{}{}={}", a ? ", " : "", axes[a].key->path, axes[a].value(idx[a]));
      throw RigError(fmt::format("--grid point ({}): key '{}': {}", where, problem->path,
                                 problem->message));
    }
  }
}

SweepResult sweep(const Rig& base, const std::vector<GridAxis>& axes, const CsTurn& turn,
                  const SweepProgress& progress) {
  check_grid(base, axes);
  SweepResult result;
  result.axes = axes;
  std::size_t total = 1;
  for (const GridAxis& a : axes) total *= static_cast<std::size_t>(a.count);
  result.summaries.resize(total);

  tbb::enumerable_thread_specific<std::vector<double>> scratch;
  // Chunks of the grid in turn, each in parallel, so progress can be told between them.
  const std::size_t chunk = std::max<std::size_t>(4096, total / 100);
  for (std::size_t begin = 0; begin < total; begin += chunk) {
    const std::size_t end = std::min(total, begin + chunk);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end, 256),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        std::vector<double>& s = scratch.local();
                        for (std::size_t p = r.begin(); p != r.end(); ++p)
                          result.summaries[p] = cs_summary(rig_at(base, result, p), turn, s);
                      });
    if (progress) progress(end, total);
  }
  return result;
}

}  // namespace polrig
