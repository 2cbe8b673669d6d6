// A bounded cache of loaded StepVolumes shared by all sessions, with background prefetch.
//
// Bounded by bytes and by entries (least recently used first out), so memory does not grow with
// the number of steps played. Volumes still used by a renderer stay alive through their shared_ptr
// after eviction; the cache only stops holding them. Prefetch loads a (step, level) on a background
// thread, touches its pages and decodes the u16 variables that the most recently used volume of that
// level has decoded, so that the next step of a playback is in memory and decoded when asked for;
// only the newest prefetch request waits, older ones are dropped.
//
// Thread safety: every member function may be called from any thread.
#pragma once

#include "dataset/dataset.h"

#include <condition_variable>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

namespace raypc::server {

class StepCache {
public:
    using Loader = std::function<std::shared_ptr<const dataset::StepVolume>(int step, int level)>;

    // `loader` throws raypc::Error for a step or level it cannot load; get() passes that on.
    StepCache(Loader loader, size_t maxBytes, size_t maxEntries);
    ~StepCache();  // stops and joins the prefetch thread
    StepCache(const StepCache&) = delete;
    StepCache& operator=(const StepCache&) = delete;

    // A cached volume one of whose files was cut short since it was mapped (StepVolume::filesCutShort)
    // is dropped and loaded again, so the loader's error names the file instead of a read raising SIGBUS.
    std::shared_ptr<const dataset::StepVolume> get(int step, int level);
    // For scans over many steps (statistics): a cached volume without changing the order of use, or
    // a fresh load that is kept only when it fits without evicting anything, so that a scan never
    // pushes the renderers' working set out.
    std::shared_ptr<const dataset::StepVolume> getWithoutEvicting(int step, int level);
    // Queues a background load; replaces an earlier request that has not started.
    void prefetch(int step, int level);
    // Waits until no prefetch is queued or running (tests).
    void waitForPrefetch();

    bool contains(int step, int level) const;
    size_t bytes() const;
    size_t entries() const;
    uint64_t loads() const;  // loader calls so far (misses and prefetches)

    // Bytes a volume occupies: its values and brick bounds (StepVolume::memoryBytes: mapped, built or
    // decoded), room for the shading gradient of one variable (3 floats a grid point,
    // StepVolume::nodeGradient), which it keeps once shown lit, and for a u16 volume room for at
    // least one decoded variable (the one a renderer colours by). Variables decoded after the volume
    // entered the cache are counted when it is next asked for.
    static size_t volumeBytes(const dataset::StepVolume& volume);

    // The bound a server's cache takes unless told (`raypc serve --step-cache`): half of the memory
    // the process may take now (availableMemory: MemAvailable, the cgroup's limit, ulimit -v), at
    // least 512 MiB; 2 GiB when none of those can be read. Never throws.
    static size_t defaultBytes();

private:
    struct Entry {
        int step, level;
        std::shared_ptr<const dataset::StepVolume> volume;
        size_t bytes;
    };
    std::shared_ptr<const dataset::StepVolume> findLocked(int step, int level);
    // Evicts from the back until within bounds, always keeping the front entry.
    void evictLocked();
    void insert(int step, int level, std::shared_ptr<const dataset::StepVolume> volume);
    void prefetchLoop();

    Loader m_loader;
    size_t m_maxBytes, m_maxEntries;
    mutable std::mutex m_mutex;
    std::list<Entry> m_lru;  // most recently used first
    size_t m_bytes = 0;
    uint64_t m_loads = 0;

    std::condition_variable m_prefetchCv, m_idleCv;
    std::optional<std::pair<int, int>> m_prefetchRequest;
    bool m_prefetchBusy = false, m_stop = false;
    std::thread m_prefetchThread;
};

}  // namespace raypc::server
