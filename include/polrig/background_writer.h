#pragma once
// Writing beside computing: one write at a time on its own thread while the caller computes the
// next piece (a sweep's blocks, in one process and on an MPI job's rank 0: a write that waits for
// the disk then idles no core; the datasets' stops go side by side instead, side_by_side.h).
// submit() waits for the previous write, throwing its error, then starts this one: writes happen
// in submission order, never two at once, and at most one is pending, so memory is bounded by one
// write's data beside what is being computed. finish() waits for the last.
// Destroyed with a write pending (the computation threw), it waits for it and drops its error:
// the computation's error is the one said, and the output folder is discarded anyway.
#include <functional>
#include <future>

namespace polrig {

class BackgroundWriter {
 public:
  BackgroundWriter() = default;
  BackgroundWriter(const BackgroundWriter&) = delete;
  BackgroundWriter& operator=(const BackgroundWriter&) = delete;
  ~BackgroundWriter();

  void submit(std::function<void()> write);
  void finish();

 private:
  std::future<void> pending_;
};

}  // namespace polrig
