#include "polrig/io/output_dir.h"

#include <fcntl.h>
#include <sys/file.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <set>
#include <string_view>
#include <stdexcept>
#include <thread>

#include <fmt/format.h>

namespace polrig {
namespace fs = std::filesystem;

int rename_no_replace(const fs::path& from, const fs::path& to) noexcept {
  return ::renameat2(AT_FDCWD, from.c_str(), AT_FDCWD, to.c_str(), RENAME_NOREPLACE) == 0 ? 0 : errno;
}

int rename_exchange(const fs::path& a, const fs::path& b) noexcept {
  return ::renameat2(AT_FDCWD, a.c_str(), AT_FDCWD, b.c_str(), RENAME_EXCHANGE) == 0 ? 0 : errno;
}

namespace {

fs::path resolved(const fs::path& p) {
  std::error_code ec;
  fs::path r = fs::weakly_canonical(fs::absolute(p, ec), ec);
  if (ec) r = fs::absolute(p, ec).lexically_normal();
  if (r.filename().empty()) r = r.parent_path();  // "DS/" as "DS"
  return r;
}

// True when `inner` is `outer` or lies below it, component by component.
bool within(const fs::path& inner, const fs::path& outer) {
  auto i = inner.begin();
  for (auto o = outer.begin(); o != outer.end(); ++o, ++i)
    if (i == inner.end() || *i != *o) return false;
  return true;
}

}  // namespace

void refuse_output_over_inputs(const fs::path& destination, const std::vector<fs::path>& inputs) {
  const fs::path out = resolved(destination);
  for (const fs::path& input : inputs) {
    std::error_code ec;
    if (input.empty() || !fs::exists(fs::symlink_status(input, ec))) continue;
    const fs::path in = resolved(input);
    const char* how = out == in ? "is" : within(in, out) ? "contains" : within(out, in) ? "lies inside" : nullptr;
    if (!how) continue;
    throw std::invalid_argument(fmt::format(
        "the output folder {} {} the input {} ({}); choose an output folder apart from the inputs",
        destination.string(), how, input.string(),
        std::string_view(how) == "lies inside" ? "the output would be written into the input"
                                               : "replacing the folder would delete the input"));
  }
}

namespace {

// The folders a signal must clean up. The lock is held while a folder is created, committed or
// removed, so the signal thread never sees one half made.
std::mutex& open_dirs_mutex() {
  static std::mutex m;
  return m;
}
std::set<OutputDir*>& open_dirs() {
  static std::set<OutputDir*> dirs;
  return dirs;
}

std::runtime_error error(const fs::path& p, const std::string& what) {
  return std::runtime_error(fmt::format("{}: {}", p.string(), what));
}

// The type of `p` itself (a symbolic link is not followed); not_found when nothing is there.
fs::file_type type_of(const fs::path& p) {
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(p, ec);
  if (st.type() == fs::file_type::not_found) return st.type();
  if (ec) throw error(p, fmt::format("cannot look at the path: {}", ec.message()));
  return st.type();
}

std::string what_is_there(const fs::path& p, fs::file_type t) {
  if (t != fs::file_type::symlink) return t == fs::file_type::directory ? "a folder" : "a file";
  std::error_code ec;
  const fs::path target = fs::read_symlink(p, ec);
  if (!fs::exists(p, ec)) return fmt::format("a symbolic link to '{}', which does not exist", target.string());
  return fmt::format("a symbolic link to '{}'", target.string());
}

long name_max_at(const fs::path& existing_folder) {
  errno = 0;
  const long n = ::pathconf(existing_folder.c_str(), _PC_NAME_MAX);
  return n > 0 ? n : NAME_MAX;
}

// Checks, inside `folder`, that the file system does the renames commit() relies on: a
// no-replace rename and, to replace, an exchange.
void probe_atomic_renames(const fs::path& folder, bool exchange) {
  const fs::path a = folder / ".rename-probe-a", b = folder / ".rename-probe-b";
  std::error_code ec;
  fs::remove(a, ec);  // left by a run killed while probing a kept (resumable) staging folder
  fs::remove(b, ec);
  for (bool swap : {false, true}) {
    if (swap && !exchange) break;
    for (const fs::path& p : {a, b})
      if (p == a || swap)
        if (!fs::create_directory(p, ec))
          throw error(p, fmt::format("cannot create a folder in the staging folder: {}", ec.message()));
    const int err = swap ? rename_exchange(a, b) : rename_no_replace(a, b);
    fs::remove(a, ec);
    fs::remove(b, ec);
    const char* flag = swap ? "RENAME_EXCHANGE" : "RENAME_NOREPLACE";
    if (err == EINVAL || err == ENOSYS)
      throw error(folder.parent_path(),
                  fmt::format("the file system does not support atomic {} renames (renameat2 {}: "
                              "{}), which polrig needs to {}; write the output elsewhere",
                              swap ? "exchanging" : "no-replace", flag, std::strerror(err),
                              swap ? "replace an output folder without a moment where it is missing"
                                   : "never replace an existing output folder"));
    if (err)
      throw error(folder, fmt::format("cannot rename inside the staging folder (renameat2 {}): {}",
                                      flag, std::strerror(err)));
  }
}

}  // namespace

OutputDir::OutputDir(fs::path destination, bool replace) : replace_(replace) {
  prepare(destination, fmt::format(".partial-{}", ::getpid()).c_str());
  const std::lock_guard lock(open_dirs_mutex());
  try {
    create_parents();
    std::error_code ec;
    fs::remove_all(staging_, ec);  // left by a killed run that had our process id
    if (!fs::create_directory(staging_, ec))
      throw error(staging_, fmt::format("cannot create the staging folder: {}",
                                        ec ? ec.message() : std::string("it exists")));
    probe_atomic_renames(staging_, replace_);
    open_dirs().insert(this);
  } catch (...) {
    remove_staging_and_parents();
    throw;
  }
}

OutputDir::OutputDir(fs::path destination, bool replace, const Resumable& resumable)
    : continue_with_(resumable.continue_with), replace_(replace) {
  prepare(destination, ".resumable");
  const std::lock_guard lock(open_dirs_mutex());
  try {
    create_parents();
    open_resumable(resumable);
    probe_atomic_renames(staging_, replace_);
    open_dirs().insert(this);
  } catch (...) {
    if (!keep_) remove_staging_and_parents();
    if (lock_fd_ >= 0) ::close(lock_fd_);
    lock_fd_ = -1;
    throw;
  }
}

void OutputDir::open_resumable(const Resumable& r) {
  std::error_code ec;
  const fs::file_type there = type_of(staging_);
  if (there != fs::file_type::not_found && there != fs::file_type::directory)
    throw error(staging_, fmt::format("the staging folder's name is taken by {}; remove it",
                                      what_is_there(staging_, there)));
  if (there == fs::file_type::not_found) {
    if (r.resume)
      throw std::runtime_error(fmt::format("--resume: there is no interrupted run of {} to continue (no {})",
                                           destination_.string(), staging_.filename().string()));
    if (!fs::create_directory(staging_, ec) && ec)
      throw error(staging_, fmt::format("cannot create the staging folder: {}", ec.message()));
    // Durable before its first progress record, which only syncs the folder itself.
    const int parent = ::open(staging_.parent_path().c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (parent >= 0) {
      ::fsync(parent);
      ::close(parent);
    }
  }
  lock_fd_ = ::open(staging_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (lock_fd_ < 0)
    throw error(staging_, fmt::format("cannot open the staging folder: {}", std::strerror(errno)));
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    keep_ = true;  // another process's
    throw error(staging_, errno == EWOULDBLOCK
                              ? "another polrig is writing this output folder now (its staging "
                                "folder is locked); wait for it or choose another folder"
                              : fmt::format("cannot lock the staging folder: {}", std::strerror(errno)));
  }
  const bool interrupted = fs::exists(staging_ / r.record, ec);
  if (interrupted && r.resume) {
    resuming_ = keep_ = true;
    return;
  }
  if (interrupted && !r.restart) {
    keep_ = true;
    throw error(destination_, fmt::format("an interrupted run left its staging folder {}: --resume "
                                          "continues it; --force starts over", staging_.string()));
  }
  if (r.resume)
    throw error(staging_, fmt::format("--resume: the staging folder holds no progress record (the "
                                      "run was stopped before its first checkpoint); run again "
                                      "without --resume"));
  // Started over: empty the folder we hold locked.
  for (const auto& e : fs::directory_iterator(staging_, ec)) fs::remove_all(e.path(), ec);
  if (ec) throw error(staging_, fmt::format("cannot empty the staging folder: {}", ec.message()));
}

void OutputDir::prepare(const fs::path& destination, const char* staging_suffix) {
  if (destination.empty()) throw std::runtime_error("the output folder's name is empty");
  std::error_code ec;
  destination_ = fs::absolute(destination, ec).lexically_normal();
  if (ec) throw error(destination, fmt::format("cannot resolve the output folder: {}", ec.message()));
  if (destination_.filename().empty()) destination_ = destination_.parent_path();
  // Replacing a folder that holds the working directory would delete the user's work.
  const fs::path cwd = fs::current_path(ec).lexically_normal();  // empty if it was deleted
  const auto [d_end, c_it] = std::mismatch(destination_.begin(), destination_.end(), cwd.begin(), cwd.end());
  if ((!cwd.empty() && d_end == destination_.end()) || destination_ == destination_.root_path())
    throw error(destination_, "refusing to write an output folder that contains the current directory");

  const fs::file_type there = type_of(destination_);
  if (there != fs::file_type::not_found && !replace_)
    throw error(destination_, fmt::format("the output folder exists ({}); choose another or pass "
                                          "--force to replace it",
                                          what_is_there(destination_, there)));

  // The nearest existing ancestor must be a folder; the ones below it are created.
  fs::path existing = destination_.parent_path();
  for (; !existing.empty() && type_of(existing) == fs::file_type::not_found; existing = existing.parent_path())
    missing_parents_.insert(missing_parents_.begin(), existing);
  if (!fs::is_directory(existing, ec))
    throw error(existing, fmt::format("cannot create the output folder inside it: it is {}",
                                      what_is_there(existing, type_of(existing))));

  const std::string staging_name = fmt::format(".{}{}", destination_.filename().string(), staging_suffix);
  const long name_max = name_max_at(existing);
  const std::size_t overhead = staging_name.size() - destination_.filename().string().size();
  if (static_cast<long>(staging_name.size()) > name_max)
    throw error(destination_, fmt::format("the folder name is {} bytes long; at most {} fit here "
                                          "(the file system allows {} and the staging folder "
                                          "'.NAME{}' adds {})",
                                          destination_.filename().string().size(),
                                          name_max - static_cast<long>(overhead), name_max,
                                          staging_suffix, overhead));
  for (const fs::path& p : missing_parents_)
    if (p.filename().string().size() > static_cast<std::size_t>(name_max))
      throw error(p, fmt::format("the folder name is {} bytes long; the file system allows {}",
                                 p.filename().string().size(), name_max));
  staging_ = destination_.parent_path() / staging_name;
}

void OutputDir::create_parents() {
  std::error_code ec;
  for (const fs::path& p : missing_parents_) {
    if (fs::create_directory(p, ec))
      created_parents_.push_back(p);  // not one that another process made meanwhile
    else if (ec)
      throw error(p, fmt::format("cannot create the folder: {}", ec.message()));
  }
}

void OutputDir::keep_on_failure() {
  const std::lock_guard lock(open_dirs_mutex());  // the signal thread reads it under this lock
  keep_ = true;
}

void OutputDir::discard_on_failure() {
  const std::lock_guard lock(open_dirs_mutex());
  keep_ = false;
}

void OutputDir::commit() {
  const std::lock_guard lock(open_dirs_mutex());
  // Three tries cover another process creating or removing the destination in between.
  for (int attempt = 0; attempt < 3; ++attempt) {
    int err = rename_no_replace(staging_, destination_);
    if (err == 0) {
      committed_ = true;
      return;
    }
    if (err != EEXIST)
      throw error(destination_, fmt::format("cannot move the finished output into place: {}",
                                            std::strerror(err)));
    if (!replace_)
      throw error(destination_, "the output folder appeared while polrig was computing; it was "
                                "left as it was and nothing was written (choose another or pass "
                                "--force to replace it)");
    err = rename_exchange(staging_, destination_);
    if (err == 0) {
      committed_ = true;
      std::error_code ec;
      fs::remove_all(staging_, ec);  // now the old destination
      return;
    }
    if (err != ENOENT)
      throw error(destination_, fmt::format("cannot swap the finished output into place: {}",
                                            std::strerror(err)));
  }
  throw error(destination_, "the output folder kept appearing and disappearing; nothing was written");
}

void OutputDir::remove_staging_and_parents() noexcept {
  if (keep_ && !committed_) return;  // a resumable run's progress
  std::error_code ec;
  // A few tries: on a signal, another thread may still be writing into the staging folder.
  for (int attempt = 0; attempt < 10 && !staging_.empty() && fs::exists(staging_, ec); ++attempt)
    fs::remove_all(staging_, ec);
  if (committed_) return;  // the parents now hold the destination
  for (auto it = created_parents_.rbegin(); it != created_parents_.rend(); ++it)
    fs::remove(*it, ec);  // only removes a folder that is still empty
}

void OutputDir::say_what_is_kept() const noexcept {
  if (!keep_ || committed_ || staging_.empty()) return;
  std::error_code ec;
  std::uintmax_t bytes = 0;
  for (auto it = fs::recursive_directory_iterator(staging_, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec))
    if (it->is_regular_file(ec)) bytes += it->file_size(ec);
  const std::string how = continue_with_.empty() ? "run the same command with --resume" : continue_with_;
  const std::string here = fs::current_path(ec).string();  // the command's relative paths start here
  std::fprintf(stderr, "%spolrig: interrupted; the work done so far is kept in %s (%.1f MB)\n"
               "polrig: to continue it, in %s: %s\n",
               ::isatty(2) ? "\r\033[K" : "", staging_.c_str(), static_cast<double>(bytes) / 1e6, here.c_str(),
               how.c_str());
}

OutputDir::~OutputDir() {
  const std::lock_guard lock(open_dirs_mutex());
  open_dirs().erase(this);
  if (!committed_) remove_staging_and_parents();
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

void clean_up_outputs_on_signals() {
  sigset_t signals;
  sigemptyset(&signals);
  // A signal the parent set to be ignored (nohup, a background job of a script) stays ignored:
  // blocking it for sigwait would deliver it after all.
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    if (sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    sigaddset(&signals, sig);
  }
  if (sigisemptyset(&signals) || pthread_sigmask(SIG_BLOCK, &signals, nullptr) != 0) return;
  std::thread([signals] {
    int sig = 0;
    if (sigwait(&signals, &sig) != 0) return;
    {
      const std::lock_guard lock(open_dirs_mutex());  // held until the process ends
      for (OutputDir* d : open_dirs()) {
        d->say_what_is_kept();
        d->remove_staging_and_parents();
      }
      // Ends by the signal itself, so that a shell sees how the command stopped.
      ::signal(sig, SIG_DFL);
      sigset_t one;
      sigemptyset(&one);
      sigaddset(&one, sig);
      pthread_sigmask(SIG_UNBLOCK, &one, nullptr);
      ::raise(sig);
      ::_exit(128 + sig);
    }
  }).detach();
}

}  // namespace polrig
