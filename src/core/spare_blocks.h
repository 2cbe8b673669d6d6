// Blocks of memory made ready off the critical path, for the arrays a new time step needs at once
// (a decoded variable, its shading gradient: 52 and 156 MB at full resolution).
//
// Why: a fresh block costs page faults and zeroing by the kernel when it is first written, and
// on huge pages (allocateHugePageBacked) direct compaction too when free huge pages are scarce
// (/sys/kernel/mm/transparent_hugepage/defrag "madvise", Debian's default): on the 2-core test
// machine after hours of uptime the 156 MB gradient of a new step took 160–220 ms to compute, 43–49
// ms on 4 KB pages and 16–22 ms on memory faulted in before (docs/scaling.md, "Playback from
// memory"). So a block
// taken here comes, when one of its size is spare, already faulted in; after each take a
// background thread at the lowest priority makes a new spare of that size (allocates it and
// writes one byte per page), and a block given back is kept as the spare of its size instead of
// being freed. At most one spare per size, and kMaxSpareBytes in all, are kept. A spare is on huge
// pages (its compaction happened in the background); a block taken when no spare is ready is mapped
// on 4 KB pages, whose faults never wait for compaction.
//
// Spares are made only in a process that asks for them (keepSpareBlocks: the server, which changes
// steps while a user waits); elsewhere (a CLI command, the Python module) a block is mapped fresh
// and advised onto huge pages as allocateHugePageBacked's are, and unmapped when given back, unless
// the process asks for blocks given back to be kept for the next takes of their size
// (reuseGivenBackBlocks: raypc preprocess, whose pathlines decode the same arrays step after step;
// no background thread, no spare made ahead: only the kernel's faults and zeroing are saved).
//
// Thread safety: every function may be called from any thread.
#pragma once

#include <cstddef>
#include <memory>
#include <new>
#include <type_traits>

namespace raypc {

// The spares kept in all (blocks over this are never kept).
inline constexpr size_t kMaxSpareBytes = size_t(512) << 20;
// Blocks smaller than this are plain allocateHugePageBacked: faulting them in is cheap.
inline constexpr size_t kMinSpareBytes = size_t(4) << 20;

// Turns making and keeping spares on (the server, at start) or off (then the spares kept are freed).
void keepSpareBlocks(bool on);

// While no spares are made (keepSpareBlocks(false)): blocks given back are kept, any number of each
// size up to `maxBytes` in all, and handed out again by takeBlock of their exact size instead of
// fresh ones. 0 (the default) keeps none and frees those kept; a smaller bound frees what exceeds it.
void reuseGivenBackBlocks(size_t maxBytes);

// `bytes` of uninitialised memory starting on a 2 MiB boundary, from the spares when one of exactly
// this size is ready (below kMinSpareBytes: allocateHugePageBacked). Release it with giveBackBlock(p, bytes). Throws
// std::bad_alloc when there is no memory.
void* takeBlock(size_t bytes);
// Keeps `p` (from takeBlock with the same `bytes`) as the spare of its size when there is none and
// the spares stay within kMaxSpareBytes; frees it otherwise. Never throws.
void giveBackBlock(void* p, size_t bytes) noexcept;
// Waits until no spare is being made (tests). Returns the bytes of the spares and of the blocks
// kept for reuse now.
size_t waitForSpareBlocks();

struct SpareBlockFree {
    size_t bytes = 0;
    void operator()(void* p) const noexcept { giveBackBlock(p, bytes); }
};

// An array of n uninitialised T from takeBlock, given back when it goes: for arrays written whole
// right after (a decoded variable, a shading gradient).
template <class T>
using SpareArray = std::unique_ptr<T[], SpareBlockFree>;

template <class T>
SpareArray<T> makeSpareArray(size_t n)
{
    static_assert(std::is_trivially_default_constructible_v<T> && std::is_trivially_destructible_v<T>,
                  "the array is never constructed nor destroyed element by element");
    if (n > size_t(-1) / sizeof(T))
        throw std::bad_array_new_length();
    const size_t bytes = (n ? n : 1) * sizeof(T);
    return SpareArray<T>(static_cast<T*>(takeBlock(bytes)), SpareBlockFree{bytes});
}

}  // namespace raypc
