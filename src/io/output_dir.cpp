#include "polrig/io/output_dir.h"

#include <unistd.h>

#include <algorithm>
#include <stdexcept>

#include <fmt/format.h>

namespace polrig {
namespace fs = std::filesystem;

OutputDir::OutputDir(fs::path destination, bool replace)
    : destination_(fs::absolute(std::move(destination)).lexically_normal()), replace_(replace) {
  if (destination_.filename().empty()) destination_ = destination_.parent_path();
  // Replacing a folder that holds the working directory would delete the user's work.
  const fs::path cwd = fs::current_path().lexically_normal();
  const auto [d_end, c_it] = std::mismatch(destination_.begin(), destination_.end(), cwd.begin(), cwd.end());
  if (d_end == destination_.end() || destination_ == destination_.root_path())
    throw std::runtime_error(fmt::format(
        "{}: refusing to write an output folder that contains the current directory",
        destination_.string()));
  if (fs::exists(destination_) && !replace_)
    throw std::runtime_error(fmt::format(
        "{}: the output folder exists; choose another or pass --force to replace it",
        destination_.string()));
  for (fs::path p = destination_.parent_path(); !p.empty() && !fs::exists(p); p = p.parent_path())
    created_parents_.insert(created_parents_.begin(), p);
  std::error_code ec;
  for (const fs::path& p : created_parents_) {
    if (!fs::create_directory(p, ec) && ec)
      throw std::runtime_error(fmt::format("{}: cannot create the folder: {}", p.string(),
                                           ec.message()));
  }
  staging_ = destination_.parent_path() /
             fmt::format(".{}.partial-{}", destination_.filename().string(), ::getpid());
  fs::remove_all(staging_, ec);
  if (!fs::create_directory(staging_, ec))
    throw std::runtime_error(fmt::format("{}: cannot create the output folder: {}",
                                         staging_.string(), ec.message()));
}

void OutputDir::commit() {
  std::error_code ec;
  fs::path old;
  if (fs::exists(destination_)) {
    old = destination_.parent_path() /
          fmt::format(".{}.old-{}", destination_.filename().string(), ::getpid());
    fs::rename(destination_, old);
  }
  fs::rename(staging_, destination_);
  committed_ = true;
  if (!old.empty()) fs::remove_all(old, ec);
}

OutputDir::~OutputDir() {
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);
  for (auto it = created_parents_.rbegin(); it != created_parents_.rend(); ++it)
    fs::remove(*it, ec);  // only removes a folder that is still empty
}

}  // namespace polrig
