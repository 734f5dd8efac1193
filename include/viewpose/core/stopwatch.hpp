#pragma once
// Stage timings: milliseconds since a steady-clock instant.
#include <chrono>

namespace viewpose {

using Clock = std::chrono::steady_clock;

inline double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace viewpose
