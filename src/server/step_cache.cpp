#include "server/step_cache.h"

#include "core/system_memory.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <exception>
#include <vector>

namespace raypc::server {

StepCache::StepCache(Loader loader, size_t maxBytes, size_t maxEntries)
    : m_loader(std::move(loader)), m_maxBytes(maxBytes), m_maxEntries(std::max<size_t>(maxEntries, 1)),
      m_prefetchThread([this] { prefetchLoop(); })
{
}

StepCache::~StepCache()
{
    {
        std::lock_guard lock(m_mutex);
        m_stop = true;
    }
    m_prefetchCv.notify_all();
    m_prefetchThread.join();
}

size_t StepCache::defaultBytes()
{
    const uint64_t available = availableMemory().bytes;
    if (available == UINT64_MAX)
        return size_t(2) << 30;
    return size_t(std::max<uint64_t>(available / 2, uint64_t(512) << 20));
}

size_t StepCache::volumeBytes(const dataset::StepVolume& volume)
{
    const size_t floats = volume.grid().cellCount() * sizeof(float);
    const size_t decodeRoom =
        volume.encoding() == dataset::ValueEncoding::Uint16 ? floats - std::min(floats, volume.decodedBytes()) : 0;
    return volume.memoryBytes() + 3 * floats + decodeRoom;
}

std::shared_ptr<const dataset::StepVolume> StepCache::findLocked(int step, int level)
{
    for (auto it = m_lru.begin(); it != m_lru.end(); ++it)
        if (it->step == step && it->level == level) {
            // A file cut short since it was mapped (outside interference): reading it would raise
            // SIGBUS, so the entry goes and the caller loads the step again, which names the file.
            if (it->volume->filesCutShort()) {
                spdlog::warn("step {} level {}: a file of the step was cut short while cached; loading it again",
                             step, level);
                m_bytes -= it->bytes;
                m_lru.erase(it);
                return nullptr;
            }
            m_lru.splice(m_lru.begin(), m_lru, it);
            // A u16 volume grows as renderers decode its variables: counted now.
            Entry& e = m_lru.front();
            const size_t bytes = volumeBytes(*e.volume);
            m_bytes += bytes - e.bytes;
            e.bytes = bytes;
            evictLocked();
            return e.volume;
        }
    return nullptr;
}

void StepCache::evictLocked()
{
    while (m_lru.size() > 1 && (m_bytes > m_maxBytes || m_lru.size() > m_maxEntries)) {
        m_bytes -= m_lru.back().bytes;
        m_lru.pop_back();
    }
}

void StepCache::insert(int step, int level, std::shared_ptr<const dataset::StepVolume> volume)
{
    std::lock_guard lock(m_mutex);
    if (findLocked(step, level))
        return;  // another thread loaded it meanwhile
    const size_t bytes = volumeBytes(*volume);
    m_lru.push_front({step, level, std::move(volume), bytes});
    m_bytes += bytes;
    // Evict from the back, but always keep the entry just inserted.
    evictLocked();
    // The shading gradients of the steps no one renders (only the cache holds them: no renderer keeps
    // pointers into them) go, their blocks given back for the new step's gradient (core/spare_blocks.h).
    // A fresh block is zeroed by the kernel page by page as the gradient is first written: 40-90 ms
    // of a step change at full resolution (156 MB), while the bound keeps dozens of steps. A step shown
    // again computes its gradient again (15-50 ms).
    for (auto it = std::next(m_lru.begin()); it != m_lru.end(); ++it)
        if (it->volume.use_count() == 1)
            it->volume->dropGradients();
}

std::shared_ptr<const dataset::StepVolume> StepCache::get(int step, int level)
{
    {
        std::lock_guard lock(m_mutex);
        if (auto v = findLocked(step, level))
            return v;
        ++m_loads;
    }
    // Load outside the lock: mapping a step must not stall other sessions' cache hits.
    auto volume = m_loader(step, level);
    insert(step, level, volume);
    return volume;
}

std::shared_ptr<const dataset::StepVolume> StepCache::getWithoutEvicting(int step, int level)
{
    {
        std::lock_guard lock(m_mutex);
        for (const auto& e : m_lru)
            if (e.step == step && e.level == level && !e.volume->filesCutShort())
                return e.volume;
        ++m_loads;
    }
    auto volume = m_loader(step, level);
    const size_t bytes = volumeBytes(*volume);
    std::lock_guard lock(m_mutex);
    const bool present = std::any_of(m_lru.begin(), m_lru.end(), [&](const Entry& e) { return e.step == step && e.level == level; });
    if (!present && m_bytes + bytes <= m_maxBytes && m_lru.size() < m_maxEntries) {
        m_lru.push_back({step, level, volume, bytes});  // least recently used: first to go later
        m_bytes += bytes;
    }
    return volume;
}

void StepCache::prefetch(int step, int level)
{
    {
        std::lock_guard lock(m_mutex);
        for (const auto& e : m_lru)
            if (e.step == step && e.level == level)
                return;
        m_prefetchRequest = {step, level};
    }
    m_prefetchCv.notify_all();
}

void StepCache::waitForPrefetch()
{
    std::unique_lock lock(m_mutex);
    m_idleCv.wait(lock, [&] { return !m_prefetchRequest && !m_prefetchBusy; });
}

bool StepCache::contains(int step, int level) const
{
    std::lock_guard lock(m_mutex);
    for (const auto& e : m_lru)
        if (e.step == step && e.level == level)
            return true;
    return false;
}

size_t StepCache::bytes() const
{
    std::lock_guard lock(m_mutex);
    return m_bytes;
}

size_t StepCache::entries() const
{
    std::lock_guard lock(m_mutex);
    return m_lru.size();
}

uint64_t StepCache::loads() const
{
    std::lock_guard lock(m_mutex);
    return m_loads;
}

void StepCache::prefetchLoop()
{
    std::unique_lock lock(m_mutex);
    for (;;) {
        m_prefetchCv.wait(lock, [&] { return m_stop || m_prefetchRequest; });
        if (m_stop)
            return;
        const auto [step, level] = *m_prefetchRequest;
        m_prefetchRequest.reset();
        m_prefetchBusy = true;
        const bool cached = findLocked(step, level) != nullptr;
        if (!cached)
            ++m_loads;
        lock.unlock();
        if (!cached) {
            try {
                auto volume = m_loader(step, level);
                // Read the mapped data now, not during the next pass, and decode (u16) or check
                // (float32) what the session shows: the variables the most recently used volume of
                // this level has ready.
                volume->touchPages();
                std::vector<size_t> shown;
                {
                    std::lock_guard relock(m_mutex);
                    for (const auto& e : m_lru)
                        if (e.level == level && e.volume->variableCount() == volume->variableCount()) {
                            for (size_t v = 0; v < e.volume->variableCount(); ++v)
                                if (e.volume->valuesReady(v))
                                    shown.push_back(v);
                            break;
                        }
                }
                for (size_t v : shown)
                    volume->values(v);
                insert(step, level, std::move(volume));
            } catch (const std::exception& e) {
                // A worker thread logs and reports: the session that asks for this step gets the error itself.
                spdlog::warn("prefetch of step {} level {}: {}", step, level, e.what());
            }
        }
        lock.lock();
        m_prefetchBusy = false;
        m_idleCv.notify_all();
    }
}

}  // namespace raypc::server
