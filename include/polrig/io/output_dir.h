#pragma once
// An output folder that appears whole or not at all: files are written into a staging folder
// beside the destination, which is renamed into place by commit(). Without commit() (an error,
// an exception) the staging folder and any parent folders the constructor created are removed,
// and the destination is left as it was.
//
// commit() never replaces an existing destination unless `replace` was given, even one that
// appeared while polrig was computing (renameat2 RENAME_NOREPLACE). With `replace` it swaps the
// two folders atomically (RENAME_EXCHANGE), so the destination exists at every instant, then
// removes the old one. A file system without these renames is refused when the folder is
// opened, before any computation.
//
// A resumable folder (a long sweep) stages in '.NAME.resumable' instead, a fixed name, locked
// (flock) while a process writes it. Once keep_on_failure() is called (the first progress
// record is on disk), the staging folder survives errors, signals, kill -9 and power loss, so
// that a later run can continue it.
#include <filesystem>
#include <string>
#include <vector>

namespace polrig {

struct Resumable {
  std::string record;   // the file in the staging folder that marks an interrupted, resumable run
  bool resume = false;  // continue an interrupted run (its staging folder must hold `record`)
  bool restart = false; // discard an interrupted run's staging folder (--force)
  std::string continue_with;  // the command that continues an interrupted run, said on a signal
};

class OutputDir {
 public:
  // Throws std::runtime_error, naming the path and leaving nothing behind, if `destination` is
  // empty, exists (even as a dangling symbolic link) and `replace` is false, has a name too long
  // for its staging folder, or cannot be created.
  OutputDir(std::filesystem::path destination, bool replace);
  // A resumable folder. Also throws if another process holds the staging folder; if it holds an
  // interrupted run's record and neither `resume` nor `restart` is given (the message says
  // "--resume continues it; --force starts over"); if `resume` is given and there is no record.
  // A staging folder without a record (killed before its first) is started over.
  OutputDir(std::filesystem::path destination, bool replace, const Resumable& resumable);
  // True when the staging folder holds an interrupted run to continue.
  bool resuming() const { return resuming_; }
  // From now on the staging folder is kept when the folder is not committed (also by a signal
  // arriving meanwhile: call it before writing the first progress record).
  void keep_on_failure();
  // From now on the staging folder is removed again when the folder is not committed: a failure
  // that resuming would only repeat, or after the progress record is gone.
  void discard_on_failure();
  ~OutputDir();
  OutputDir(const OutputDir&) = delete;
  OutputDir& operator=(const OutputDir&) = delete;

  const std::filesystem::path& staging() const { return staging_; }
  const std::filesystem::path& destination() const { return destination_; }
  // Throws std::runtime_error if the destination appeared without `replace` (it is left as it
  // was; the staging folder is removed by the destructor).
  void commit();

  // Removes the staging folder, and the parents the constructor created unless committed.
  void remove_staging_and_parents() noexcept;
  // On stderr, when the staging folder is kept for a later run: where, how big, how to continue.
  void say_what_is_kept() const noexcept;

 private:

  void prepare(const std::filesystem::path& destination, const char* staging_suffix);
  void open_resumable(const Resumable& resumable);
  void create_parents();

  std::filesystem::path destination_, staging_;
  std::vector<std::filesystem::path> missing_parents_, created_parents_;
  std::string continue_with_;
  bool replace_ = false, committed_ = false, resuming_ = false, keep_ = false;
  int lock_fd_ = -1;  // the resumable staging folder, locked
};

// On SIGINT, SIGTERM or SIGHUP: removes the staging folder and created parents of every
// OutputDir not yet committed (but those kept by keep_on_failure(), which it names on stderr with
// their size and the command that continues them), then ends the process by the same signal. Call at the start of
// main, before any other thread exists (it blocks these signals and waits for them in a thread
// of its own, so the cleanup runs as ordinary code, not in a signal handler).
void clean_up_outputs_on_signals();

// Throws std::invalid_argument, before anything is written, when the output folder `destination`
// is one of `inputs` (files or folders the command reads), contains one, or lies inside one: with
// --force the first two would delete the input when the output is swapped into place (a measured
// dataset lost), and the third would write into it. Paths are compared after resolving symbolic
// links and `..` (std::filesystem::weakly_canonical); inputs that do not exist are passed over.
void refuse_output_over_inputs(const std::filesystem::path& destination,
                               const std::vector<std::filesystem::path>& inputs);

// Renames `from` to `to` only if `to` does not exist, atomically (renameat2 RENAME_NOREPLACE).
// Returns 0 or the errno: EEXIST when `to` exists, EINVAL when the file system cannot do it.
int rename_no_replace(const std::filesystem::path& from, const std::filesystem::path& to) noexcept;
// Swaps two existing paths atomically (renameat2 RENAME_EXCHANGE). Returns 0 or the errno.
int rename_exchange(const std::filesystem::path& a, const std::filesystem::path& b) noexcept;

}  // namespace polrig
