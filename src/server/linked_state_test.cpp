#include "server/linked_state.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace raypc::server {
namespace {

using nlohmann::json;

json brushed(double minKm, double maxKm)
{
    return {{"version", 7}, {"step", 1}, {"brushes", json::array({{{"name", "depth"}, {"min", minKm}, {"max", maxKm}}})}};
}

TEST(LinkedState, StartsEmptyAtVersionZero)
{
    const LinkedState link;
    EXPECT_EQ(link.toJson(), json::parse(R"({"version": 0, "state": null, "source": null, "sessions": 0})"));
}

TEST(LinkedState, EveryChangeBumpsTheVersionAndNamesItsSource)
{
    LinkedState link;
    EXPECT_TRUE(link.commitFromUi(brushed(560, 760)));
    json j = link.toJson();
    EXPECT_EQ(j["version"], 1);
    EXPECT_EQ(j["source"], "ui");
    EXPECT_EQ(j["state"], brushed(560, 760));

    const LinkedState::Pushed pushed = link.setFromApi(brushed(100, 200));
    EXPECT_EQ(pushed.version, 2u);
    EXPECT_EQ(pushed.sessions, 0u);
    j = link.toJson();
    EXPECT_EQ(j["version"], 2);
    EXPECT_EQ(j["source"], "api");
    EXPECT_EQ(j["state"], brushed(100, 200));

    EXPECT_TRUE(link.commitFromUi(brushed(100, 300)));
    EXPECT_EQ(link.toJson()["version"], 3);
    EXPECT_EQ(link.toJson()["source"], "ui");
}

TEST(LinkedState, TheUiSendingBackTheSameStateIsNoChange)
{
    LinkedState link;
    link.setFromApi(brushed(560, 760));
    // JSON-equal: the same document with its keys in another order and 560 written as 560.0.
    const json same = json::parse(R"({"brushes": [{"max": 760, "min": 560.0, "name": "depth"}], "step": 1, "version": 7})");
    EXPECT_FALSE(link.commitFromUi(same));
    json j = link.toJson();
    EXPECT_EQ(j["version"], 1);
    EXPECT_EQ(j["source"], "api");
    EXPECT_FALSE(link.commitFromUi(brushed(560, 760)));
    EXPECT_EQ(link.toJson()["version"], 1);
    // A program setting the same state again is a change (it is pushed again).
    EXPECT_EQ(link.setFromApi(brushed(560, 760)).version, 2u);
}

TEST(LinkedState, APushedStateGoesToEverySessionInOrderUntilItIsRemoved)
{
    LinkedState link;
    std::vector<std::string> a, b;
    const uint64_t keyA = link.addSession([&](std::string text) { a.push_back(std::move(text)); });
    link.addSession([&](std::string text) { b.push_back(std::move(text)); });
    EXPECT_EQ(link.toJson()["sessions"], 2);

    EXPECT_EQ(link.setFromApi(brushed(560, 760)).sessions, 2u);
    link.commitFromUi(brushed(0, 100));  // the UI's own changes are not pushed
    link.removeSession(keyA);
    link.removeSession(keyA);
    EXPECT_EQ(link.toJson()["sessions"], 1);
    EXPECT_EQ(link.setFromApi(brushed(600, 700)).sessions, 1u);

    ASSERT_EQ(a.size(), 1u);
    ASSERT_EQ(b.size(), 2u);
    EXPECT_EQ(json::parse(a[0]), json({{"type", "link"}, {"version", 1}, {"state", brushed(560, 760)}}));
    EXPECT_EQ(json::parse(b[1]), json({{"type", "link"}, {"version", 3}, {"state", brushed(600, 700)}}));
}

// What must reach a session first (its hello reply) runs once it counts and before any push to it.
TEST(LinkedState, WhatASessionGetsFirstComesBeforeAnyPush)
{
    LinkedState link;
    std::vector<std::string> got;
    int firstCalls = 0;
    link.addSession([&](std::string text) { got.push_back(std::move(text)); }, [&] {
        ++firstCalls;
        got.push_back("hello");
    });
    EXPECT_EQ(firstCalls, 1);
    EXPECT_EQ(link.toJson()["sessions"], 1);
    link.setFromApi(brushed(100, 200));
    ASSERT_EQ(got.size(), 2u);
    EXPECT_EQ(got[0], "hello");
    EXPECT_EQ(json::parse(got[1])["type"], "link");
}

}  // namespace
}  // namespace raypc::server
