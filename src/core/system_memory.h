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

// For a long-running process that allocates and frees buffers of tens of MB again and again (the
// server: a frame buffer, its picture and depth map per state and pass): glibc then keeps blocks up
// to 256 MB in its heap and reuses them, instead of mapping fresh pages for each (every page a
// fault and a zeroing by the kernel) and unmapping them when freed; freed memory beyond 256 MB at
// the heap's top is still returned (what it saves a 1920x1080 still: docs/reliability.md). Never
// throws.
void keepLargeBlocksForReuse();
// As keepLargeBlocksForReuse, for blocks that threads other than the main one allocate and free:
// every thread started from now on allocates from the main heap (one glibc arena), since a
// thread's own arena grows in heaps of at most 64 MB and maps a larger block afresh each time.
// For `raypc serve FILES`, whose background run of the series makes step-sized arrays on a thread
// of its own. Never throws.
void keepLargeBlocksForReuseOnEveryThread();

// Runs this program again, in place (the same process and arguments; the environment gains one
// tunable), with glibc's malloc told to ask for transparent huge pages
// (GLIBC_TUNABLES=glibc.malloc.hugetlb=1), when the kernel gives them only on request
// (/sys/kernel/mm/transparent_hugepage/enabled is "madvise", as on Debian). RayPC's arrays are tens
// to hundreds of MB (a variable of a full-resolution step is 52 MB) and mostly written once after
// allocation; on 4 KB pages every page costs a fault and a zeroing, which took about half the time
// of preprocessing a full-resolution step (docs/format.md). The user's other tunables are kept
// after it. Does nothing when the user set the tunable (their choice stands), when
// RAYPC_HUGE_PAGES=0 (for A/B runs), or when the kernel uses huge pages always or never. Call it
// first thing in main; returns only if nothing was done or the exec failed. Never throws.
void restartWithTransparentHugePages(char** argv);

// A size of memory as a user writes it: a number (decimals allowed) with an optional unit K, M, G or
// T, each 1024 times the one before, optionally followed by "iB" or "B" ("512M", "1.5GiB", "8G",
// "3000000" bytes). Throws raypc::Error naming `option` ("--step-cache: '12Q' is not a size ...")
// for anything else, for zero, and for a size of 2^63 bytes or more.
uint64_t parseMemorySize(const std::string& text, const std::string& option);

// "1.5 GB", "830 MB": bytes for messages (decimal units).
std::string formatBytes(uint64_t bytes);

}  // namespace raypc
