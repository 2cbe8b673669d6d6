// Elapsed wall time on the steady clock, the one clock RayPC times work with (log lines, pass
// statistics, progress, protocol timings).
#pragma once

#include <chrono>

namespace raypc {

using SteadyClock = std::chrono::steady_clock;

inline double secondsSince(SteadyClock::time_point start)
{
    return std::chrono::duration<double>(SteadyClock::now() - start).count();
}

inline double millisecondsSince(SteadyClock::time_point start)
{
    return std::chrono::duration<double, std::milli>(SteadyClock::now() - start).count();
}

}  // namespace raypc
