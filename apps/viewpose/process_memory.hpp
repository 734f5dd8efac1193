#pragma once
#include <string>

namespace viewpose::cli {

/// Keeps memory the command frees for its own reuse instead of handing it back to the system at
/// once (glibc's malloc), unless the user has tuned malloc through its environment variables.
void keep_freed_memory();

/// glibc's tunables as the command runs with them (start_environment.cpp adds glibc.malloc.hugetlb=1
/// unless the user set GLIBC_TUNABLES), for benchmarks to report.
std::string malloc_tunables();

}  // namespace viewpose::cli
