#pragma once
// An output folder that appears whole or not at all: files are written into a staging folder
// beside the destination, which is renamed into place by commit(). Without commit() (an error,
// an exception) the staging folder is removed and the destination is left as it was.
#include <filesystem>
#include <vector>

namespace polrig {

class OutputDir {
 public:
  // Throws std::runtime_error if `destination` exists and `replace` is false.
  OutputDir(std::filesystem::path destination, bool replace);
  ~OutputDir();
  OutputDir(const OutputDir&) = delete;
  OutputDir& operator=(const OutputDir&) = delete;

  const std::filesystem::path& staging() const { return staging_; }
  const std::filesystem::path& destination() const { return destination_; }
  void commit();

 private:
  std::filesystem::path destination_, staging_;
  std::vector<std::filesystem::path> created_parents_;
  bool replace_ = false, committed_ = false;
};

}  // namespace polrig
