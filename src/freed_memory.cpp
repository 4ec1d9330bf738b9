#include "polrig/freed_memory.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace polrig {

void keep_freed_memory() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's ceiling on 64-bit (DEFAULT_MMAP_THRESHOLD_MAX)
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
}

}  // namespace polrig
