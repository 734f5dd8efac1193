// How the command's memory is reused, chosen before any work.
//
// glibc's malloc serves each block of 128 kB or more with a mapping of its own and unmaps it when it
// is freed, returns the top of its heap to the system once 128 kB of it are free, and grows its heap
// 128 kB at a time. A run of one frame allocates and frees frames, clouds and file buffers of
// megabytes, one after another, so every one of them came as fresh pages, each a page fault when
// first written, which on a virtual machine costs microseconds (start_environment.cpp). Here freed
// blocks stay for reuse, and the heap grows 64 MB at a time, so that the large pages asked for
// there (GLIBC_TUNABLES=glibc.malloc.hugetlb=1) can back it (docs/BENCHMARK.md, "Page faults", has
// what that saves, measured). Blocks over 32 MB (grids of large scans, filled lazily, which rely on
// untouched pages costing nothing) are still mapped apart. A long run (`bench`, `live`) is unchanged per frame.
#include "process_memory.hpp"

#include <cstdlib>
#include <cstring>

#ifdef __GLIBC__
#include <malloc.h>
#endif

namespace viewpose::cli {

void keep_freed_memory() {
#ifdef __GLIBC__
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  const auto tuned = [&](const char* name) { return tunables != nullptr && std::strstr(tunables, name) != nullptr; };
  if (std::getenv("MALLOC_MMAP_THRESHOLD_") || std::getenv("MALLOC_TRIM_THRESHOLD_") || std::getenv("MALLOC_TOP_PAD_") ||
      tuned("glibc.malloc.mmap_threshold") || tuned("glibc.malloc.trim_threshold") || tuned("glibc.malloc.top_pad")) {
    return;  // the user's choice
  }
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
  mallopt(M_TOP_PAD, 64 << 20);
#endif
}

std::string malloc_tunables() {
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  return tunables ? tunables : "glibc's default";
}

}  // namespace viewpose::cli
