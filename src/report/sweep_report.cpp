#include "polrig/report/sweep_report.h"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <fstream>
#include <functional>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "polrig/io/csv.h"
#include "polrig/io/output_dir.h"
#include "polrig/io/plot.h"
#include "polrig/io/sweep_state.h"
#include "polrig/study/rank_failure.h"
#include "polrig/version.h"
#include "pair_style.h"

namespace polrig {
namespace fs = std::filesystem;

namespace {
struct PairColumn {
  const char* name;
  const char* unit;
  const char* description;
  double (*get)(const CsPairSummary&);
};
// sweep.csv's columns after the axes, for each pair, in order (docs/formats.md §6.3).
constexpr PairColumn kPairColumns[] = {
    {"bsd_mV", "mV", "BSD: population standard deviation of ΔV_br over the turn",
     [](const CsPairSummary& s) { return s.bsd_mV; }},
    {"asd_mV", "mV", "ASD: population standard deviation of ΔV_mr (after CS) over the turn",
     [](const CsPairSummary& s) { return s.asd_mV; }},
    {"asd_bsd_pct", "%", "100·ASD/BSD; NaN where BSD is below 1e-9 mV (undefined)", &asd_bsd_pct},
    {"mean_br_mV", "mV", "mean of ΔV_br over the turn", [](const CsPairSummary& s) { return s.mean_br_mV; }},
    {"mean_mr_mV", "mV", "mean of ΔV_mr over the turn (the expectation after CS)",
     [](const CsPairSummary& s) { return s.mean_mr_mV; }},
    {"eq6_mV", "mV", "Eq. 6's CS constant; NaN where the source has no closed form (a traced source)",
     [](const CsPairSummary& s) { return s.eq6_mV; }},
    {"eq6_dev_pct", "%", "100·(eq6 − mean_mr)/mean_mr; NaN where |mean_mr| is below 1e-9 mV or Eq. 6 is NaN",
     &eq6_dev_pct},
};
constexpr std::size_t kColumnsPerPair = std::size(kPairColumns);
constexpr std::size_t kColumns = 3 * kColumnsPerPair;

std::string column_name(std::size_t c) {
  return fmt::format("pair{}_{}", c / kColumnsPerPair + 1, kPairColumns[c % kColumnsPerPair].name);
}

std::vector<std::string> csv_header(const std::vector<GridAxis>& axes) {
  std::vector<std::string> header;
  for (const GridAxis& a : axes) header.emplace_back(a.key->path);
  for (std::size_t c = 0; c < kColumns; ++c) header.push_back(column_name(c));
  return header;
}

std::string axis_label(const GridAxis& a) {
  return a.key->unit.empty() ? std::string(a.key->path) : fmt::format("{} ({})", a.key->path, a.key->unit);
}

// 64-bit FNV-1a (polrig/fnv.h): a short, stable fingerprint of a long input (a rig's text, an
// axis's values, the files a resumable sweep has written).
std::string fnv_text(std::uint64_t h) { return fmt::format("{:016x}", h); }
struct Fingerprint {
  std::uint64_t h = kFnvBasis;
  void add(std::string_view bytes) { fnv_add(h, bytes); }
  std::string text() const { return fnv_text(h); }
};
// sweep.h5's fingerprint takes each point's values, column after column, in point order: the
// same whatever the blocks were. The files' fingerprints are FnvWords (a value a word): hashing
// the bytes one at a time was a third of a CSV sweep's writer thread.
void add_point(FnvWords& h, const double* column0, std::size_t stride, std::size_t columns) {
  for (std::size_t c = 0; c < columns; ++c) h.add_word(std::bit_cast<std::uint64_t>(column0[c * stride]));
}
std::string fingerprint(std::string_view bytes) {
  Fingerprint f;
  f.add(bytes);
  return f.text();
}
}  // namespace

SweepH5Layout sweep_h5_layout(const std::vector<GridAxis>& axes, bool eq6,
                              std::vector<std::pair<std::string, std::string>> attributes) {
  SweepH5Layout l;
  for (std::size_t k = 0; k < axes.size(); ++k) {
    const GridAxis& a = axes[k];
    // A key may be swept on several axes; a dataset name is unique, so the later ones say which.
    const bool repeated = std::any_of(axes.begin(), axes.begin() + static_cast<long>(k),
                                      [&](const GridAxis& b) { return b.key == a.key; });
    const std::string name = repeated ? fmt::format("{} (axis {})", a.key->path, k + 1) : std::string(a.key->path);
    l.axes.push_back({name, std::string(a.key->unit), std::string(a.key->doc),
                      static_cast<std::size_t>(a.count), [a](std::size_t i) { return a.value(static_cast<int>(i)); }});
  }
  for (std::size_t c = 0; c < kColumns; ++c) {
    const PairColumn& p = kPairColumns[c % kColumnsPerPair];
    const std::string_view name = p.name;
    const bool nan = name == "asd_bsd_pct" || name == "eq6_dev_pct" || (name == "eq6_mV" && !eq6);
    l.columns.push_back({column_name(c), p.unit, fmt::format("pair {}: {}", c / kColumnsPerPair + 1, p.description), nan});
  }
  l.attributes = std::move(attributes);
  return l;
}

namespace {
// sweep.csv's lines of the block's points first … first + n − 1 (their values checked above):
// formatting, not the disk, set a CSV sweep's pace (issue 35), so chunks of lines are formatted
// on TBB's threads and written in order, the bytes those of one thread.
// `parts` keeps its strings' memory from block to block; part k holds points k·kCsvChunk onwards.
// `axis_text[a][i]` is axis a's value i as append_csv_line writes it, with its comma: formatted
// once, not once a line.
constexpr std::size_t kCsvChunk = 1024;
std::vector<std::vector<std::string>> axis_csv_text(const std::vector<GridAxis>& axes) {
  std::vector<std::vector<std::string>> text(axes.size());
  for (std::size_t a = 0; a < axes.size(); ++a)
    for (int i = 0; i < axes[a].count; ++i) {
      std::string t;
      const double v = axes[a].value(i);
      append_csv_line(t, std::span<const double>(&v, 1));
      t.back() = ',';  // its line end, as the separator before the next column
      text[a].push_back(std::move(t));
    }
  return text;
}
void csv_lines(const std::vector<GridAxis>& axes, const std::vector<std::vector<std::string>>& axis_text,
               std::size_t first, std::size_t n, const std::vector<double>& columns, std::vector<std::string>& parts) {
  const std::size_t chunks = (n + kCsvChunk - 1) / kCsvChunk;
  if (parts.size() < chunks) parts.resize(chunks);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t ch) {
    double row[kColumns];
    std::string& out = parts[ch];
    out.clear();
    for (std::size_t k = ch * kCsvChunk; k < std::min(n, (ch + 1) * kCsvChunk); ++k) {
      const std::vector<int> idx = grid_indices(axes, first + k);
      for (std::size_t a = 0; a < axes.size(); ++a) out += axis_text[a][static_cast<std::size_t>(idx[a])];
      for (std::size_t c = 0; c < kColumns; ++c) row[c] = columns[c * n + k];
      append_csv_line(out, row);
    }
  });
}
}  // namespace

