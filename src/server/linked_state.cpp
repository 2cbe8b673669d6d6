#include "server/linked_state.h"

#include "server/protocol.h"

namespace raypc::server {

using nlohmann::json;

uint64_t LinkedState::addSession(Sink sink, const std::function<void()>& first)
{
    std::lock_guard lock(m_mutex);
    const uint64_t key = ++m_nextKey;
    m_sessions.emplace(key, std::move(sink));
    if (first)
        first();
    return key;
}

void LinkedState::removeSession(uint64_t key)
{
    std::lock_guard lock(m_mutex);
    m_sessions.erase(key);
}

bool LinkedState::commitFromUi(const json& state)
{
    std::lock_guard lock(m_mutex);
    // A state the UI sends back unchanged (e.g. one a program just set) is no change.
    if (state == m_state)
        return false;
    m_state = state;
    m_source = LinkSource::Ui;
    ++m_version;
    return true;
}

LinkedState::Pushed LinkedState::setFromApi(const json& state)
{
    std::lock_guard lock(m_mutex);
    m_state = state;
    m_source = LinkSource::Api;
    ++m_version;
    const std::string text = linkMessage(m_version, m_state);
    for (const auto& [key, sink] : m_sessions)
        sink(text);
    return {m_version, m_sessions.size()};
}

json LinkedState::toJson() const
{
    std::lock_guard lock(m_mutex);
    const json source = m_source == LinkSource::Ui ? json("ui") : m_source == LinkSource::Api ? json("api") : json();
    return {{"version", m_version}, {"state", m_state}, {"source", source}, {"sessions", m_sessions.size()}};
}

}  // namespace raypc::server
