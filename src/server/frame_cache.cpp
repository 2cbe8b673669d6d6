#include "server/frame_cache.h"

#include <algorithm>

namespace raypc::server {

int typicalPlaybackLevel(const std::vector<int>& countsByLevel)
{
    int total = 0;
    for (const int n : countsByLevel)
        total += n;
    if (total <= 0)
        return -1;
    int finer = 0;
    for (size_t level = 0; level < countsByLevel.size(); ++level)
        if ((finer += countsByLevel[level]) * 2 >= total)
            return int(level);
    return int(countsByLevel.size()) - 1;  // not reached: the counts add up to the total
}

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

std::shared_ptr<const EncodedFrame> FrameCache::find(const std::string& key, int step, int draftsUpToLevel)
{
    std::lock_guard lock(m_mutex);
    if (key != m_key)
        return nullptr;
    const auto it = m_frames.find(step);
    if (it == m_frames.end() ||
        (!it->second->finished && it->second->header.value("level", 0) > draftsUpToLevel))
        return nullptr;
    ++m_hits;
    return it->second;
}

bool FrameCache::contains(const std::string& key, int step, bool finishedOnly) const
{
    std::lock_guard lock(m_mutex);
    const auto it = m_frames.find(step);
    return key == m_key && it != m_frames.end() && (!finishedOnly || it->second->finished);
}

bool FrameCache::insert(const std::string& key, int step, std::shared_ptr<const EncodedFrame> frame)
{
    const size_t bytes = frame->bytes();
    std::lock_guard lock(m_mutex);
    const auto it = m_frames.find(step);
    const bool replacesDraft = it != m_frames.end() && !it->second->finished && frame->finished;
    const size_t freed = replacesDraft ? it->second->bytes() : 0;
    if (key != m_key || (it != m_frames.end() && !replacesDraft) || m_bytes - freed + bytes > m_maxBytes)
        return false;
    // The frame memory: what the frame adds beyond the draft it replaces (or gives back, if smaller).
    if (m_budget && bytes > freed && !m_budget->takeKept(bytes - freed))
        return false;  // the sessions' images and the other kept frames fill the frame memory
    if (m_budget && freed > bytes)
        m_budget->returnKept(freed - bytes);
    m_bytes = m_bytes - freed + bytes;
    m_frames[step] = std::move(frame);
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