SweepReport::SweepReport(const fs::path& dir, std::vector<GridAxis> axes, bool eq6, bool csv,
                         const std::vector<std::pair<std::string, std::string>>& attributes,
                         std::optional<Resume> resume)
    : dir_(dir), axes_(std::move(axes)), layout_(sweep_h5_layout(axes_, eq6, attributes)) {
  const fs::path h5 = dir / "sweep.h5", csv_path = dir / "sweep.csv";
  if (resume) check_resume(*resume, csv);
  h5_.emplace(resume ? SweepH5Writer::reopen(h5, layout_) : SweepH5Writer::create(h5, layout_));
  if (csv) {
    table_.emplace(csv_header(axes_));
    csv_axis_text_ = axis_csv_text(axes_);
    for (const SweepH5Column& c : layout_.columns)
      if (c.may_be_nan) table_->allow_undefined(c.name);
    csv_ = resume ? std::make_unique<TextFileWriter>(csv_path, resume->csv_bytes)
                  : std::make_unique<TextFileWriter>(csv_path);
    if (!resume) {
      const std::string header = table_->header_line();
      csv_->write(header);
      csv_hash_.add(header);
    }
  }
  if (resume) points_ = resume->points_done;
}

// The record against the files, before either is reopened: the points it counts fit the grid,
// sweep.h5's first points_done points are those it fingerprinted, and sweep.csv's first
// csv_bytes bytes are its header and one line per point, as fingerprinted. The hashes go on
// from there. (A sweep.csv shorter than csv_bytes is left to TextFileWriter, which names it.)
void SweepReport::check_resume(const Resume& r, bool csv) {
  const fs::path record = dir_ / kSweepStateFile, h5 = dir_ / "sweep.h5", csv_path = dir_ / "sweep.csv";
  const std::size_t total = layout_.points();
  if (r.points_done > total)
    throw std::runtime_error(fmt::format("{}: points_done {}, but the grid has {} points: the record was changed",
                                         record.string(), r.points_done, total));
  if (r.h5_fingerprint.empty() || (csv && r.csv_fingerprint.empty()))
    throw std::runtime_error(fmt::format("{}: no fingerprint of the files it counts (h5_fingerprint{}): they cannot "
                                         "be checked", record.string(), csv ? ", csv_fingerprint" : ""));
  {
    const SweepH5Reader reader(h5);
    constexpr std::size_t kChunk = 4096;
    const std::size_t columns = layout_.columns.size();
    std::vector<double> values(columns * kChunk);
    FnvWords h;
    for (std::size_t first = 0; first < r.points_done; first += kChunk) {
      const std::size_t n = std::min(kChunk, r.points_done - first);
      for (std::size_t c = 0; c < columns; ++c)
        reader.read(layout_.columns[c].name, first, std::span<double>(values.data() + c * n, n));
      for (std::size_t k = 0; k < n; ++k) add_point(h, values.data() + k, n, columns);
    }
    if (fnv_text(h.value()) != r.h5_fingerprint)
      throw std::runtime_error(fmt::format("{}: its first {} points are not those {} counts (the file is from another "
                                           "checkpoint, or one of them was changed)",
                                           h5.string(), r.points_done, record.string()));
    h5_hash_ = h;
  }
  if (!csv) {
    if (r.csv_bytes != 0)
      throw std::runtime_error(fmt::format("{}: csv_bytes {}, but this sweep writes no sweep.csv: the record was changed",
                                           record.string(), r.csv_bytes));
    return;
  }
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(csv_path, ec);
  if (ec || size < r.csv_bytes) return;  // TextFileWriter names it
  std::ifstream in(csv_path, std::ios::binary);
  std::vector<char> buffer(1 << 20);
  FnvWords h;
  std::uint64_t left = r.csv_bytes, lines = 0;
  char last = '\n';
  while (left > 0 && in) {
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(left, buffer.size()));
    if (!in.read(buffer.data(), static_cast<std::streamsize>(n))) break;
    const std::string_view bytes(buffer.data(), n);
    h.add(bytes);
    lines += static_cast<std::uint64_t>(std::count(bytes.begin(), bytes.end(), '\n'));
    last = bytes.back();
    left -= n;
  }
  if (left > 0)
    throw std::runtime_error(fmt::format("{}: cannot read its first {} bytes", csv_path.string(), r.csv_bytes));
  if (lines != r.points_done + 1 || last != '\n' || fnv_text(h.value()) != r.csv_fingerprint)
    throw std::runtime_error(fmt::format("{}: its first {} bytes are not the header and the {} lines {} counts (the file "
                                         "is from another checkpoint, or one of them was changed)",
                                         csv_path.string(), r.csv_bytes, r.points_done, record.string()));
  csv_hash_ = h;
}

