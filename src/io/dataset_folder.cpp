// A dataset's folder opened once (include/polrig/io/dataset_folder.h).
#include "polrig/io/dataset_folder.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include <fmt/format.h>

#include "polrig/io/measured.h"

namespace polrig {

DatasetFolder::DatasetFolder(std::filesystem::path dir) : dir_(std::move(dir)) {
  fd_ = ::open(dir_.empty() ? "." : dir_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ < 0)
    throw DataError(fmt::format("{}: cannot open the dataset folder: {}", dir_.string(),
                                errno == ENOTDIR ? "not a folder" : std::strerror(errno)));
}

DatasetFolder::~DatasetFolder() {
  if (fd_ >= 0) ::close(fd_);
}

bool DatasetFolder::has(std::string_view name) const {
  struct stat st {};
  return ::fstatat(fd_, std::string(name).c_str(), &st, 0) == 0 && S_ISREG(st.st_mode);
}

int DatasetFolder::open(std::string_view name) const {
  const std::string n(name);
  struct stat st {};
  if (::fstatat(fd_, n.c_str(), &st, 0) != 0)
    throw DataError(fmt::format("{}: cannot read the file: {}", path(name).string(),
                                errno == ENOENT ? "no such file" : std::strerror(errno)));
  if (!S_ISREG(st.st_mode)) throw DataError(fmt::format("{}: cannot read the file: not a regular file", path(name).string()));
  const int fd = ::openat(fd_, n.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw DataError(fmt::format("{}: cannot read the file: {}", path(name).string(), std::strerror(errno)));
  return fd;
}

std::string DatasetFolder::read(std::string_view name, std::uintmax_t max_bytes) const {
  const int fd = open(name);
  struct stat st {};
  if (::fstat(fd, &st) == 0 && static_cast<std::uintmax_t>(st.st_size) > max_bytes) {
    ::close(fd);
    throw DataError(fmt::format("{}: {} bytes, more than the {} bytes its reader takes", path(name).string(),
                                static_cast<std::uintmax_t>(st.st_size), max_bytes));
  }
  std::string text;
  char buf[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int err = errno;
      ::close(fd);
      throw DataError(fmt::format("{}: cannot read the file: {}", path(name).string(), std::strerror(err)));
    }
    if (n == 0) break;
    text.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fd);
  return text;
}

}  // namespace polrig
