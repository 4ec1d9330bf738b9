#pragma once
// sweep.h5 (docs/formats.md): one N-dimensional float64 dataset per summary column, shaped as
// the grid (axis order, row-major: the last axis varies fastest), one 1-D dataset per axis
// holding its values, made an HDF5 dimension scale and attached to every column, and the
// manifest as attributes of the file.
//
// Every dataset is contiguous and allocated when the file is created (no fill values), and
// objects carry no timestamps: the file's bytes depend only on its layout and on the values
// written, never on when, in how many runs (resuming) or by how many threads they were written.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace polrig {

struct SweepH5Axis {
  std::string name, unit, description;
  std::size_t size = 0;
  std::function<double(std::size_t)> value;  // the grid's values along this axis, computed on demand
};

struct SweepH5Column {
  std::string name, unit, description;
  bool may_be_nan = false;  // NaN marks an undefined value (documented in its description)
};

struct SweepH5Layout {
  std::vector<SweepH5Axis> axes;      // the datasets' dimensions, in order
  std::vector<SweepH5Column> columns;
  std::vector<std::pair<std::string, std::string>> attributes;  // of the file: name, text
  std::size_t points() const;  // the product of the axes' sizes
};

// Writes a sweep.h5 as its points are computed: blocks of consecutive points in grid order.
class SweepH5Writer {
 public:
  // Creates the file (refusing an existing one) with every dataset allocated, the axes and
  // attributes written, and flushes it. Throws std::runtime_error naming the path.
  static SweepH5Writer create(const std::filesystem::path& path, const SweepH5Layout& layout);
  // Opens a file made by create() with the same layout, to write more of its points (resuming).
  static SweepH5Writer reopen(const std::filesystem::path& path, const SweepH5Layout& layout);
  SweepH5Writer(SweepH5Writer&&) noexcept;
  SweepH5Writer& operator=(SweepH5Writer&&) = delete;
  ~SweepH5Writer();  // closes without checking: call close() to know the file is whole

  // Points [first, first + n) of every column: `values` holds column c's n values at [c·n, c·n + n).
  void write(std::size_t first, std::size_t n, std::span<const double> values);
  // Makes everything written so far durable (H5Fflush, then fsync).
  void sync();
  void close();

 private:
  SweepH5Writer(std::filesystem::path path, const SweepH5Layout& layout, std::int64_t file);
  std::filesystem::path path_;
  std::vector<unsigned long long> shape_;
  std::int64_t file_ = -1;
  std::vector<std::int64_t> datasets_;  // one per column
};

// Reads a sweep.h5's columns back, a range of points at a time (the plots, tests).
class SweepH5Reader {
 public:
  explicit SweepH5Reader(const std::filesystem::path& path);
  SweepH5Reader(const SweepH5Reader&) = delete;
  SweepH5Reader& operator=(const SweepH5Reader&) = delete;
  ~SweepH5Reader();
  // Points [first, first + out.size()) of the column named `name`.
  void read(const std::string& name, std::size_t first, std::span<double> out) const;

 private:
  std::filesystem::path path_;
  std::int64_t file_ = -1;
};

}  // namespace polrig