void SweepReport::write(std::size_t first, std::span<const CsSummary> block) {
  if (first != points_)
    throw std::logic_error(fmt::format("sweep.h5: block at point {} after {} points", first, points_));
  const std::size_t n = block.size();
  columns_.resize(kColumns * n);
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t c = 0; c < kColumns; ++c) {
      const double v = kPairColumns[c % kColumnsPerPair].get(block[k][c / kColumnsPerPair]);
      // No NaN or infinity leaves unless it is documented to mean "undefined" (as CsvTable).
      if (!std::isfinite(v) && !(std::isnan(v) && layout_.columns[c].may_be_nan)) {
        const std::vector<int> idx = grid_indices(axes_, first + k);
        std::string at;
        for (std::size_t a = 0; a < axes_.size(); ++a)
          at += fmt::format("{}{}={}", a ? ", " : "", axes_[a].key->path, axes_[a].value(idx[a]));
        throw std::domain_error(fmt::format("sweep: {} is {} at grid point {} ({})", column_name(c), v,
                                             first + k, at));
      }
      columns_[c * n + k] = v;
    }
  h5_->write(first, n, columns_);
  for (std::size_t k = 0; k < n; ++k) add_point(h5_hash_, columns_.data() + k, n, kColumns);
  if (csv_) {
    csv_lines(axes_, csv_axis_text_, first, n, columns_, csv_parts_);
    for (std::size_t ch = 0; ch * kCsvChunk < n; ++ch) {
      csv_->write(csv_parts_[ch]);
      csv_hash_.add(csv_parts_[ch]);
    }
    csv_->start_writeback();  // at the disk's pace beside the computing, not all at the checkpoint
  }
  points_ += n;
}

