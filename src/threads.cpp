#include "polrig/threads.h"

#include <algorithm>
#include <cstddef>

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

namespace polrig {

int usable_threads() {
  return static_cast<int>(std::min<std::size_t>(
      static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()),
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism)));
}

}  // namespace polrig
