#include "polrig/io/sweep_h5.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <deque>
#include <stdexcept>

#include <fmt/format.h>
#include <hdf5.h>
#include <hdf5_hl.h>

namespace polrig {
namespace fs = std::filesystem;

namespace {

// HDF5's own error stack is silenced: errors become exceptions naming the file and the step,
// with the library's innermost message.
struct Hdf5Error {
  std::string message;
  bool system = false;  // the innermost error is the file system's: errno says more
};

Hdf5Error hdf5_error() {
  Hdf5Error err;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, [](unsigned, const H5E_error2_t* e, void* out) -> herr_t {
    auto* m = static_cast<Hdf5Error*>(out);
    if (m->message.empty() && e->desc && *e->desc) {
      m->message = e->desc;
      m->system = e->maj_num == H5E_IO || e->maj_num == H5E_FILE;
    }
    return 0;
  }, &err);
  H5Eclear2(H5E_DEFAULT);
  if (err.message.empty()) err.message = "HDF5 error";
  return err;
}

[[noreturn]] void fail(const fs::path& path, const std::string& what) {
  const int errno_now = errno;
  Hdf5Error err = hdf5_error();
  // errno may be left from an unrelated earlier call: named only for the file system's errors.
  if (err.system && errno_now != 0 && err.message.find("errno") == std::string::npos)
    err.message += fmt::format(" ({})", std::strerror(errno_now));
  throw std::runtime_error(fmt::format("{}: cannot {}: {}", path.string(), what, err.message));
}

// An identifier or a status (herr_t): negative on failure.
hid_t check(hid_t id, const fs::path& path, const std::string& what) {
  if (id < 0) fail(path, what);
  return id;
}

// Closes an HDF5 identifier when it leaves scope.
class Id {
 public:
  Id(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  ~Id() {
    if (id_ >= 0) close_(id_);
  }
  operator hid_t() const { return id_; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

void silence_hdf5() {
  static const bool once = [] { return H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr) >= 0; }();
  (void)once;
}

// Fixed format versions (1.8's), so that the bytes do not depend on the library's defaults.
Id file_access(const fs::path& path) {
  Id fapl(check(H5Pcreate(H5P_FILE_ACCESS), path, "create a property list"), H5Pclose);
  check(H5Pset_libver_bounds(fapl, H5F_LIBVER_V18, H5F_LIBVER_V18), path, "set the format version");
  check(H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG), path, "set the close degree");
#if H5_VERSION_GE(1, 10, 7)
  // HDF5 locks its files, which some file systems cannot do: the staging folder's own lock
  // already keeps a second writer out, so go on there without HDF5's.
  check(H5Pset_file_locking(fapl, true, true), path, "set file locking");
#endif
  return Id(H5Pcopy(fapl), H5Pclose);
}

void write_text_attribute(hid_t object, const std::string& name, const std::string& text,
                          const fs::path& path) {
  Id type(check(H5Tcopy(H5T_C_S1), path, "make a string type"), H5Tclose);
  check(H5Tset_size(type, H5T_VARIABLE), path, "make a string type");
  check(H5Tset_cset(type, H5T_CSET_UTF8), path, "make a string type");
  Id space(check(H5Screate(H5S_SCALAR), path, "make a dataspace"), H5Sclose);
  const std::string what = fmt::format("write the attribute '{}'", name);
  Id attr(check(H5Acreate2(object, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT), path, what), H5Aclose);
  const char* data = text.c_str();
  check(H5Awrite(attr, type, &data), path, what.c_str());
}

void write_unit_and_description(hid_t object, const std::string& unit, const std::string& description,
                                const fs::path& path) {
  write_text_attribute(object, "units", unit, path);
  write_text_attribute(object, "description", description, path);
}

Id dataset_creation(const fs::path& path) {
  Id dcpl(check(H5Pcreate(H5P_DATASET_CREATE), path, "create a property list"), H5Pclose);
  check(H5Pset_layout(dcpl, H5D_CONTIGUOUS), path, "set the layout");
  // Allocated at creation and never filled: data positions are fixed, and writing a block
  // later (resuming) changes only that block's bytes.
  check(H5Pset_alloc_time(dcpl, H5D_ALLOC_TIME_EARLY), path, "set the allocation time");
  check(H5Pset_fill_time(dcpl, H5D_FILL_TIME_NEVER), path, "set the fill time");
  check(H5Pset_obj_track_times(dcpl, false), path, "turn off timestamps");
  return Id(H5Pcopy(dcpl), H5Pclose);
}

std::vector<hsize_t> shape_of(const SweepH5Layout& layout) {
  std::vector<hsize_t> shape;
  for (const SweepH5Axis& a : layout.axes) shape.push_back(a.size);
  return shape;
}

// Selects points [first, first + n) (row-major) of `shape` in `space`: a union of at most
// 2·rank boxes, each the largest aligned box that starts where the previous one ended.
void select_points(hid_t space, const std::vector<hsize_t>& shape, std::size_t first, std::size_t n,
                   const fs::path& path) {
  const std::size_t rank = shape.size();
  std::vector<hsize_t> stride(rank, 1);  // points per step of each axis
  for (std::size_t d = rank - 1; d > 0; --d) stride[d - 1] = stride[d] * shape[d];
  check(H5Sselect_none(space), path, "select points");
  std::vector<hsize_t> start(rank), count(rank);
  for (std::size_t at = first, end = first + n; at < end;) {
    for (std::size_t d = 0; d < rank; ++d) {
      if (at % stride[d] != 0) continue;  // not aligned to whole steps of axis d
      const hsize_t index = (at / stride[d]) % shape[d];
      const hsize_t steps = std::min<hsize_t>((end - at) / stride[d], shape[d] - index);
      if (steps == 0) continue;
      for (std::size_t e = 0; e < rank; ++e) {
        start[e] = e <= d ? (at / stride[e]) % shape[e] : 0;
        count[e] = e < d ? 1 : e == d ? steps : shape[e];
      }
      check(H5Sselect_hyperslab(space, H5S_SELECT_OR, start.data(), nullptr, count.data(), nullptr),
            path, "select points");
      at += steps * stride[d];
      break;
    }
  }
}

std::vector<hsize_t> dataset_shape(hid_t dataset, const fs::path& path, const std::string& name) {
  Id space(check(H5Dget_space(dataset), path, "read the shape of " + name), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space);
  if (rank < 0) fail(path, "read the shape of " + name);
  std::vector<hsize_t> shape(static_cast<std::size_t>(rank));
  if (H5Sget_simple_extent_dims(space, shape.data(), nullptr) < 0) fail(path, "read the shape of " + name);
  return shape;
}

std::size_t product(const std::vector<hsize_t>& shape) {
  std::size_t p = 1;
  for (hsize_t s : shape) p *= s;
  return p;
}

}  // namespace

std::size_t SweepH5Layout::points() const {
  std::size_t p = 1;
  for (const SweepH5Axis& a : axes) p *= a.size;
  return p;
}

SweepH5Writer::SweepH5Writer(fs::path path, const SweepH5Layout& layout, std::int64_t file)
    : path_(std::move(path)), shape_(shape_of(layout)), file_(file) {}

SweepH5Writer::SweepH5Writer(SweepH5Writer&& o) noexcept
    : path_(std::move(o.path_)), shape_(std::move(o.shape_)), file_(o.file_), datasets_(std::move(o.datasets_)) {
  o.file_ = -1;
  o.datasets_.clear();
}

SweepH5Writer::~SweepH5Writer() {
  for (hid_t d : datasets_) H5Dclose(d);
  if (file_ >= 0) H5Fclose(file_);
}

SweepH5Writer SweepH5Writer::create(const fs::path& path, const SweepH5Layout& layout) {
  silence_hdf5();
  if (layout.axes.empty()) throw std::invalid_argument("sweep.h5: a grid with no axis");
  Id fcpl(check(H5Pcreate(H5P_FILE_CREATE), path, "create a property list"), H5Pclose);
  check(H5Pset_obj_track_times(fcpl, false), path, "turn off timestamps");
  Id fapl = file_access(path);
  errno = 0;
  SweepH5Writer w(path, layout, check(H5Fcreate(path.c_str(), H5F_ACC_EXCL, fcpl, fapl), path, "create the file"));
  for (const auto& [name, text] : layout.attributes) write_text_attribute(w.file_, name, text, path);

  Id dcpl = dataset_creation(path);
  const hid_t type = H5T_IEEE_F64LE;
  std::vector<hid_t> scales;
  std::deque<Id> scale_ids;
  for (const SweepH5Axis& a : layout.axes) {
    const hsize_t size = a.size;
    Id space(check(H5Screate_simple(1, &size, nullptr), path, "make a dataspace"), H5Sclose);
    const std::string what = fmt::format("write the axis '{}'", a.name);
    scale_ids.emplace_back(check(H5Dcreate2(w.file_, a.name.c_str(), type, space, H5P_DEFAULT, dcpl,
                                            H5P_DEFAULT), path, what), H5Dclose);
    const hid_t d = scale_ids.back();
    // A slice at a time: an axis may have 1e8 values.
    constexpr std::size_t kSlice = 1 << 16;
    std::vector<double> values(std::min<std::size_t>(a.size, kSlice));
    for (std::size_t first = 0; first < a.size; first += kSlice) {
      const std::size_t n = std::min(kSlice, a.size - first);
      for (std::size_t i = 0; i < n; ++i) values[i] = a.value(first + i);
      select_points(space, {size}, first, n, path);
      const hsize_t count = n;
      Id memory(check(H5Screate_simple(1, &count, nullptr), path, "make a dataspace"), H5Sclose);
      check(H5Dwrite(d, H5T_NATIVE_DOUBLE, memory, space, H5P_DEFAULT, values.data()), path, what.c_str());
    }
    write_unit_and_description(d, a.unit, a.description, path);
    check(H5DSset_scale(d, a.name.c_str()), path, what.c_str());
    scales.push_back(d);
  }
  Id space(check(H5Screate_simple(static_cast<int>(w.shape_.size()), w.shape_.data(), nullptr), path,
                 "make a dataspace"), H5Sclose);
  for (const SweepH5Column& c : layout.columns) {
    const std::string what = fmt::format("create the dataset '{}'", c.name);
    const hid_t d = check(H5Dcreate2(w.file_, c.name.c_str(), type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT), path, what);
    w.datasets_.push_back(d);
    write_unit_and_description(d, c.unit, c.description, path);
    for (std::size_t k = 0; k < scales.size(); ++k)
      check(H5DSattach_scale(d, scales[k], static_cast<unsigned>(k)), path, what.c_str());
  }
  w.sync();
  return w;
}

SweepH5Writer SweepH5Writer::reopen(const fs::path& path, const SweepH5Layout& layout) {
  silence_hdf5();
  Id fapl = file_access(path);
  errno = 0;
  SweepH5Writer w(path, layout, check(H5Fopen(path.c_str(), H5F_ACC_RDWR, fapl), path, "open the file"));
  for (const SweepH5Column& c : layout.columns) {
    const std::string what = fmt::format("open the dataset '{}'", c.name);
    w.datasets_.push_back(check(H5Dopen2(w.file_, c.name.c_str(), H5P_DEFAULT), path, what));
    if (dataset_shape(w.datasets_.back(), path, c.name) != w.shape_)
      throw std::runtime_error(fmt::format("{}: the dataset '{}' does not have the grid's shape",
                                           path.string(), c.name));
  }
  return w;
}

void SweepH5Writer::write(std::size_t first, std::size_t n, std::span<const double> values) {
  if (values.size() != n * datasets_.size() || first + n > product(shape_))
    throw std::logic_error(fmt::format("{}: a block of {} values at point {}", path_.string(), values.size(), first));
  if (n == 0) return;
  Id file_space(check(H5Screate_simple(static_cast<int>(shape_.size()), shape_.data(), nullptr), path_,
                      "make a dataspace"), H5Sclose);
  select_points(file_space, shape_, first, n, path_);
  const hsize_t count = n;
  Id memory(check(H5Screate_simple(1, &count, nullptr), path_, "make a dataspace"), H5Sclose);
  for (std::size_t c = 0; c < datasets_.size(); ++c) {
    errno = 0;
    check(H5Dwrite(datasets_[c], H5T_NATIVE_DOUBLE, memory, file_space, H5P_DEFAULT, values.data() + c * n),
          path_, "write");
  }
}

void SweepH5Writer::sync() {
  errno = 0;
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL), path_, "flush");
  void* handle = nullptr;
  check(H5Fget_vfd_handle(file_, H5P_DEFAULT, &handle), path_, "find the file descriptor");
  if (::fsync(*static_cast<int*>(handle)) != 0)
    throw std::runtime_error(fmt::format("{}: cannot sync to disk: {}", path_.string(), std::strerror(errno)));
}