SweepReport::Resume SweepReport::sync() {
  h5_->sync();
  const std::uint64_t csv_bytes = csv_ ? csv_->sync() : 0;
  return {points_, csv_bytes, fnv_text(h5_hash_.value()), csv_ ? fnv_text(csv_hash_.value()) : std::string()};
}

namespace {

// Mean values over a grid of bins: the points of grid index i along an axis of n values go to
// bin i·B/n, B = min(n, max_bins), so that a grid smaller than the bins is drawn exactly.
struct Bins {
  std::size_t count;
  std::size_t of(std::size_t index, std::size_t n) const { return index * count / n; }
};
Bins bins_for(const GridAxis& a, std::size_t max_bins) {
  return {std::min<std::size_t>(static_cast<std::size_t>(a.count), max_bins)};
}
// The bin's position on the axis: the value itself when every bin holds one, else the middle
// of the bin on a regular grid between the axis's ends (what `with image` needs).
double bin_centre(const GridAxis& a, const Bins& b, std::size_t bin) {
  if (b.count == static_cast<std::size_t>(a.count)) return a.value(static_cast<int>(bin));
  const double lo = a.value(0), hi = a.value(a.count - 1);
  return lo + (static_cast<double>(bin) + 0.5) * (hi - lo) / static_cast<double>(b.count);
}

// Sums the named columns of sweep.h5 into bins, reading it a slice at a time. NaN (undefined)
// values are left out of a bin's mean; a bin with none defined is NaN.
std::vector<std::vector<double>> binned_means(const fs::path& h5, const std::vector<std::string>& names,
                                              std::size_t points, std::size_t bins,
                                              const std::function<std::size_t(std::size_t)>& bin_of) {
  const SweepH5Reader reader(h5);
  std::vector<std::vector<double>> sum(names.size(), std::vector<double>(bins, 0.0));
  std::vector<std::vector<std::uint32_t>> count(names.size(), std::vector<std::uint32_t>(bins, 0));
  constexpr std::size_t kSlice = 1 << 16;
  std::vector<double> values(std::min(points, kSlice));
  for (std::size_t first = 0; first < points; first += kSlice) {
    const std::size_t n = std::min(kSlice, points - first);
    for (std::size_t q = 0; q < names.size(); ++q) {
      reader.read(names[q], first, std::span<double>(values.data(), n));
      for (std::size_t k = 0; k < n; ++k)
        if (!std::isnan(values[k])) {
          const std::size_t b = bin_of(first + k);
          sum[q][b] += values[k];
          ++count[q][b];
        }
    }
  }
  for (std::size_t q = 0; q < names.size(); ++q)
    for (std::size_t b = 0; b < bins; ++b)
      sum[q][b] = count[q][b] ? sum[q][b] / count[q][b] : std::numeric_limits<double>::quiet_NaN();
  return sum;
}

constexpr std::size_t kMaxCurveBins = 2000;  // a line plot's points along one axis
constexpr std::size_t kMaxImageBins = 256;   // an image's pixels along each axis

// A title's line breaks as gnuplot's "\n" escape (for a double-quoted string).
std::string escaped_line_breaks(const std::string& text) {
  std::string out;
  for (char c : text) out += c == '\n' ? std::string("\\n") : std::string(1, c);
  return out;
}

std::vector<DatasetFile> plot_one_axis(const fs::path& dir, const GridAxis& axis, const std::string& fixed) {
  const Bins bins = bins_for(axis, kMaxCurveBins);
  const std::size_t n = static_cast<std::size_t>(axis.count);
  std::vector<std::string> names, header{std::string(axis.key->path)};
  for (int i = 1; i <= 3; ++i)
    for (const char* c : {"asd_mV", "asd_bsd_pct", "mean_mr_mV", "eq6_mV"}) {
      names.push_back(fmt::format("pair{}_{}", i, c));
      header.push_back(names.back());
    }
  const auto means = binned_means(dir / "sweep.h5", names, n, bins.count,
                                  [&](std::size_t p) { return bins.of(p, n); });
  CsvTable table(header);
  for (std::size_t q = 0; q < names.size(); ++q) table.allow_undefined(names[q]);
  std::array<bool, 3> ratio_defined{}, eq6_defined{};
  for (std::size_t b = 0; b < bins.count; ++b) {
    // The bin's x: the mean of its axis values (exact when it holds one).
    const std::size_t lo = (b * n + bins.count - 1) / bins.count, hi = ((b + 1) * n + bins.count - 1) / bins.count;
    double x = 0;
    for (std::size_t i = lo; i < hi; ++i) x += axis.value(static_cast<int>(i));
    std::vector<double> row{x / static_cast<double>(hi - lo)};
    for (std::size_t q = 0; q < names.size(); ++q) row.push_back(means[q][b]);
    for (std::size_t i = 0; i < 3; ++i) {
      ratio_defined[i] |= !std::isnan(means[4 * i + 1][b]);
      eq6_defined[i] |= !std::isnan(means[4 * i + 3][b]);
    }
    table.add_row(row);
  }
  write_text_file(dir / "sweep_plot.csv", table.text());

  const std::string x = axis_label(axis);
  Plot asd{"sweep_asd.png", "After CS: ASD (solid) and ASD/BSD (dashed, right)" + fixed, x, "ASD (mV)", "ASD/BSD (%)"};
  Plot mean{"sweep_expectation.png",
            "Expectation of ΔV_mr (lines), Eq. 6 (points), Eq. 6 - expectation (dashed, right)" + fixed, x,
            "expectation (mV)", "Eq. 6 - expectation (µV)"};
  for (int i = 0; i < 3; ++i) {
    const auto col = [&](int offset) { return "$" + names[static_cast<std::size_t>(4 * i + offset)]; };
    const std::string x_col = "$" + header[0] + ":";
    asd.series.push_back({"sweep_plot.csv", x_col + col(0), fmt::format("ASD pair {}", i + 1), line_style(i)});
    // gnuplot refuses a series with no defined point: the ratio is NaN where BSD is zero.
    if (ratio_defined[static_cast<std::size_t>(i)])
      asd.series.push_back({"sweep_plot.csv", x_col + col(1), fmt::format("ASD/BSD pair {}", i + 1),
                            line_style(i, "dt 2"), true});
    mean.series.push_back({"sweep_plot.csv", x_col + col(2), fmt::format("expectation pair {}", i + 1),
                           line_style(i)});
    if (eq6_defined[static_cast<std::size_t>(i)]) {
      mean.series.push_back({"sweep_plot.csv", x_col + col(3), fmt::format("Eq. 6 pair {}", i + 1),
                             fmt::format("points pt 6 ps 0.8 lc rgb '{}'", kPairColour[i])});
      mean.series.push_back({"sweep_plot.csv", fmt::format("{}(({}-{})*1e3)", x_col, col(3), col(2)),
                             fmt::format("Eq. 6 - expectation, pair {}", i + 1), line_style(i, "dt 2"), true});
    }
  }
  // Enough digits for a nearly flat curve (gnuplot's default shows 0.00074 on every tic).
  asd.extra = mean.extra = "set format y '%.6g'\nset format y2 '%.6g'";
  render_plots(dir, "plots.gp", {asd, mean});
  return {{"sweep_plot.csv", 1,
           fmt::format("the plotted curves: per pair ASD, ASD/BSD, expectation and Eq. 6, the mean over each of "
                       "{} bins of the swept key", bins.count)}};
}

std::vector<DatasetFile> plot_two_axes(const fs::path& dir, const GridAxis& outer, const GridAxis& inner,
                                       const std::string& fixed) {
  const Bins by = bins_for(outer, kMaxImageBins), bx = bins_for(inner, kMaxImageBins);
  const std::size_t ny = static_cast<std::size_t>(outer.count), nx = static_cast<std::size_t>(inner.count);
  const std::vector<std::string> names{"pair1_asd_mV", "pair1_mean_mr_mV"};
  const auto means = binned_means(dir / "sweep.h5", names, nx * ny, by.count * bx.count, [&](std::size_t p) {
    return by.of(p / nx, ny) * bx.count + bx.of(p % nx, nx);
  });
  // Scan lines of constant outer value, a blank line after each (gnuplot's grid format).
  CsvTable table({std::string(inner.key->path), std::string(outer.key->path), names[0], names[1]});
  table.allow_undefined(names[0]).allow_undefined(names[1]);
  std::string text = table.header_line();
  for (std::size_t j = 0; j < by.count; ++j) {
    for (std::size_t i = 0; i < bx.count; ++i)
      table.add_row({bin_centre(inner, bx, i), bin_centre(outer, by, j), means[0][j * bx.count + i],
                     means[1][j * bx.count + i]});
    text += table.take_body() + "\n";
  }
  write_text_file(dir / "sweep_map.csv", text);

  const auto image = [&](const char* png, const std::string& title, const char* cblabel, const std::string& column) {
    std::string s = fmt::format(
        "reset session\nset terminal pngcairo size 960,720 enhanced font 'DejaVu Sans,11'\n"
        "set output '{}'\nset datafile separator ','\nset datafile columnheaders\n"
        "set title \"{}\" noenhanced\nset xlabel \"{}\" noenhanced\nset ylabel \"{}\" noenhanced\n"
        "set cblabel \"{}\" offset 1.5,0\nset format cb '%g'\nset rmargin at screen 0.80\nset palette defined (0 '#440154', 0.25 '#3b528b', 0.5 '#21918c', 0.75 '#5ec962', 1 '#fde725')\nset autoscale fix\nset tics out\n"
        "plot 'sweep_map.csv' using \"{}\":\"{}\":\"{}\" with image notitle\nunset output\n",
        png, escaped_line_breaks(title), axis_label(inner), axis_label(outer), cblabel, inner.key->path,
        outer.key->path, column);
    return s;
  };
  const std::string mean_of = by.count * bx.count < nx * ny ? " (mean of each bin)" : "";
  const std::string script =
      image("sweep_asd.png", "Pair 1 ASD after CS" + mean_of + fixed, "ASD (mV)", names[0]) + "\n" +
      image("sweep_expectation.png", "Pair 1 expectation of ΔV_mr after CS" + mean_of + fixed, "expectation (mV)",
            names[1]);
  run_gnuplot(dir, "plots.gp", script, {"sweep_asd.png", "sweep_expectation.png"});
  return {{"sweep_map.csv", 1,
           fmt::format("the plotted images: pair 1 ASD and expectation, the mean over each of {}×{} bins of the "
                       "grid (blank line after each row)", by.count, bx.count)}};
}

}  // namespace

