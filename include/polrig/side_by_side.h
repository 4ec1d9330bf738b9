#pragma once
// Pieces of work side by side, their results collected in order: a dataset's stops, each stop's
// frames made, compressed and written on one thread (its data stay in that core's caches) while
// other threads do other stops, and each stop's CSV row and preview gathered in stop order.
// work(i) runs for every i in [0, count) on any thread, several at once; collect(result) runs
// for i = 0, 1, … in order, one at a time. At most `tokens` pieces are in flight (by default
// usable_threads() + 1), so memory is bounded by them, not by the dataset; piece i starts only
// once piece i − tokens has been collected; both run in the caller's TBB arena, so nothing
// runs beside the threads polrig may use (--threads). An exception from work(i) is thrown when
// collecting reaches i (the first failing piece in order, whichever thread met it); one from
// collect is thrown at once. Either stops the pipeline.
#include <cstddef>
#include <exception>
#include <optional>
#include <vector>

#include <tbb/parallel_pipeline.h>

#include "polrig/threads.h"

namespace polrig {

template <class Work, class Collect>
void side_by_side_in_order(std::size_t count, Work&& work, Collect&& collect,
                           std::size_t tokens = static_cast<std::size_t>(usable_threads() + 1)) {
  using Result = decltype(work(std::size_t{0}));
  struct Done {
    std::optional<Result> result;
    std::exception_ptr error;
  };
  // Piece i lives in slot i mod tokens: TBB lets piece i in only once piece i − tokens has left the
  // last stage. Only indices pass between the stages, so a pipeline stopped by an exception
  // leaves nothing behind (TBB does not destroy the objects in flight when it cancels).
  std::vector<Done> slots(tokens);
  std::size_t next = 0;
  tbb::parallel_pipeline(
      tokens,
      tbb::make_filter<void, std::size_t>(tbb::filter_mode::serial_in_order,
                                          [&](tbb::flow_control& fc) -> std::size_t {
                                            if (next == count) fc.stop();
                                            return next++;
                                          }) &
          tbb::make_filter<std::size_t, std::size_t>(tbb::filter_mode::parallel,
                                                     [&](std::size_t i) {
                                                       Done& d = slots[i % tokens];
                                                       try {
                                                         d.result.emplace(work(i));
                                                       } catch (...) {
                                                         d.error = std::current_exception();
                                                       }
                                                       return i;
                                                     }) &
          tbb::make_filter<std::size_t, void>(tbb::filter_mode::serial_in_order, [&](std::size_t i) {
            Done& d = slots[i % tokens];
            if (d.error) std::rethrow_exception(d.error);
            collect(std::move(*d.result));
            d.result.reset();
          }));
}

}  // namespace polrig