void SweepH5Writer::close() {
  for (hid_t d : datasets_) H5Dclose(d);
  datasets_.clear();
  const hid_t f = file_;
  file_ = -1;
  errno = 0;
  if (f >= 0) check(H5Fclose(f), path_, "close");
}

SweepH5Reader::SweepH5Reader(const fs::path& path) : path_(path) {
  silence_hdf5();
  errno = 0;
  file_ = check(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), path, "open the file");
}

SweepH5Reader::~SweepH5Reader() {
  if (file_ >= 0) H5Fclose(file_);
}

void SweepH5Reader::read(const std::string& name, std::size_t first, std::span<double> out) const {
  const std::string what = fmt::format("read the dataset '{}'", name);
  Id d(check(H5Dopen2(file_, name.c_str(), H5P_DEFAULT), path_, what), H5Dclose);
  const std::vector<hsize_t> shape = dataset_shape(d, path_, name);
  if (first + out.size() > product(shape))
    throw std::logic_error(fmt::format("{}: reading points {}..{} of {}", path_.string(), first,
                                       first + out.size(), product(shape)));
  if (out.empty()) return;
  Id file_space(check(H5Dget_space(d), path_, what), H5Sclose);
  select_points(file_space, shape, first, out.size(), path_);
  const hsize_t count = out.size();
  Id memory(check(H5Screate_simple(1, &count, nullptr), path_, "make a dataspace"), H5Sclose);
  check(H5Dread(d, H5T_NATIVE_DOUBLE, memory, file_space, H5P_DEFAULT, out.data()), path_, what.c_str());
}

}  // namespace polrig
