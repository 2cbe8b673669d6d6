// Elapsed wall time on the steady clock, the one clock RayPC times work with (log lines, pass
// statistics, progress, protocol timings).
#pragma once

#include <chrono>

namespace raypc {

inline double secondsSince(std::chrono::steady_clock::time_point start)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

inline double millisecondsSince(std::chrono::steady_clock::time_point start)
{
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace raypc
