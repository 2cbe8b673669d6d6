// The linked state (docs/protocol.md, GET/POST /api/link): the state the UI shows, readable and
// settable by a program (e.g. a notebook's `view.state`). It is the last settled state a
// WebSocket session committed (source "ui") or the last state a program set (source "api"), with a
// version that counts its changes; a state a program sets is pushed to every open session as a
// `link` message. No network types here: a session registers a sink that hands text to its
// connection.
//
// Thread safety: every member may be called from any thread. Sinks are called with the registry's
// lock held (so that every session sees the versions in order): they must only hand the text over
// (e.g. post it to the session's network thread) and never call back into the registry.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>

namespace raypc::server {

enum class LinkSource { None, Ui, Api };

class LinkedState {
public:
    using Sink = std::function<void(std::string text)>;

    // A session that receives `link` messages until it is removed; returns its key for removeSession.
    // `first` (optional) runs once the session counts and before any state can be pushed to it
    // (under the lock): what must reach it before any link message, e.g. its hello reply, so that a
    // client that has its reply is already among the sessions GET /api/link counts.
    uint64_t addSession(Sink sink, const std::function<void()>& first = {});
    // Removing a key that is not there (or twice) does nothing.
    void removeSession(uint64_t key);

    // A session's settled state, already validated and handed to rendering: it becomes the linked
    // state (source ui, version + 1) unless it is JSON-equal to the current one. True when it changed.
    bool commitFromUi(const nlohmann::json& state);

    struct Pushed {
        uint64_t version = 0;
        size_t sessions = 0;  // the sessions it was sent to
    };
    // A program's state, already validated: it becomes the linked state (source api, version + 1)
    // and goes to every session as {"type": "link", "version": N, "state": …}.
    Pushed setFromApi(const nlohmann::json& state);

    // GET /api/link: {version, state (null before the first), source ("ui", "api" or null), sessions}.
    nlohmann::json toJson() const;

private:
    mutable std::mutex m_mutex;
    uint64_t m_version = 0;
    nlohmann::json m_state;  // null until the first change
    LinkSource m_source = LinkSource::None;
    uint64_t m_nextKey = 0;
    std::map<uint64_t, Sink> m_sessions;
};

}  // namespace raypc::server
