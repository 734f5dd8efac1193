// How long OpenMP's idle threads spin before they sleep, chosen for the command before libgomp starts.
//
// libgomp's threads spin for 300,000 turns at the end of each parallel region before they sleep.
// On an idle machine that saves a wake-up; on a machine whose cores are busy with other programs
// (a robot's computer always is) a spinning thread takes the core the thread still working needs,
// and a frame of many small regions takes 2-4 times as long (docs/BENCHMARK.md, "Under load").
// A short spin keeps nearly all of the idle speed and loses little under load.
//
// libgomp reads GOMP_SPINCOUNT once, in its own constructor, before main, from the environment the
// process started with: a program cannot change it after the fact (setenv before libc's own
// constructor is undone by it). So when the user has set neither GOMP_SPINCOUNT nor
// OMP_WAIT_POLICY, the command starts itself once more, at once, with GOMP_SPINCOUNT added: the
// same process (exec keeps the pid), the same arguments, a few milliseconds. This runs from the
// executable's .preinit_array, before any shared library's constructor, so nothing has started yet.
// Should the exec fail (no /proc), the command simply goes on with libgomp's default.
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

void choose_openmp_spin(int /*argc*/, char** argv, char** envp) {
  if (argv == nullptr || has_variable(envp, "GOMP_SPINCOUNT") || has_variable(envp, "OMP_WAIT_POLICY")) return;
  static char variable[64] = "GOMP_SPINCOUNT=";
  std::strncat(variable, viewpose::kSpinCountUnderLoad, sizeof variable - std::strlen(variable) - 1);
  std::size_t count = 0;
  while (envp != nullptr && envp[count] != nullptr) ++count;
  // malloc, not new: the C++ runtime has not started; the exec frees it, and a failed exec leaks one array.
  auto** with = static_cast<char**>(std::malloc((count + 2) * sizeof(char*)));
  if (with == nullptr) return;
  for (std::size_t i = 0; i < count; ++i) with[i] = envp[i];
  with[count] = variable;
  with[count + 1] = nullptr;
  ::execve("/proc/self/exe", argv, with);
  std::free(with);  // the exec failed: go on as we are
}

}  // namespace

// The array's element type is fixed by the ELF ABI: void(int, char**, char**).
__attribute__((section(".preinit_array"), used)) void (*const viewpose_choose_openmp_spin)(int, char**, char**) = &choose_openmp_spin;
