#include "polrig/progress.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <ctime>
#include <mutex>

#include <fmt/format.h>

namespace polrig {

std::string format_duration(double seconds) {
  const long long s = std::isfinite(seconds) && seconds > 0 ? std::llround(seconds) : 0;
  if (s >= 3600) return fmt::format("{}:{:02d}:{:02d}", s / 3600, (s / 60) % 60, s % 60);
  return fmt::format("{}:{:02d}", s / 60, s % 60);
}

std::string format_progress(const ProgressReport& r) {
  const double f = std::clamp(r.fraction, 0.0, 1.0);
  std::string line = fmt::format("{}  {:3.0f} %", r.stage, std::floor(100 * f));
  if (f >= 1) return line + fmt::format("  {}", format_duration(r.elapsed_s));
  return line + (r.eta_s < 0 ? std::string("  ETA ?") : "  ETA " + format_duration(r.eta_s));
}

using Clock = std::chrono::steady_clock;

namespace {
// The process's CPU time, every thread's (std::clock is CLOCK_PROCESS_CPUTIME_ID on Linux).
double process_cpu_s() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }
}  // namespace

struct Progress::State {
  ProgressSink sink;
  StageLog log;
  bool open = false;  // a stage begun and not yet logged
  double cpu_start = 0;
  double interval_s = 0.2;
  std::mutex report_mutex;  // one report at a time; advance() skips a report rather than wait
  std::string stage;
  long long total = 0;
  std::atomic<long long> done{0};
  Clock::time_point start, last;
  bool shown = false;  // a stage that ends before its first report stays silent

  void close_stage() {
    if (!open || !log) return;
    open = false;
    log({stage, std::chrono::duration<double>(Clock::now() - start).count(), process_cpu_s() - cpu_start});
  }

  void report(bool final) {
    if (!sink) return;
    // A stage's 100 % is said once, by finish().
    if (!final && done.load(std::memory_order_relaxed) >= total) return;
    const Clock::time_point now = Clock::now();
    if (final ? !shown : std::chrono::duration<double>(now - last).count() < interval_s) return;
    last = now;
    shown = true;
    ProgressReport r;
    r.stage = stage;
    const long long d = final ? total : std::min(done.load(std::memory_order_relaxed), total);
    r.fraction = total > 0 ? static_cast<double>(d) / static_cast<double>(total) : 1.0;
    r.elapsed_s = std::chrono::duration<double>(now - start).count();
    // Unknown until a little is done: an early rate says little.
    if (r.fraction >= 0.01 && r.elapsed_s >= 0.5) r.eta_s = r.elapsed_s * (1 - r.fraction) / r.fraction;
    sink(r);
  }
};

Progress::Progress(ProgressSink sink, double interval_s) : state_(std::make_shared<State>()) {
  state_->sink = std::move(sink);
  state_->interval_s = interval_s;
}

Progress::Progress(ProgressSink sink, double interval_s, StageLog log) : Progress(std::move(sink), interval_s) {
  state_->log = std::move(log);
}

void Progress::begin(std::string stage, long long total) const {
  if (!state_) return;
  const std::lock_guard lock(state_->report_mutex);
  state_->close_stage();
  state_->stage = std::move(stage);
  state_->total = total;
  state_->done.store(0);
  state_->start = state_->last = Clock::now();
  state_->shown = false;
  state_->open = true;
  state_->cpu_start = state_->log ? process_cpu_s() : 0.0;
}

void Progress::advance(long long units) const {
  if (!state_) return;
  state_->done.fetch_add(units, std::memory_order_relaxed);
  std::unique_lock lock(state_->report_mutex, std::try_to_lock);
  if (lock.owns_lock()) state_->report(false);
}

void Progress::finish() const {
  if (!state_) return;
  const std::lock_guard lock(state_->report_mutex);
  state_->report(true);
  state_->close_stage();
}

}  // namespace polrig