std::vector<DatasetFile> SweepReport::finish(bool plots) {
  sync();  // the blocks since the last checkpoint reach the disk before the record goes
  h5_->close();
  h5_.reset();
  if (csv_) csv_->close();
  std::vector<DatasetFile> files{
      {"sweep.h5", 1, "HDF5: one dataset per summary column shaped as the grid, the axes as dimension scales, "
                      "the manifest as attributes"}};
  if (csv_) files.push_back({"sweep.csv", 1, "one row per grid point: the grid values and the CS summary of each pair"});
  if (!plots || axes_.empty() || axes_.size() > 2) return files;
  std::vector<DatasetFile> data =
      axes_.size() == 1 ? plot_one_axis(dir_, axes_[0], fixed_) : plot_two_axes(dir_, axes_[0], axes_[1], fixed_);
  files.insert(files.end(), data.begin(), data.end());
  files.push_back({"sweep_asd.png", 1, axes_.size() == 1 ? "ASD and ASD/BSD against the swept key (Figs. 11a, 12a)"
                                                         : "pair 1 ASD over the grid, an image (Figs. 11a, 12a)"});
  files.push_back({"sweep_expectation.png", 1,
                   axes_.size() == 1 ? "expectation after CS and Eq. 6 against the swept key (Figs. 10, 11b, 12b)"
                                     : "pair 1 expectation after CS over the grid, an image (Figs. 10, 11b, 12b)"});
  return files;
}

