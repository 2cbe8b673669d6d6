#include "core/spare_blocks.h"

#include "core/huge_pages.h"

#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <deque>
#include <map>
#include <mutex>
#include <string_view>
#include <thread>

namespace raypc {
namespace {

// A block of `bytes` (at least kMinSpareBytes) mapped on its own, starting on a 2 MiB boundary. With
// `huge`, its interior is advised onto huge pages (unless RAYPC_HUGE_PAGES=0) — for a spare, which
// is faulted in off the critical path, where the kernel's compaction for huge pages costs nothing
// that waits; without, it stays on 4 KB pages: faulted in by whoever writes it first, never waiting
// for compaction (a fresh block a step needs now). Throws std::bad_alloc when there is no memory.
void* mapBlock(size_t bytes, bool huge)
{
    const size_t length = bytes + kHugePageBytes;
    void* m = mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (m == MAP_FAILED)
        throw std::bad_alloc();
    const uintptr_t begin = reinterpret_cast<uintptr_t>(m);
    const uintptr_t aligned = (begin + kHugePageBytes - 1) & ~uintptr_t(kHugePageBytes - 1);
    const size_t pageBytes = size_t(sysconf(_SC_PAGESIZE));
    const uintptr_t end = (aligned + bytes + pageBytes - 1) & ~uintptr_t(pageBytes - 1);
    if (aligned > begin)
        munmap(m, aligned - begin);
    if (begin + length > end)
        munmap(reinterpret_cast<void*>(end), begin + length - end);
    void* p = reinterpret_cast<void*>(aligned);
    const char* setting = std::getenv("RAYPC_HUGE_PAGES");
    if (huge && !(setting && std::string_view(setting) == "0")) {
        const size_t interior = bytes & ~(kHugePageBytes - 1);
        if (interior > 0)
            madvise(p, interior, MADV_HUGEPAGE);  // only advice: failure leaves 4 KB pages
    }
    return p;
}

void unmapBlock(void* p, size_t bytes) noexcept { munmap(p, bytes); }

// The spares and the thread that makes them. Never destroyed: the thread may still be making a
// spare when the process exits, and a static destructor joining it would make exit wait for that.
class Spares {
public:
    static Spares& instance()
    {
        static Spares* spares = new Spares;
        return *spares;
    }

    void* take(size_t bytes)
    {
        if (bytes < kMinSpareBytes)
            return allocateHugePageBacked(bytes);
        if (bytes > kMaxSpareBytes)
            return mapBlock(bytes, false);
        void* p = nullptr;
        {
            std::lock_guard lock(m_mutex);
            if (!m_keep) {
                if (const auto it = m_reusable.find(bytes); it != m_reusable.end()) {
                    p = it->second;
                    m_reusableBytes -= bytes;
                    m_reusable.erase(it);
                    return p;
                }
                return mapBlock(bytes, true);  // as allocateHugePageBacked would
            }
            if (const auto it = m_spares.find(bytes); it != m_spares.end()) {
                p = it->second;
                m_spareBytes -= bytes;
                m_spares.erase(it);
            }
            m_wanted.push_back(bytes);  // a spare of this size for the next take
            if (!m_thread.joinable())
                m_thread = std::thread([this] { loop(); });
        }
        m_cv.notify_one();
        return p ? p : mapBlock(bytes, false);
    }

    void giveBack(void* p, size_t bytes) noexcept
    {
        if (!p)
            return;
        if (bytes < kMinSpareBytes) {
            std::free(p);  // allocateHugePageBacked's
            return;
        }
        {
            std::lock_guard lock(m_mutex);
            if (m_keep && !m_spares.contains(bytes) && m_spareBytes + bytes <= kMaxSpareBytes) {
                m_spares.emplace(bytes, p);
                m_spareBytes += bytes;
                return;
            }
            if (!m_keep && m_reusableBytes + bytes <= m_reusableLimit) {
                m_reusable.emplace(bytes, p);
                m_reusableBytes += bytes;
                return;
            }
        }
        unmapBlock(p, bytes);
    }

