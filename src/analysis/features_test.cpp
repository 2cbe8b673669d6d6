#include "analysis/features.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "dataset/dataset_format.h"
#include "core/spherical.h"
#include "grid/coordinates.h"
#include "grid/test_util.h"
#include "io/netcdf_reader.h"
#include "preprocess/preprocess.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

namespace raypc::analysis {
namespace {

using testing::TempDir;

// A volume of one field "f" on a centred grid (no pole rows), given per grid point.
std::shared_ptr<dataset::StepVolume> volumeOf(const grid::SphericalGrid& g, const std::function<double(size_t, size_t, size_t)>& f,
                                     const std::string& units = "K")
{
    grid::Snapshot snap;
    snap.grid = g;
    snap.fields.push_back({"f", units, testing::fillGrid(g, f)});
    return dataset::StepVolume::fromSnapshot(snap);
}

std::vector<RangeFilter> above(float threshold) { return {RangeFilter{0, std::nullopt, {{threshold, 1e30f}}}}; }

// Circular distance of two longitudes, degrees.
double lonDistance(double a, double b)
{
    const double d = std::fmod(std::abs(a - b), 360.0);
    return std::min(d, 360.0 - d);
}

TEST(Features, ABlobAcrossTheSeamIsOneFeatureWithItsVolumeAndCentroid)
{
    const grid::SphericalGrid g = testing::centredGrid(36, 21, 72);
    // Centred on the seam (lon 0) at 1000 km depth: half its points have lon near 360.
    const auto volume = volumeOf(g, [&](size_t a, size_t r, size_t o) {
        return testing::gaussianBlob(g, a, r, o, 10.0, 0.0, kSurfaceRadiusKm - 1000.0, 600.0);
    });
    const auto filters = above(0.5f);
    const StepFeatures f = extractFeatures(*volume, filters);
    ASSERT_EQ(f.features.size(), 1u);
    const Feature& blob = f.features[0];
    EXPECT_EQ(blob.id, 1);
    EXPECT_NEAR(blob.volumeKm3, selectedVolume(*volume, filters).volumeKm3, 1e-6 * blob.volumeKm3);
    bool east = false, west = false;
    size_t labelled = 0;
    for (size_t a = 0; a < g.nLat(); ++a)
        for (size_t r = 0; r < g.nR(); ++r)
            for (size_t o = 0; o < g.nLon(); ++o)
                if (f.labels[g.index(a, r, o)] == 1) {
                    ++labelled;
                    east |= g.lonDeg[o] < 30;
                    west |= g.lonDeg[o] > 330;
                }
    EXPECT_TRUE(east && west) << "the blob's points lie on both sides of the seam";
    EXPECT_EQ(labelled, blob.points);
    EXPECT_LT(lonDistance(blob.centroidLonDeg, 0.0), 2.5) << blob.centroidLonDeg;
    EXPECT_NEAR(blob.centroidLatDeg, 10.0, 2.5);
    // The centroid of a ball is its centre (the grid's own sampling of it aside).
    EXPECT_NEAR(blob.centroidDepthKm, 1000.0, 60.0);
    EXPECT_LE(blob.topDepthKm, 1000.0);
    EXPECT_GE(blob.bottomDepthKm, 1000.0);
    ASSERT_EQ(blob.variables.size(), 1u);
    EXPECT_GE(blob.variables[0].min, 0.5);
    EXPECT_LE(blob.variables[0].max, 1.0);
    EXPECT_GT(blob.variables[0].mean, 0.5);
    EXPECT_LT(blob.variables[0].mean, blob.variables[0].max);
}

TEST(Features, ARingAroundAPoleIsOneFeature)
{
    const grid::SphericalGrid g = testing::centredGrid(36, 11, 72);
    // Selected: the outermost northern row only, four arcs of 45 degrees with gaps of 45 degrees
    // between them: connected only through the pole.
    const auto volume = volumeOf(g, [&](size_t a, size_t, size_t o) {
        return a == g.nLat() - 1 && (o % 18) < 9 ? 1.0 : 0.0;
    });
    const StepFeatures f = extractFeatures(*volume, above(0.5f));
    ASSERT_EQ(f.features.size(), 1u);
    EXPECT_GT(f.features[0].centroidLatDeg, 85.0);
    // The same arcs one row further from the pole are four features.
    const auto off = volumeOf(g, [&](size_t a, size_t, size_t o) { return a == g.nLat() - 2 && (o % 18) < 9 ? 1.0 : 0.0; });
    EXPECT_EQ(extractFeatures(*off, above(0.5f)).features.size(), 4u);
}

TEST(Features, SeparateBlobsAreFeaturesByDecreasingVolumeAndSpecksAreDropped)
{
    const grid::SphericalGrid g = testing::centredGrid(36, 21, 72);
    const auto volume = volumeOf(g, [&](size_t a, size_t r, size_t o) {
        return testing::gaussianBlob(g, a, r, o, -20.0, 90.0, 5000.0, 300.0) +
               testing::gaussianBlob(g, a, r, o, 30.0, 250.0, 4500.0, 700.0);
    });
    const auto filters = above(0.5f);
    StepFeatures f = extractFeatures(*volume, filters);
    ASSERT_EQ(f.features.size(), 2u);
    EXPECT_GT(f.features[0].volumeKm3, f.features[1].volumeKm3);
    EXPECT_LT(lonDistance(f.features[0].centroidLonDeg, 250.0), 5.0);
    EXPECT_LT(lonDistance(f.features[1].centroidLonDeg, 90.0), 5.0);
    std::map<int32_t, size_t> counts;
    for (const int32_t label : f.labels)
        ++counts[label];
    EXPECT_EQ(counts[1], f.features[0].points);
    EXPECT_EQ(counts[2], f.features[1].points);
    EXPECT_NEAR(f.features[0].volumeKm3 + f.features[1].volumeKm3, selectedVolume(*volume, filters).volumeKm3,
                1e-6 * f.features[0].volumeKm3);

    FeatureOptions options;
    options.minVolumeKm3 = 0.5 * (f.features[0].volumeKm3 + f.features[1].volumeKm3);
    ASSERT_GT(options.minVolumeKm3, f.features[1].volumeKm3);
    ASSERT_LT(options.minVolumeKm3, f.features[0].volumeKm3);
    const StepFeatures big = extractFeatures(*volume, filters, options);
    ASSERT_EQ(big.features.size(), 1u);
    EXPECT_EQ(big.features[0].volumeKm3, f.features[0].volumeKm3);
    size_t dropped = 0;
    for (size_t i = 0; i < big.labels.size(); ++i)
        dropped += f.labels[i] == 2 && big.labels[i] == 0;
    EXPECT_EQ(dropped, f.features[1].points);
}

TEST(Features, AShellSelectedByDepthIsOneFeatureWithItsBandShares)
{
    const grid::SphericalGrid g = testing::centredGrid(18, 41, 36);
    const auto volume = volumeOf(g, [](size_t, size_t, size_t) { return 3.0; });
    const std::vector<RangeFilter> filters{RangeFilter{-1, grid::Coordinate::Depth, {{500.0f, 900.0f}}}};
    FeatureOptions options;
    options.bandDepthsKm = {660.0, 2000.0};
    const StepFeatures f = extractFeatures(*volume, filters, options);
    ASSERT_EQ(f.features.size(), 1u);
    const Feature& shell = f.features[0];
    // The share within ±50 km of 660 km, from the grid's radii and their shells' volumes.
    const auto w = g.volumeFactors();
    double inBand = 0, all = 0;
    for (size_t r = 0; r < g.nR(); ++r) {
        const double depth = kSurfaceRadiusKm - g.rKm[r];
        if (depth < 500.0 || depth > 900.0)
            continue;
        all += w.r[r];
        inBand += std::abs(depth - 660.0) <= 50.0 ? w.r[r] : 0.0;
    }
    ASSERT_GT(inBand, 0.0);
    ASSERT_EQ(shell.bandFractions.size(), 2u);
    EXPECT_NEAR(shell.bandFractions[0], inBand / all, 1e-9);
    EXPECT_EQ(shell.bandFractions[1], 0.0);
    EXPECT_NEAR(shell.variables[0].mean, 3.0, 1e-12);
    EXPECT_NEAR(shell.centroidDepthKm, kSurfaceRadiusKm, 1.0) << "a whole shell's centroid is the planet's centre";
}

TEST(Features, AnEmptySelectionHasNoFeaturesAndBadOptionsAreRefused)
{
    const grid::SphericalGrid g = testing::centredGrid(8, 5, 16);
    const auto volume = volumeOf(g, [](size_t, size_t, size_t) { return 0.0; });
    const StepFeatures f = extractFeatures(*volume, above(1.0f));
    EXPECT_TRUE(f.features.empty());
    EXPECT_EQ(std::count(f.labels.begin(), f.labels.end(), 0), std::ptrdiff_t(g.cellCount()));
    FeatureOptions bad;
    bad.minVolumeKm3 = -1;
    EXPECT_THROW(extractFeatures(*volume, above(1.0f), bad), Error);
    const std::vector<RangeFilter> unknownVariable{RangeFilter{3, std::nullopt, {{0, 1}}}};
    EXPECT_THROW(extractFeatures(*volume, unknownVariable), Error);
}


// A blob (variable 0) at (latDeg, lonDeg, 5000 km) in a solid-body rotation about the z axis by
// `degreesPerMyr` (variables 1-3: vx, vy, vz in m/s).
std::shared_ptr<dataset::StepVolume> rotatingBlobs(const grid::SphericalGrid& g, const std::vector<std::pair<double, double>>& blobs,
                                          double degreesPerMyr)
{
    grid::Snapshot snap;
    snap.grid = g;
    snap.fields.push_back({"f", "1", testing::fillGrid(g, [&](size_t a, size_t r, size_t o) {
                               double v = 0;
                               for (const auto& [lat, lon] : blobs)
                                   v += testing::gaussianBlob(g, a, r, o, lat, lon, 5000.0, 300.0);
                               return v;
                           })});
    const double omega = degToRad(degreesPerMyr) / kSecondsPerMyr;  // rad/s
    for (const int axis : {0, 1, 2})
        snap.fields.push_back({std::string("v") + "xyz"[axis], "m/s", testing::fillGrid(g, [&](size_t a, size_t r, size_t o) {
                                   const Vec3d p = sphericalToCartesianKm(g.latDeg[a], g.lonDeg[o], g.rKm[r]);
                                   const Vec3d v{-omega * p.y * 1e3, omega * p.x * 1e3, 0.0};  // m/s
                                   return axis == 0 ? v.x : axis == 1 ? v.y : v.z;
                               })});
    return dataset::StepVolume::fromSnapshot(snap);
}

TEST(FeatureTracks, AFastBlobIsLinkedAfterMovingItsPointsWithTheFlow)
{
    const grid::SphericalGrid g = testing::centredGrid(72, 41, 144);
    const VelocityVariables velocity{1, 2, 3};
    // 15 degrees a step, 2 Myr apart: at 5000 km about 1300 km, four times the blob's radius.
    std::vector<std::shared_ptr<dataset::StepVolume>> steps;
    std::vector<StepFeatures> features;
    for (int k = 0; k < 3; ++k) {
        steps.push_back(rotatingBlobs(g, {{20.0, 40.0 + 15.0 * k}}, 7.5));
        features.push_back(extractFeatures(*steps.back(), above(0.5f)));
        ASSERT_EQ(features.back().features.size(), 1u);
    }
    const auto links = linkFeatures(*steps[0], features[0], features[1], velocity, 2.0);
    ASSERT_EQ(links.size(), 1u);
    EXPECT_EQ(links[0].from, 1);
    EXPECT_EQ(links[0].to, 1);
    EXPECT_GT(links[0].overlapKm3, 0.5 * features[0].features[0].volumeKm3);
    // Bare positions (no time to move): the blob of the next step is elsewhere.
    EXPECT_TRUE(linkFeatures(*steps[0], features[0], features[1], velocity, 0.0).empty());

    FeatureTracker tracker;
    std::vector<int> tracks;
    for (int k = 0; k < 3; ++k)
        tracks.push_back(tracker.add(k, features[size_t(k)], k == 0 ? std::vector<FeatureLink>{}
                                     : linkFeatures(*steps[size_t(k) - 1], features[size_t(k) - 1], features[size_t(k)], velocity, 2.0))[0]);
    EXPECT_EQ(tracks, (std::vector<int>{1, 1, 1})) << "one track";
    EXPECT_TRUE(tracker.events().empty());
}

TEST(FeatureTracks, TouchingBlobsMergeAndMovingApartSplitAndLoneOnesAreBornAndDie)
{
    const grid::SphericalGrid g = testing::centredGrid(72, 41, 144);
    const VelocityVariables velocity{1, 2, 3};
    // Step 0: two blobs 16 degrees (1400 km) apart; step 1: a chain of blobs 4 degrees apart over
    // both (one feature; the flow at rest); step 2: the two again; step 3: a blob somewhere else.
    const std::vector<std::pair<double, double>> two{{0.0, 100.0}, {0.0, 116.0}};
    const std::vector<std::vector<std::pair<double, double>>> layout{
        two, {{0.0, 100.0}, {0.0, 104.0}, {0.0, 108.0}, {0.0, 112.0}, {0.0, 116.0}}, two, {{-40.0, 250.0}}};
    FeatureTracker tracker;
    std::shared_ptr<dataset::StepVolume> previous;
    StepFeatures previousFeatures;
    std::vector<std::vector<int>> tracks;
    for (size_t k = 0; k < layout.size(); ++k) {
        const auto volume = rotatingBlobs(g, layout[k], 0.0);
        StepFeatures f = extractFeatures(*volume, above(0.5f));
        tracks.push_back(tracker.add(int(k), f, previous ? linkFeatures(*previous, previousFeatures, f, velocity, 1.0)
                                                         : std::vector<FeatureLink>{}));
        previous = volume;
        previousFeatures = std::move(f);
    }
    ASSERT_EQ(tracks[0].size(), 2u);
    ASSERT_EQ(tracks[1].size(), 1u) << "the chain of step 1 is one feature";
    ASSERT_EQ(tracks[2].size(), 2u);
    std::vector<std::string> seen;
    for (const TrackEvent& e : tracker.events())
        seen.push_back(fmt::format("{} {} {}", trackEventName(e.kind), e.step, e.others.size()));
    EXPECT_EQ(seen, (std::vector<std::string>{"merge 1 2", "split 1 2", "birth 3 0", "death 2 0", "death 2 0"}))
        << fmt::format("{}", fmt::join(seen, "; "));
    EXPECT_TRUE(tracks[1][0] == tracks[0][0] || tracks[1][0] == tracks[0][1]) << "the merged blob continues a track";
    EXPECT_NE(tracks[3][0], tracks[2][0]);
    EXPECT_NE(tracks[3][0], tracks[2][1]);
}


TEST(FeatureTracks, StallsAreRunsOfStepsNearADepthAndSayHowTheyEnded)
{
    // A slab sinking to 660 km, held there for 3 steps (2 Myr apart), then sinking on; another
    // depth band it only passes through in one step.
    const std::vector<TrackPoint> track{{0, 0, 450, -2}, {1, 2, 560, -2}, {2, 4, 650, -0.2}, {3, 6, 668, -0.1},
                                        {4, 8, 655, -0.3}, {5, 10, 800, -1.5}, {6, 12, 1010, -1.5}};
    const std::vector<double> depths{660, 1000};
    const auto stalls = stallTimes(track, depths, 50, 9);
    ASSERT_EQ(stalls.size(), 2u);
    EXPECT_EQ(stalls[0].depthKm, 660);
    EXPECT_EQ(stalls[0].firstStep, 2);
    EXPECT_EQ(stalls[0].lastStep, 4);
    EXPECT_DOUBLE_EQ(stalls[0].durationMyr, 4.0);
    EXPECT_NEAR(stalls[0].meanRadialVelocityCmPerYr, -0.2, 1e-12);
    EXPECT_EQ(stalls[0].left, "down");
    EXPECT_EQ(stalls[1].depthKm, 1000);
    EXPECT_EQ(stalls[1].firstStep, 6);
    EXPECT_DOUBLE_EQ(stalls[1].durationMyr, 0.0);
    EXPECT_EQ(stalls[1].left, "ended") << "the track stops at step 6 of a series to step 9";
    EXPECT_EQ(stallTimes(track, depths, 50, 6)[1].left, "") << "still there at the series' last step";
    const std::vector<TrackPoint> rising{{0, 0, 700, 1}, {1, 1, 600, 1}};
    EXPECT_EQ(stallTimes(rising, std::vector<double>{700}, 20, 1)[0].left, "up");
}

TEST(Features, StallsCanBeTimedByTheDeepestOrShallowestPoint)
{
    // A slab: its mean depth stays at 450-470 km, its tip (deepest point) reaches 640 km at step 1,
    // lies on 660 km to step 3 and falls through at step 4; its top stays at 300 km.
    const std::vector<TrackPoint> slab{{0, 0, 450, -2, 300, 560}, {1, 5, 460, -1, 300, 640},
                                       {2, 10, 465, -0.2, 300, 668}, {3, 15, 465, -0.1, 300, 700},
                                       {4, 20, 470, -3, 300, 900}};
    const std::vector<double> depths{300, 660};
    EXPECT_TRUE(stallTimes(slab, std::vector<double>{660}, 50, 4).empty()) << "the mean depth is never at 660 km";
    const auto byTip = stallTimes(slab, std::vector<double>{660}, 50, 4, StallMeasure::Deepest);
    ASSERT_EQ(byTip.size(), 1u);
    EXPECT_EQ(byTip[0].firstStep, 1);
    EXPECT_EQ(byTip[0].lastStep, 3);
    EXPECT_DOUBLE_EQ(byTip[0].durationMyr, 10.0);
    EXPECT_EQ(byTip[0].left, "down");
    const auto byTop = stallTimes(slab, depths, 10, 4, StallMeasure::Shallowest);
    ASSERT_EQ(byTop.size(), 1u);
    EXPECT_EQ(byTop[0].depthKm, 300);
    EXPECT_EQ(byTop[0].lastStep, 4);
    EXPECT_EQ(byTop[0].left, "");
    for (const StallMeasure m : kStallMeasures)
        EXPECT_EQ(parseStallMeasure(stallMeasureName(m)), m);
    EXPECT_THROW(parseStallMeasure("tip"), Error);
}

// Whether two steps' features are the same, bit for bit (labels, volumes, every variable's summary).
void expectSameFeatures(const StepFeatures& a, const StepFeatures& b, const dataset::Dataset& dataset)
{
    ASSERT_GT(a.features.size(), 0u);
    ASSERT_EQ(a.features.size(), b.features.size());
    for (size_t k = 0; k < a.features.size(); ++k) {
        EXPECT_EQ(a.features[k].points, b.features[k].points);
        EXPECT_EQ(a.features[k].volumeKm3, b.features[k].volumeKm3);
        ASSERT_EQ(a.features[k].variables.size(), dataset.variables().size());
        for (size_t v = 0; v < dataset.variables().size(); ++v) {
            const VariableSummary &x = a.features[k].variables[v], &y = b.features[k].variables[v];
            EXPECT_EQ(fmt::format("{} {} {}", x.mean, x.min, x.max), fmt::format("{} {} {}", y.mean, y.min, y.max))
                << "feature " << k + 1 << ", " << dataset.variables()[v].name;
        }
    }
    EXPECT_TRUE(std::equal(a.labels.begin(), a.labels.end(), b.labels.begin(), b.labels.end()));
}

// A step's features read the selected points alone: on a u16 dataset nothing is decoded whole (the
// anomalies' bases' shell means are kept in the manifest), no anomaly's array or bounds are computed,
// a brush on a stored variable or an anomaly decodes only what its bricks' bounds cannot rule out, and
// linking two steps reads the velocity near the features alone; the features and links are those of
// the steps decoded whole, bit for bit. A dataset written before the means were kept decodes the
// bases whole for them and gives the same features.
TEST(Features, AStepOfAU16DatasetDecodesOnlyWhatItsSelectedPointsNeed)
{
    const TempDir dir("features-u16");
    preprocess::PreprocessOptions o;
    o.quiet = true;
    o.sampleRows = 200;
    o.encoding = dataset::ValueEncoding::Uint16;
    o.pathlines.enabled = false;
    preprocess::preprocess(io::listSnapshotFiles({testing::contestLayoutDir()}), dir.path() / "ds", o);
    const auto dataset = dataset::Dataset::open(dir.path() / "ds");
    const int t = dataset->variableIndex("radial velocity");  // stored, no anomaly's base
    const int anomaly = dataset->variableIndex("temperature anomaly");
    ASSERT_GE(t, 0);
    ASSERT_GE(anomaly, 0);
    ASSERT_GE(dataset->steps().size(), 2u);
    const dataset::ValueRange range = dataset->steps()[0].stats[size_t(t)].range;
    const dataset::ValueRange cold = dataset->steps()[0].stats[size_t(anomaly)].range;
    // The faster half of the upwellings, below the top 100 km; the coldest third of the anomaly.
    const std::vector<std::vector<NamedRange>> brushes{
        {{"radial velocity", 0.5f * range.max, range.max}, {"depth", 100, 6371}},
        {{"temperature anomaly", cold.min, 0.66f * cold.min}, {"depth", 100, 6371}}};
    const FeatureOptions options = featureOptions(0, {660}, 50);
    const VelocityVariables velocity{size_t(dataset->variableIndex("vx")), size_t(dataset->variableIndex("vy")),
                                     size_t(dataset->variableIndex("vz"))};
    for (const auto& brush : brushes) {
        SCOPED_TRACE(brush[0].name);
        const auto filters = resolveRangeFilters(*dataset, brush);
        const auto lazy = dataset->load(0, 0), lazyNext = dataset->load(1, 0);
        const StepFeatures a = extractFeatures(*lazy, filters, options);
        const StepFeatures aNext = extractFeatures(*lazyNext, filters, options);
        const std::vector<FeatureLink> lazyLinks = linkFeatures(*lazy, a, aNext, velocity, 1.0);
        const auto whole = dataset->load(0, 0), wholeNext = dataset->load(1, 0);
        for (size_t v = 0; v < whole->variableCount(); ++v) {
            whole->values(v);
            wholeNext->values(v);
        }
        expectSameFeatures(a, extractFeatures(*whole, filters, options), *dataset);
        const StepFeatures bNext = extractFeatures(*wholeNext, filters, options);
        expectSameFeatures(aNext, bNext, *dataset);
        const std::vector<FeatureLink> wholeLinks = linkFeatures(*whole, a, bNext, velocity, 1.0);
        ASSERT_GT(wholeLinks.size(), 0u);
        ASSERT_EQ(lazyLinks.size(), wholeLinks.size());
        for (size_t k = 0; k < lazyLinks.size(); ++k)
            EXPECT_EQ(fmt::format("{} {} {}", lazyLinks[k].from, lazyLinks[k].to, lazyLinks[k].overlapKm3),
                      fmt::format("{} {} {}", wholeLinks[k].from, wholeLinks[k].to, wholeLinks[k].overlapKm3));
        for (size_t v = 0; v < lazy->variableCount(); ++v)
            if (lazy->computedFrom(v)) {
                EXPECT_FALSE(lazy->valuesReady(v)) << dataset->variables()[v].name << ": no array computed";
            }
        EXPECT_FALSE(lazy->valuesReady(size_t(t))) << "the brushed variable read brick by brick";
        EXPECT_EQ(lazy->decodedBytes(), 0u) << "nothing decoded whole, the velocity for linking neither";
    }

    // Without the kept means (a dataset written before): the bases decoded whole, the same features.
    nlohmann::json manifest = nlohmann::json::parse(readFile(dir.path() / "ds" / dataset::format::kManifest));
    for (nlohmann::json& step : manifest.at("steps"))
        ASSERT_EQ(step.erase("level_shell_means"), 1u);
    writeFileAtomic(dir.path() / "ds" / dataset::format::kManifest, manifest.dump(1));
    const auto before = dataset::Dataset::open(dir.path() / "ds");
    const auto filters = resolveRangeFilters(*before, brushes[1]);
    const auto lazy = before->load(0, 0), kept = dataset->load(0, 0);
    expectSameFeatures(extractFeatures(*lazy, filters, options), extractFeatures(*kept, filters, options), *before);
    std::set<size_t> bases;
    for (size_t v = 0; v < lazy->variableCount(); ++v)
        if (const dataset::ShellAnomalyOf* of = lazy->computedFrom(v))
            bases.insert(of->base);
    ASSERT_FALSE(bases.empty());
    EXPECT_EQ(lazy->decodedBytes(), bases.size() * lazy->grid().cellCount() * sizeof(float))
        << "decoded whole: the anomalies' bases alone";
}

}  // namespace
}  // namespace raypc::analysis