namespace {
// Everything that determines a sweep folder's bytes, but the command and working directory
// (kept from the first run): a resumed run must match each.
std::vector<std::pair<std::string, std::string>> sweep_inputs(const LoadedRig& r, const std::vector<GridAxis>& axes,
                                                              int steps, const SweepFolder& f) {
  std::string overrides, grid;
  for (const RigOverride& o : r.overrides) overrides += o.path + "=" + o.value + "\n";
  for (const GridAxis& a : axes) {
    Fingerprint values;
    for (int i = 0; i < a.count; ++i) {
      const double v = a.value(i);
      values.add(std::string_view(reinterpret_cast<const char*>(&v), sizeof v));
    }
    grid += fmt::format("{} ({} values, fingerprint {})\n", a.key->path, a.count, values.text());
  }
  return {{"program", fmt::format("polrig {} ({})", POLRIG_VERSION, POLRIG_GIT_REVISION)},
          {"rig file", r.origin},
          {"rig file's text", fingerprint(r.text)},
          {"overrides (--set)", overrides},
          {"effective rig", fingerprint(rig_to_yaml(r.rig))},
          {"grid (--grid)", grid},
          {"steps (--steps)", fmt::format("{}", steps)},
          {"csv (--csv)", f.csv ? "yes" : "no"},
          {"plots (--no-plots)", f.plots ? "yes" : "no"}};
}
}  // namespace

