#pragma once
// Progress of a long computation: its stage, the fraction done and an estimate of the time left.
// Library parts report through a Progress handle and never print; the command line decides
// where (and whether) the reports go. A default-constructed Progress reports nothing and costs
// one branch per call. Reports never feed back into results.
#include <functional>
#include <memory>
#include <string>

namespace polrig {

struct ProgressReport {
  std::string stage;
  double fraction = 0;   // of the stage, in [0, 1]
  double elapsed_s = 0;  // since the stage began
  double eta_s = -1;     // seconds left at the rate so far; < 0 while unknown
};

// "1:05", "12:03", "1:02:03": a whole number of seconds as [h:]mm:ss (m:ss under an hour).
std::string format_duration(double seconds);
// "study cs: poses  42 %  ETA 0:13" ("ETA ?" while unknown, no ETA when done).
std::string format_progress(const ProgressReport& r);

using ProgressSink = std::function<void(const ProgressReport&)>;

// One stage's cost, for a stage log: the wall time from begin() to finish() (or to the next
// begin()), and the process's CPU time over it (every thread's). bench/serial_fraction.py reads
// them (through the CLI's POLRIG_STAGE_TIMES) to find the serial parts of a command.
struct StageTime {
  std::string stage;
  double wall_s = 0, cpu_s = 0;
};
using StageLog = std::function<void(const StageTime&)>;

// A shared handle (copies report to the same sink). advance() may be called from any thread;
// begin() and finish() from the thread that runs the stage. The first report comes `interval_s`
// after begin(), then at most one per `interval_s`, and a last one at finish(); a stage that
// ends sooner is not reported at all, so quick commands stay quiet.
class Progress {
 public:
  Progress() = default;
  explicit Progress(ProgressSink sink, double interval_s = 0.2);
  // Also every stage's time to `log` (called by finish(), or by the next begin()). sink may be
  // empty: a stage log alone.
  Progress(ProgressSink sink, double interval_s, StageLog log);

  explicit operator bool() const { return state_ != nullptr; }
  void begin(std::string stage, long long total) const;
  void advance(long long units = 1) const;
  void finish() const;

  struct State;

 private:
  std::shared_ptr<State> state_;
};

}  // namespace polrig
