#pragma once
// Pieces made in order and written side by side: a dataset's stops, each stop's image compressed
// and written on whichever thread is free while the next stops are made. make(i) runs for
// i = 0, 1, … in order, one at a time (its own work may run in parallel inside); write(piece)
// runs on any thread, several at once, in no set order (each piece is its own file). At most
// usable_threads() + 1 pieces exist at a time (one being made, one written per thread): memory
// is bounded by them, not by the dataset.
// Both run in the caller's TBB arena, so nothing runs beside the threads polrig may use
// (--threads). An exception from either stops the pipeline and is rethrown.
#include <cstddef>
#include <memory>

#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

namespace polrig {

// The threads polrig may use: the arena's concurrency within --threads (tbb::global_control, which
// limits the workers but not what the arena says).
int usable_threads();

template <class Make, class Write>
void make_in_order_write_beside(std::size_t count, Make&& make, Write&& write) {
  using Piece = decltype(make(std::size_t{0}));
  std::size_t next = 0;
  tbb::parallel_pipeline(
      static_cast<std::size_t>(usable_threads() + 1),
      tbb::make_filter<void, std::shared_ptr<Piece>>(tbb::filter_mode::serial_in_order,
                                                     [&](tbb::flow_control& fc) -> std::shared_ptr<Piece> {
                                                       if (next == count) {
                                                         fc.stop();
                                                         return nullptr;
                                                       }
                                                       // Isolated: while make's own parallel work
                                                       // waits, its thread takes none of the writes,
                                                       // which would hold up the next piece.
                                                       return tbb::this_task_arena::isolate(
                                                           [&] { return std::make_shared<Piece>(make(next++)); });
                                                     }) &
          tbb::make_filter<std::shared_ptr<Piece>, void>(tbb::filter_mode::parallel,
                                                         [&](const std::shared_ptr<Piece>& p) { write(*p); }));
}

}  // namespace polrig
