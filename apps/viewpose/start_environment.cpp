// What the command needs in its environment before any library starts: how long OpenMP's idle
// threads spin, and memory in large pages.
//
// libgomp's threads spin for 300,000 turns at the end of each parallel region before they sleep.
// On an idle machine that saves a wake-up; on a machine whose cores are busy with other programs
// (a robot's computer always is) a spinning thread takes the core the thread still working needs,
// and a frame of many small regions takes 2-4 times as long (docs/BENCHMARK.md, "Under load").
// A short spin keeps nearly all of the idle speed and loses little under load: GOMP_SPINCOUNT=1000.
//
// Every page of memory a process touches first is a page fault, and on a virtual machine a fault
// costs microseconds: a run of one frame touches tens of megabytes (the database, the scene, the
// frame's clouds), and on this project's 2-core VM those faults were a third to a half of
// `viewpose recognize`'s process time. glibc's malloc can ask for transparent huge pages (2 MB, one
// fault where there were 512) for its heaps: GLIBC_TUNABLES=glibc.malloc.hugetlb=1, which with the
// heap grown 64 MB at a time (process_memory.cpp) halves the process time of one frame, for 3 MB more
// resident memory (docs/BENCHMARK.md, "Page faults", has the measurements).
// (Where the system does not offer huge pages, the setting does nothing.)
//
// libgomp and glibc read these once, before main, from the environment the process started with: a
// program cannot change them after the fact (setenv before libc's own constructor is undone by
// it). So when the user has set neither, the command starts itself once more, at once, with what is
// missing added: the same process (exec keeps the pid), the same arguments, a few milliseconds. A
// variable the user set (GOMP_SPINCOUNT or OMP_WAIT_POLICY; GLIBC_TUNABLES) is left as it is. This
// runs from the executable's .preinit_array, before any shared library's constructor, so nothing
// has started yet. Should the exec fail (no /proc), the command simply goes on as it is.
#include <unistd.h>

#include <cstdlib>
#include <cstring>

#include "viewpose/core/threads.hpp"

namespace {

bool has_variable(char** envp, const char* name) {
  const std::size_t n = std::strlen(name);
  for (char** e = envp; e != nullptr && *e != nullptr; ++e)
    if (std::strncmp(*e, name, n) == 0 && (*e)[n] == '=') return true;
  return false;
}

void choose_start_environment(int /*argc*/, char** argv, char** envp) {
  if (argv == nullptr) return;
  static char spin[64] = "GOMP_SPINCOUNT=";
  static char tunables[] = "GLIBC_TUNABLES=glibc.malloc.hugetlb=1";
  const bool add_spin = !has_variable(envp, "GOMP_SPINCOUNT") && !has_variable(envp, "OMP_WAIT_POLICY");
  const bool add_tunables = !has_variable(envp, "GLIBC_TUNABLES");
  if (!add_spin && !add_tunables) return;
  std::strncat(spin, viewpose::kSpinCountUnderLoad, sizeof spin - std::strlen(spin) - 1);
  std::size_t count = 0;
  while (envp != nullptr && envp[count] != nullptr) ++count;
  // malloc, not new: the C++ runtime has not started; the exec frees it, and a failed exec leaks one array.
  auto** with = static_cast<char**>(std::malloc((count + 3) * sizeof(char*)));
  if (with == nullptr) return;
  for (std::size_t i = 0; i < count; ++i) with[i] = envp[i];
  if (add_spin) with[count++] = spin;
  if (add_tunables) with[count++] = tunables;
  with[count] = nullptr;
  ::execve("/proc/self/exe", argv, with);
  std::free(with);  // the exec failed: go on as we are
}

}  // namespace

// The array's element type is fixed by the ELF ABI: void(int, char**, char**).
__attribute__((section(".preinit_array"), used)) void (*const viewpose_choose_start_environment)(int, char**, char**) = &choose_start_environment;
