// A small thread-safe cache of shared values by key, least recently used out: the server's caches of
// pathline windows and persistence pairs (server/dataset_caches.h), of selection statistics per step
// and of feature series (server/analysis_caches.h). The step cache (server/step_cache.h) bounds bytes
// and pins what renderers hold, so it has its own.
//
// Thread safety: every member function from any thread; values are made outside the lock, and
// concurrent requests of one key share one making.
#pragma once

#include <algorithm>
#include <cstddef>
#include <exception>
#include <future>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <utility>

namespace raypc {

// Key needs operator< (it indexes a std::map).
template <typename Key, typename Value>
class LruCache {
public:
    using Ptr = std::shared_ptr<const Value>;

    // How the values given so far came: found in the cache, waited for while another caller made
    // them, or made by the caller (what a test counts to see that a value was made once).
    struct Counts {
        size_t hits = 0, shared = 0, made = 0;
    };

    explicit LruCache(size_t maxEntries) : m_maxEntries(std::max<size_t>(1, maxEntries)) {}

    // The value of `key`: the cached one (now the most recently used); else the one another thread is
    // making for it, waited for; else `make()` (a Value), cached with the least recently used beyond
    // maxEntries dropped. make() runs outside the lock. Its exceptions propagate, to the threads that
    // waited for it too, and nothing is cached then. `how`, when given, says which of the three it was.
    template <typename Make>
    Ptr get(const Key& key, Make&& make, int* how = nullptr)
    {
        std::promise<Ptr> promise;
        std::shared_future<Ptr> other;
        {
            std::lock_guard lock(m_mutex);
            if (const auto it = m_index.find(key); it != m_index.end()) {
                m_lru.splice(m_lru.begin(), m_lru, it->second);
                ++m_counts.hits;
                if (how)
                    *how = kHit;
                return it->second->second;
            }
            if (const auto it = m_making.find(key); it != m_making.end()) {
                other = it->second;
                ++m_counts.shared;
            } else {
                m_making.emplace(key, promise.get_future().share());
                ++m_counts.made;
            }
        }
        if (other.valid()) {
            if (how)
                *how = kShared;
            return other.get();  // rethrows the maker's exception
        }
        if (how)
            *how = kMade;
        Ptr value;
        try {
            value = std::make_shared<const Value>(make());
        } catch (...) {
            {
                std::lock_guard lock(m_mutex);
                m_making.erase(key);
            }
            promise.set_exception(std::current_exception());
            throw;
        }
        {
            std::lock_guard lock(m_mutex);
            m_making.erase(key);
            insertLocked(key, value);
        }
        promise.set_value(value);
        return value;
    }

    // The cached value of `key` (now the most recently used), or nullptr; makes nothing.
    Ptr find(const Key& key)
    {
        std::lock_guard lock(m_mutex);
        const auto it = m_index.find(key);
        if (it == m_index.end())
            return nullptr;
        m_lru.splice(m_lru.begin(), m_lru, it->second);
        return it->second->second;
    }

    // Caches `value` as the value of `key` (replacing one there), the least recently used out.
    void put(const Key& key, Ptr value)
    {
        std::lock_guard lock(m_mutex);
        insertLocked(key, std::move(value));
    }

    Counts counts() const
    {
        std::lock_guard lock(m_mutex);
        return m_counts;
    }
    size_t size() const
    {
        std::lock_guard lock(m_mutex);
        return m_lru.size();
    }

    // The values of get()'s `how`.
    static constexpr int kHit = 0, kShared = 1, kMade = 2;

private:
    using Entries = std::list<std::pair<Key, Ptr>>;  // most recently used first

    void insertLocked(const Key& key, Ptr value)
    {
        if (const auto it = m_index.find(key); it != m_index.end()) {
            it->second->second = std::move(value);
            m_lru.splice(m_lru.begin(), m_lru, it->second);
            return;
        }
        m_lru.emplace_front(key, std::move(value));
        m_index.emplace(key, m_lru.begin());
        while (m_lru.size() > m_maxEntries) {
            m_index.erase(m_lru.back().first);
            m_lru.pop_back();
        }
    }

    size_t m_maxEntries;
    mutable std::mutex m_mutex;
    Entries m_lru;
    std::map<Key, typename Entries::iterator> m_index;
    std::map<Key, std::shared_future<Ptr>> m_making;  // keys being made, for the callers that come meanwhile
    Counts m_counts;
};

}  // namespace raypc