    void reuse(size_t maxBytes)
    {
        std::multimap<size_t, void*> dropped;
        {
            std::lock_guard lock(m_mutex);
            m_reusableLimit = maxBytes;
            // The newest kept first (a multimap keeps equal sizes in the order given back).
            while (m_reusableBytes > m_reusableLimit) {
                const auto last = std::prev(m_reusable.end());
                m_reusableBytes -= last->first;
                dropped.insert(*last);
                m_reusable.erase(last);
            }
        }
        for (const auto& [bytes, p] : dropped)
            unmapBlock(p, bytes);
    }

    void keep(bool on)
    {
        std::map<size_t, void*> dropped;
        {
            std::lock_guard lock(m_mutex);
            m_keep = on;
            if (!on) {
                dropped.swap(m_spares);
                m_spareBytes = 0;
                m_wanted.clear();
            }
        }
        for (const auto& [bytes, p] : dropped)
            unmapBlock(p, bytes);
    }

    size_t waitIdle()
    {
        std::unique_lock lock(m_mutex);
        m_idleCv.wait(lock, [&] { return m_wanted.empty() && !m_busy; });
        return m_spareBytes + m_reusableBytes;
    }

private:
    void loop()
    {
        // The lowest priority: a spare is made while the cores have nothing better to do.
        setpriority(PRIO_PROCESS, pid_t(syscall(SYS_gettid)), 19);
        std::unique_lock lock(m_mutex);
        for (;;) {
            m_cv.wait(lock, [&] { return !m_wanted.empty(); });
            const size_t bytes = m_wanted.front();
            m_wanted.pop_front();
            if (!m_keep || m_spares.contains(bytes) || m_spareBytes + bytes > kMaxSpareBytes) {
                m_idleCv.notify_all();
                continue;
            }
            m_busy = true;
            lock.unlock();
            void* p = nullptr;
            try {
                p = mapBlock(bytes, true);
                // Fault every page in now (one byte a page), so that whoever takes it writes at once.
                auto* bytesOf = static_cast<volatile unsigned char*>(p);
                for (size_t i = 0; i < bytes; i += 4096)
                    bytesOf[i] = 0;
            } catch (const std::bad_alloc&) {
                p = nullptr;  // no memory for a spare: the next take allocates as it would without
            }
            lock.lock();
            m_busy = false;
            if (p && m_keep && !m_spares.contains(bytes) && m_spareBytes + bytes <= kMaxSpareBytes) {
                m_spares.emplace(bytes, p);
                m_spareBytes += bytes;
                p = nullptr;
            }
            if (p) {
                lock.unlock();
                unmapBlock(p, bytes);
                lock.lock();
            }
            m_idleCv.notify_all();
        }
    }

    std::mutex m_mutex;
    std::condition_variable m_cv, m_idleCv;
    std::map<size_t, void*> m_spares;  // by size: one each
    size_t m_spareBytes = 0;
    bool m_keep = false;
    std::deque<size_t> m_wanted;
    bool m_busy = false;
    // Blocks given back kept as they are while no spares are made (reuseGivenBackBlocks): any
    // number of each size, m_reusableLimit bytes in all.
    std::multimap<size_t, void*> m_reusable;
    size_t m_reusableBytes = 0, m_reusableLimit = 0;
    std::thread m_thread;
};

}  // namespace

void keepSpareBlocks(bool on) { Spares::instance().keep(on); }

void reuseGivenBackBlocks(size_t maxBytes) { Spares::instance().reuse(maxBytes); }

void* takeBlock(size_t bytes) { return Spares::instance().take(bytes); }

void giveBackBlock(void* p, size_t bytes) noexcept { Spares::instance().giveBack(p, bytes); }

size_t waitForSpareBlocks() { return Spares::instance().waitIdle(); }

}  // namespace raypc
