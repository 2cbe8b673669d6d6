// Memory for RayPC's big arrays on transparent huge pages, asked for by the library itself, so that
// every program linking it (the raypc CLI, the server, the Python module inside python3) gets them.
//
// Why: a variable of a step is megabytes to hundreds of MB (52 MB at full resolution), mostly
// written once after allocation. On 4 KB pages every page costs a fault and a zeroing by the
// kernel and a TLB entry; on 2 MiB pages one fault covers 512 of them. Where the kernel gives huge
// pages only on request (/sys/kernel/mm/transparent_hugepage/enabled is "madvise", Debian's
// default), nothing gets them unless it asks with madvise(MADV_HUGEPAGE): `raypc features` over the
// demo spends 0.20 s in the kernel with them (36 000 page faults) and 0.41 s without (140 000;
// bench/python_features.sh). The raypc CLI also runs itself again with glibc's malloc asking for
// every block it maps (restartWithTransparentHugePages, core/system_memory.h), which still covers
// what does not come from here (preprocessing's snapshots and levels); a library loaded into
// python3 cannot do that, so the arrays of the analyses ask for themselves.
//
// RAYPC_HUGE_PAGES=0 in the environment (read at each large allocation) turns the asking off, for
// A/B runs: the arrays are then plain malloc'd memory (hugePagesEnabled).
#pragma once

#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

namespace raypc {

// The size of a transparent huge page on x86-64 and arm64 with 4 KB base pages.
inline constexpr size_t kHugePageBytes = size_t(2) << 20;

// Asks the kernel to back the 2 MiB-aligned interior of [p, p + bytes) with transparent huge pages
// (madvise MADV_HUGEPAGE); the partial huge pages at either end are left as they are, since the
// kernel can only map a whole aligned 2 MiB with one. Does nothing for a range without such an
// interior, or when RAYPC_HUGE_PAGES=0. Only advice: a kernel without THP, or one refusing it,
// changes nothing but speed. Thread-safe; never throws.
void adviseHugePages(void* p, size_t bytes) noexcept;

// Whether adviseHugePages asks: RAYPC_HUGE_PAGES is not "0", and glibc's malloc does not ask for
// every block already (GLIBC_TUNABLES holds no glibc.malloc.hugetlb other than 0, as in a raypc CLI
// that ran itself again with it). Thread-safe unless another thread changes the environment
// meanwhile (as getenv).
bool hugePagesEnabled() noexcept;

// `bytes` of uninitialised memory, released with std::free. From `kHugePageBytes` up it starts on a
// 2 MiB boundary and is advised (adviseHugePages), so that all of it but the last partial 2 MiB
// lies on huge pages; smaller blocks are plain malloc'd. The alignment costs address space only
// (less than 2 MiB a block, never touched). Throws std::bad_alloc when there is no memory.
void* allocateHugePageBacked(size_t bytes);

// A std::vector allocator for arrays of at least 2 MiB (StepFeatures::labels, the selection mask):
// allocateHugePageBacked. Stateless: every instance is equal to every other.
template <class T>
struct HugePageAllocator {
    using value_type = T;
    HugePageAllocator() = default;
    template <class U>
    HugePageAllocator(const HugePageAllocator<U>&) noexcept {}
    T* allocate(size_t n)
    {
        if (n > size_t(-1) / sizeof(T))
            throw std::bad_array_new_length();
        static_assert(alignof(T) <= alignof(std::max_align_t), "malloc's alignment is the small blocks' alignment");
        return static_cast<T*>(allocateHugePageBacked(n * sizeof(T)));
    }
    void deallocate(T* p, size_t) noexcept { std::free(p); }
    template <class U>
    bool operator==(const HugePageAllocator<U>&) const noexcept { return true; }
};

template <class T>
using HugePageVector = std::vector<T, HugePageAllocator<T>>;


}  // namespace raypc
