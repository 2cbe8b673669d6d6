// How much memory this process can still take, for checks before large allocations.
#pragma once

#include <cstdint>
#include <string>

namespace raypc {

struct AvailableMemory {
    uint64_t bytes = 0;
    std::string limitedBy;  // what sets the figure: "MemAvailable", "cgroup memory.max" or "ulimit -v"
};

// The smallest of: the kernel's estimate of memory available without swapping (MemAvailable in
// /proc/meminfo), what the process's cgroup (v2) may still use (memory.max - memory.current),
// and the address space left under RLIMIT_AS (ulimit -v). Limits that are absent or unreadable
// are ignored; if none is readable, `bytes` is UINT64_MAX. Never throws.
AvailableMemory availableMemory();

// "1.5 GB", "830 MB": bytes for messages (decimal units).
std::string formatBytes(uint64_t bytes);

}  // namespace raypc