namespace {
// "\n(fixed: eccentricity.L_IS = 0.05 mm, …)": the eccentricity keys the grid does not sweep, as
// the rig holds them, for the plots' titles.
std::string fixed_keys(const Rig& rig, const std::vector<GridAxis>& axes) {
  Rig copy = rig;
  std::string text;
  for (const char* path : {"eccentricity.L_IS", "eccentricity.alpha_IS", "eccentricity.L_S", "eccentricity.alpha_S"}) {
    const bool swept = std::any_of(axes.begin(), axes.end(), [&](const GridAxis& a) { return a.key->path == path; });
    const RigKey* key = find_rig_key(path);
    if (swept || key == nullptr || key->real == nullptr) continue;
    text += fmt::format("{}{} = {:g} {}", text.empty() ? "" : ", ", path, key->real(copy), key->unit);
  }
  return text.empty() ? text : "\n(fixed: " + text + ")";
}

// The command that continues this sweep when interrupted: its own, without --force, with --resume.
std::string continue_command(const SweepFolder& f) {
  if (f.command.rfind("polrig ", 0) != 0) return {};  // not started from the command line
  // The command line's words are shell-quoted ('…'): split at spaces outside quotes.
  std::vector<std::string> words(1);
  bool quoted = false, escaped = false;  // shell_word writes a ' inside a word as '\''
  for (char ch : f.command) {
    if (ch == '\'' && !escaped) quoted = !quoted;
    escaped = !quoted && ch == '\\' && !escaped;
    if (ch == ' ' && !quoted) words.emplace_back();
    else words.back() += ch;
  }
  std::string c;
  for (const std::string& word : words)
    if (word != "--force") c += (c.empty() ? "" : " ") + word;
  return f.resume ? c : c + " --resume";
}

// The folder a sweep writes into, opened (or resumed) by rank 0.
struct OpenSweep {
  std::optional<OutputDir> dir;
  SweepState state;
  Manifest manifest;
  std::optional<SweepReport> report;
};

void open_sweep(OpenSweep& o, const LoadedRig& r, const std::vector<GridAxis>& axes, int steps, const SweepFolder& f) {
  try {
    o.dir.emplace(f.out, f.force, Resumable{kSweepStateFile, f.resume, f.force && !f.resume, continue_command(f)});
  } catch (const std::runtime_error& e) {
    if (f.argument.empty()) throw;
    throw std::runtime_error(fmt::format("{}: {}", f.argument, e.what()));
  }
  const fs::path staging = o.dir->staging();
  o.state = {0, 0, f.command, manifest_working_directory({f.command, &r, {}}), sweep_inputs(r, axes, steps, f)};
  std::optional<SweepReport::Resume> resume;
  if (o.dir->resuming()) {
    const std::optional<SweepState> saved = read_sweep_state(staging);
    const std::vector<std::string> differ = differing_inputs(*saved, o.state.inputs);
    if (!differ.empty())
      throw std::runtime_error(fmt::format("--resume: the interrupted run in {} was started with another {}; "
                                           "run the same command to continue it, or pass --force without "
                                           "--resume to start over", staging.string(), fmt::join(differ, ", ")));
    o.state.points_done = saved->points_done;
    o.state.csv_bytes = saved->csv_bytes;
    o.state.h5_fingerprint = saved->h5_fingerprint;
    o.state.csv_fingerprint = saved->csv_fingerprint;
    o.state.command = saved->command;
    o.state.working_directory = saved->working_directory;
    resume = SweepReport::Resume{o.state.points_done, o.state.csv_bytes, o.state.h5_fingerprint,
                                 o.state.csv_fingerprint};
  }
  o.manifest = Manifest{o.state.command, &r, {}, {}, o.state.working_directory};
  try {
    o.report.emplace(staging, axes, r.rig.light->has(Source::kClosedFormEq6), f.csv, manifest_fields(o.manifest), resume);
    o.report->set_fixed_keys(fixed_keys(r.rig, axes));
  } catch (const std::runtime_error& e) {
    if (!resume) throw;
    throw std::runtime_error(fmt::format("--resume: {}; pass --force without --resume to start over", e.what()));
  }
}
}  // namespace

