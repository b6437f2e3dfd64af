#pragma once
// A stage's wall time, on the steady clock: auto t0 = StageClock::now(); ...; SecondsSince(t0).
#include <chrono>

namespace satmesh {

using StageClock = std::chrono::steady_clock;

inline double SecondsSince(StageClock::time_point since) {
  return std::chrono::duration<double>(StageClock::now() - since).count();
}

}  // namespace satmesh
