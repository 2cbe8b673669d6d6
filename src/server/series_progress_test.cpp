#include "server/series_progress.h"

#include <gtest/gtest.h>

#include <chrono>

namespace raypc::server {
namespace {

using Clock = SeriesProgress::Clock;
using std::chrono::milliseconds;

// A one-pass run (`raypc serve FILES`) reports its steps and its pathline sets in turn. The UI's line
// stays on the steps until they are all written, then goes to the pathlines, and the time left is the
// phase's own at its rate over this run, not from the time since the other phase's last report.
TEST(SeriesProgress, StepsAndPathlinesReportedInTurnKeepTheirOwnRatesAndTheStepsAreShownFirst)
{
    const Clock::time_point t0{};
    const auto at = [&](int ms) { return t0 + milliseconds(ms); };
    SeriesProgress progress("/tmp/series", 12, t0);
    EXPECT_EQ(progress.toJson(t0)["phase"], "steps");
    EXPECT_EQ(progress.toJson(t0)["total"], 12);
    EXPECT_TRUE(progress.toJson(t0)["etaSeconds"].is_null());

    progress.update({"steps", 2, 12}, at(0));  // two steps finished by an earlier run
    EXPECT_TRUE(progress.toJson(at(500))["etaSeconds"].is_null()) << "no item of this run yet";
    // A step a second; the first pathline set 0.9 s after the fourth step.
    progress.update({"steps", 3, 12}, at(1000));
    progress.update({"steps", 4, 12}, at(2000));
    progress.update({"pathlines", 1, 12}, at(2900));
    EXPECT_EQ(progress.toJson(at(2900))["phase"], "steps");
    progress.update({"steps", 5, 12}, at(3000));

    nlohmann::json j = progress.toJson(at(3200));
    EXPECT_EQ(j["phase"], "steps");
    EXPECT_EQ(j["done"], 5);
    EXPECT_EQ(j["total"], 12);
    // 3 steps in 3 s, 7 left: 7 s, 0.2 s of it gone.
    EXPECT_NEAR(j["etaSeconds"].get<double>(), 6.8, 1e-6);
    EXPECT_NEAR(j["elapsedSeconds"].get<double>(), 3.2, 1e-6);

    for (int s = 6; s <= 12; ++s)
        progress.update({"steps", s, 12}, at(1000 * (s - 2)));
    progress.update({"pathlines", 8, 12}, at(10000));
    j = progress.toJson(at(10000));
    EXPECT_EQ(j["phase"], "pathlines") << "every step is written: the pathlines are what is left";
    EXPECT_EQ(j["done"], 8);
    // Pathlines: 8 sets in 8 s since the report before their first (2.0 s), 4 left.
    EXPECT_NEAR(j["etaSeconds"].get<double>(), 4.0, 1e-6);
    EXPECT_NEAR(progress.toJson(at(15000))["etaSeconds"].get<double>(), 0.0, 1e-6) << "late: never negative";

    progress.finished();
    j = progress.toJson(at(15000));
    EXPECT_EQ(j["state"], "ready");
    EXPECT_TRUE(j["etaSeconds"].is_null());
}

TEST(SeriesProgress, AFailedRunSaysWhyAndGivesNoTimeLeft)
{
    SeriesProgress progress("/tmp/series", 3);
    progress.update({"steps", 0, 3});
    progress.update({"steps", 1, 3});
    progress.failed("spherical002.nc: not a netCDF file");
    const nlohmann::json j = progress.toJson();
    EXPECT_EQ(j["state"], "failed");
    EXPECT_EQ(j["message"], "spherical002.nc: not a netCDF file");
    EXPECT_EQ(j["done"], 1);
    EXPECT_TRUE(j["etaSeconds"].is_null());
}

}  // namespace
}  // namespace raypc::server
