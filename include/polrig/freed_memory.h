#pragma once
// How this process's allocator keeps the memory it frees. glibc's malloc gives a buffer above its
// mmap threshold its own mapping and unmaps it when freed, and gives a thread heap's free top back
// to the system: a command that makes or reads one stop's images after another then has the
// kernel map and zero every page of them again (locate on 120 W16 stops: 0.74 M page faults, 1.9
// of its 11.3 CPU-seconds in the kernel). keep_freed_memory() raises the threshold to glibc's
// ceiling (32 MiB) and trims only past 1 GiB of free top: freed buffers are reused, and the process
// keeps what it held at its peak (each thread's arena its own peak, ≤ 64 MiB a heap). A
// process-wide setting: the CLI calls it first thing; a Python script may
// (polrig.keep_freed_memory()). Nothing without glibc.

namespace polrig {

void keep_freed_memory();

}  // namespace polrig
