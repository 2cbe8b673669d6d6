#include "core/huge_pages.h"

#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>
#include <string_view>

namespace raypc {

bool hugePagesEnabled() noexcept
{
    // Read at each call (a lookup among a few dozen strings, beside a call that maps megabytes), so
    // that Python's os.environ["RAYPC_HUGE_PAGES"] = "0" after import still counts.
    const char* value = std::getenv("RAYPC_HUGE_PAGES");
    if (value && std::string_view(value) == "0")
        return false;
    // When glibc's malloc asks for every block it maps already (the raypc CLI runs itself with
    // glibc.malloc.hugetlb=1, core/system_memory.h), asking again only adds aligned blocks and split
    // mappings: with both, `raypc features` over the demo took 0.58 s against 0.46 s with the
    // tunable alone (medians of 9 interleaved runs, bench/python_features.sh).
    const char* tunables = std::getenv("GLIBC_TUNABLES");
    if (!tunables)
        return true;
    const std::string_view t(tunables);
    const size_t at = t.find("glibc.malloc.hugetlb=");
    return at == std::string_view::npos || t.substr(at + 21, 1) == "0";
}

void adviseHugePages(void* p, size_t bytes) noexcept
{
    if (!p || !hugePagesEnabled())
        return;
    const uintptr_t begin = reinterpret_cast<uintptr_t>(p);
    if (bytes > UINTPTR_MAX - begin)
        return;
    const uintptr_t first = (begin + kHugePageBytes - 1) & ~uintptr_t(kHugePageBytes - 1);
    const uintptr_t last = (begin + bytes) & ~uintptr_t(kHugePageBytes - 1);
    if (first >= last)
        return;
    // Failure (EINVAL from a kernel built without THP) leaves 4 KB pages: nothing to report.
    madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
}

void* allocateHugePageBacked(size_t bytes)
{
    void* p = nullptr;
    if (bytes < kHugePageBytes || !hugePagesEnabled()) {
        p = std::malloc(bytes ? bytes : 1);
        if (!p)
            throw std::bad_alloc();
        return p;
    }
    // Aligned, so that every whole 2 MiB of the block is one huge page; the partial one at its end
    // stays on 4 KB pages. Rounding blocks up to whole huge pages instead took twice the kernel's
    // time of `raypc features` over the demo (0.47 s against 0.20 s: more memory to zero, on
    // arrays of 2.7 MB), for 27 000 fewer faults.
    if (posix_memalign(&p, kHugePageBytes, bytes) != 0)
        throw std::bad_alloc();
    adviseHugePages(p, bytes);
    return p;
}

}  // namespace raypc