fs::path sweep_to_folder(const LoadedRig& r, const std::vector<GridAxis>& axes, int steps, const SweepFolder& f,
                         const Progress& progress) {
  check_grid(r.rig, axes);
  const Ranks& ranks = f.ranks ? *f.ranks : this_process_only();
  // Rank 0 opens the folder; every rank learns whether it could, and where to start.
  OpenSweep o;
  std::exception_ptr error;
  std::optional<std::string> failure;
  if (ranks.is_root()) {
    try {
      open_sweep(o, r, axes, steps, f);
    } catch (const std::exception& e) {
      error = std::current_exception();
      failure = rank_failure_text(e);
    }
  }
  if (const std::optional<std::string> first = ranks.first_failure(failure)) {
    if (error) std::rethrow_exception(error);
    throw_rank_failure(*first);  // the same kind of error, so every rank exits with rank 0's code
  }
  std::vector<std::byte> start(sizeof(std::size_t));
  std::memcpy(start.data(), &o.state.points_done, sizeof(std::size_t));
  ranks.broadcast(start);
  SweepOptions options;
  std::memcpy(&options.first_point, start.data(), sizeof(std::size_t));
  options.ranks = &ranks;

  // A checkpoint costs a few fsyncs: after the first block (so that an early interruption
  // already resumes), then at most once a second. The sink runs on rank 0 only.
  using Clock = std::chrono::steady_clock;
  auto last = Clock::now();
  bool checkpointed = false;
  // An error that would recur on resuming (a grid point that breaks a rule, a value out of its
  // domain, a programming error) leaves nothing; an I/O error or a signal keeps the staging
  // folder and its record for --resume.
  try {
    sweep(r.rig, axes, CsTurn(steps), [&](std::size_t first, std::span<const CsSummary> block) {
      o.report->write(first, block);
      if (checkpointed && Clock::now() - last < std::chrono::seconds(1)) return;
      const SweepReport::Resume at = o.report->sync();
      o.state.points_done = at.points_done;
      o.state.csv_bytes = at.csv_bytes;
      o.state.h5_fingerprint = at.h5_fingerprint;
      o.state.csv_fingerprint = at.csv_fingerprint;
      o.dir->keep_on_failure();  // first: a signal between the record and this would remove it
      write_sweep_state(o.dir->staging(), o.state);
      checkpointed = true;
      last = Clock::now();
    }, progress, options);
  } catch (const RigError&) {
    if (o.dir) o.dir->discard_on_failure();
    throw;
  } catch (const std::logic_error&) {
    if (o.dir) o.dir->discard_on_failure();
    throw;
  }
  // Rank 0 finishes the folder; every rank learns whether it could, so all exit alike.
  if (ranks.is_root()) {
    try {
      const fs::path staging = o.dir->staging();
      o.manifest.files = o.report->finish(f.plots);
      write_manifest(staging, o.manifest);
      // Every file on disk before the record goes and the folder moves: a power loss after
      // "wrote" must not leave holes (zeros) in a folder that no record can resume.
      for (const fs::directory_entry& e : fs::directory_iterator(staging))
        if (e.is_regular_file() && e.path().filename() != kSweepStateFile) sync_to_disk(e.path());
      sync_to_disk(staging);
      std::error_code ec;
      fs::remove(staging / kSweepStateFile, ec);
      if (ec) throw std::runtime_error(fmt::format("{}: cannot remove: {}", (staging / kSweepStateFile).string(), ec.message()));
      o.dir->discard_on_failure();  // no record now: nothing to resume
      sync_to_disk(staging);
      o.dir->commit();
      sync_to_disk(o.dir->destination().parent_path());
    } catch (const std::exception& e) {
      error = std::current_exception();
      failure = rank_failure_text(e);
    }
  }
  if (ranks.size() > 1)
    if (const std::optional<std::string> first = ranks.first_failure(failure); first && !error) throw_rank_failure(*first);
  if (error) std::rethrow_exception(error);
  return ranks.is_root() ? o.dir->destination() : fs::path{};
}

}  // namespace polrig
