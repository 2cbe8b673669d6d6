#include "server/frame_cache.h"

#include <algorithm>

namespace raypc::server {

size_t EncodedFrame::bytes() const
{
    return jpeg.size() + depth.size() * sizeof(float) + header.dump().size() + sizeof(EncodedFrame);
}

std::string frameCacheKey(const nlohmann::json& document)
{
    nlohmann::json key = document;
    key.erase("step");
    key.erase("timeBudgetMs");
    return key.dump();
}

void FrameBudget::addCache(FrameCache* cache)
{
    std::lock_guard lock(m_cachesMutex);
    m_caches.push_back(cache);
}

void FrameBudget::removeCache(FrameCache* cache)
{
    std::lock_guard lock(m_cachesMutex);
    std::erase(m_caches, cache);
}

size_t FrameBudget::reclaimKeptFrames()
{
    std::lock_guard lock(m_cachesMutex);
    size_t freed = 0;
    for (FrameCache* cache : m_caches)
        freed += cache->clear();
    return freed;
}

FrameCache::FrameCache(size_t maxBytes, FrameBudget* budget) : m_maxBytes(maxBytes), m_budget(budget)
{
    if (m_budget)
        m_budget->addCache(this);
}

FrameCache::~FrameCache()
{
    if (m_budget)
        m_budget->removeCache(this);  // first: reclaimKeptFrames no longer reaches this cache
    std::lock_guard lock(m_mutex);
    dropLocked();
}

void FrameCache::dropLocked()
{
    if (m_budget)
        m_budget->returnKept(m_bytes);
    m_frames.clear();
    m_bytes = 0;
}

void FrameCache::setKey(const std::string& key)
{
    std::lock_guard lock(m_mutex);
    if (key == m_key)
        return;
    m_key = key;
    dropLocked();
}

size_t FrameCache::clear()
{
    std::lock_guard lock(m_mutex);
    const size_t freed = m_bytes;
    dropLocked();
    return freed;
}

std::shared_ptr<const EncodedFrame> FrameCache::find(const std::string& key, int step)
{
    std::lock_guard lock(m_mutex);
    if (key != m_key)
        return nullptr;
    const auto it = m_frames.find(step);
    if (it == m_frames.end())
        return nullptr;
    ++m_hits;
    return it->second;
}

bool FrameCache::contains(const std::string& key, int step) const
{
    std::lock_guard lock(m_mutex);
    return key == m_key && m_frames.contains(step);
}

bool FrameCache::insert(const std::string& key, int step, std::shared_ptr<const EncodedFrame> frame)
{
    const size_t bytes = frame->bytes();
    std::lock_guard lock(m_mutex);
    if (key != m_key || m_frames.contains(step) || m_bytes + bytes > m_maxBytes)
        return false;
    if (m_budget && !m_budget->takeKept(bytes))
        return false;  // the sessions' images and the other kept frames fill the frame memory
    m_frames.emplace(step, std::move(frame));
    m_bytes += bytes;
    return true;
}

bool FrameCache::hasRoomFor(size_t bytes) const
{
    std::lock_guard lock(m_mutex);
    return m_bytes + bytes <= m_maxBytes && (!m_budget || m_budget->fitsKept(bytes));
}

size_t FrameCache::bytes() const
{
    std::lock_guard lock(m_mutex);
    return m_bytes;
}

size_t FrameCache::frames() const
{
    std::lock_guard lock(m_mutex);
    return m_frames.size();
}

uint64_t FrameCache::hits() const
{
    std::lock_guard lock(m_mutex);
    return m_hits;
}

}  // namespace raypc::server
