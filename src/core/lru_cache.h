// A small thread-safe cache of shared values by key, least recently used out: the server's caches of
// pathline windows and persistence pairs (server/dataset_caches.h). The step cache (server/step_cache.h)
// bounds bytes and pins what renderers hold, so it has its own.
//
// Thread safety: get() from any thread; values are made outside the lock.
#pragma once

#include <algorithm>
#include <cstddef>
#include <list>
#include <memory>
#include <mutex>
#include <utility>

namespace raypc {

template <typename Key, typename Value>
class LruCache {
public:
    explicit LruCache(size_t maxEntries) : m_maxEntries(std::max<size_t>(1, maxEntries)) {}

    // The value of `key`: the cached one (now the most recently used), else `make()` (a Value),
    // cached with the least recently used beyond maxEntries dropped. make() runs outside the lock, so
    // two threads may make the same key once each, which is harmless; its exceptions propagate and
    // nothing is cached then.
    template <typename Make>
    std::shared_ptr<const Value> get(const Key& key, Make&& make)
    {
        {
            std::lock_guard lock(m_mutex);
            for (auto it = m_lru.begin(); it != m_lru.end(); ++it)
                if (it->first == key) {
                    m_lru.splice(m_lru.begin(), m_lru, it);
                    return it->second;
                }
        }
        auto value = std::make_shared<const Value>(make());
        std::lock_guard lock(m_mutex);
        m_lru.emplace_front(key, value);
        while (m_lru.size() > m_maxEntries)
            m_lru.pop_back();
        return value;
    }

private:
    size_t m_maxEntries;
    std::mutex m_mutex;
    std::list<std::pair<Key, std::shared_ptr<const Value>>> m_lru;  // most recently used first
};

}  // namespace raypc
