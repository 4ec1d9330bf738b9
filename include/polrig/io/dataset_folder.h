#pragma once
// A dataset's folder opened once, so that every file a reader takes from it is the folder's as it
// was when opened: polrig replaces an output folder by an atomic exchange of folders
// (io/output_dir.h), so a reader that opens imu.csv, then units.csv, while `simulate --force`
// replaces the dataset reads both from the old folder, or fails (its files deleted) with a
// message naming the file; it never mixes two datasets.
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace polrig {

class DatasetFolder {
 public:
  // Throws DataError (io/measured.h) when `dir` is not a folder that can be opened.
  explicit DatasetFolder(std::filesystem::path dir);
  ~DatasetFolder();
  DatasetFolder(const DatasetFolder&) = delete;
  DatasetFolder& operator=(const DatasetFolder&) = delete;

  const std::filesystem::path& path() const { return dir_; }
  // The name within the folder as a reader's messages name it: DIR/name.
  std::filesystem::path path(std::string_view name) const { return dir_ / name; }
  // True when the folder holds a regular file of that name.
  bool has(std::string_view name) const;
  // A read-only descriptor of the named regular file (the caller closes it), or DataError naming
  // DIR/name: no such file, not a regular file, cannot be opened.
  int open(std::string_view name) const;
  // The whole file, of at most max_bytes (checked before it is read: DataError naming DIR/name,
  // its size and the limit, so that a reader's memory never follows a file it cannot take).
  std::string read(std::string_view name, std::uintmax_t max_bytes) const;

 private:
  std::filesystem::path dir_;
  int fd_ = -1;
};

}  // namespace polrig
