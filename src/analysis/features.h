// Features of a selection: the connected regions of the selected grid
// points of one step, each measured — volume, depth extent, centroid, every variable's mean, min and
// max, and how much of it lies near chosen depths (so "how much of this slab is within 50 km of
// 660 km" is a number). docs/features.md gives the definitions.
//
// Connectivity: two selected grid points belong to one feature when they are neighbours in the
// 26-neighbourhood of (lat, r, lon) index space, with the longitude seam joined (column nLon-1 next
// to column 0) and, at each pole, every point of the outermost lat row joined with every other of
// that row at the same or a neighbouring radius (the row's dual cells meet in the polar cap).
//
// Thread safety: pure functions of their arguments.
#pragma once

#include "core/huge_pages.h"
#include "dataset/dataset.h"
#include "analysis/selection.h"

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace raypc::analysis {

struct FeatureOptions {
    // Features of a smaller volume (km³) are dropped (specks); their points are labelled 0.
    double minVolumeKm3 = 0;
    // Depths (km) whose neighbourhood each feature reports its share in: the points within
    // ±bandHalfWidthKm of each depth (by the points' own depths).
    std::vector<double> bandDepthsKm{410, 660, 1000, 1600};
    double bandHalfWidthKm = 50;
};

struct VariableSummary {
    double mean = 0;  // weighted by the points' dual-cell volumes; NaN if no finite value
    double min = 0, max = 0;
};

struct Feature {
    int id = 0;  // 1.. in order of decreasing volume
    size_t points = 0;
    double volumeKm3 = 0;         // sum of its points' dual-cell volumes
    double fractionOfMantle = 0;  // of the grid's whole shell
    double topDepthKm = 0, bottomDepthKm = 0;  // shallowest and deepest of its points
    // Volume-weighted centroid: the mean of the points' Cartesian positions, as latitude,
    // longitude in [0, 360) and depth of that point (inside a curved feature it lies deeper than
    // the feature; the depth of the mean radius is meanDepthKm).
    double centroidLatDeg = 0, centroidLonDeg = 0, centroidDepthKm = 0;
    double meanDepthKm = 0;                  // volume-weighted mean of the points' depths
    std::vector<VariableSummary> variables;  // one per variable of the volume, in its order
    std::vector<double> bandFractions;       // per FeatureOptions::bandDepthsKm: share of its volume
};

struct StepFeatures {
    std::vector<Feature> features;  // by decreasing volume
    // Per grid point (canonical order): the id of its feature, 0 when unselected or dropped.
    HugePageVector<int32_t> labels;
};

// The options of feature settings however they are given (a state's `features`, through
// state::featureOptions; the command line's options; Python's arguments): minimum volume (km³),
// depths (km) and their band's half-width (km). Checks nothing (extractFeatures does).
FeatureOptions featureOptions(double minVolumeKm3, std::vector<double> depthsKm, double bandHalfWidthKm);

// Throws raypc::Error as selectedVolume does (filters), and for a negative minimum volume or band
// half-width. An empty selection gives no features.
StepFeatures extractFeatures(const dataset::StepVolume& volume, std::span<const RangeFilter> filters,
                             const FeatureOptions& options = {});

// Linking the features of two consecutive steps. Every point of a feature of the earlier step is
// moved with the flow over the interval — one midpoint (second-order Runge–Kutta) step in the
// earlier step's velocity (three variables in m/s: x, y, z components, sampled as the probe and
// pathlines sample) — and the feature of the later step labelled at the grid point nearest to where
// it lands gets the point's dual-cell volume as overlap. Moving the points, not comparing bare
// positions, keeps a fast small feature linked to itself. A point carried outside the mantle shell
// counts for no feature.
struct FeatureLink {
    int from = 0, to = 0;    // feature ids of the earlier and the later step
    double overlapKm3 = 0;   // the earlier feature's volume carried onto the later one
};
struct VelocityVariables {
    size_t x = 0, y = 0, z = 0;  // variable indices of vx, vy, vz (m/s)
};
std::vector<FeatureLink> linkFeatures(const dataset::StepVolume& earlier, const StepFeatures& a, const StepFeatures& b,
                                      const VelocityVariables& velocity, double intervalMyr);

// Features followed through a series of steps (tracks) and what happens to them (events).
// A link counts when its overlap is at least `minOverlapShare` of the earlier feature's volume or
// of the later one's. A later feature continues the track of the earlier feature that gives it the
// largest overlap when that earlier feature's largest overlap is this later feature (mutual best);
// otherwise it starts a track. Events: birth (a later feature without a link, not in the first
// step), death (an earlier feature without a link, not in the last step), merge (a later feature
// with two or more links), split (an earlier feature with two or more links). Ties of overlap go to
// the smaller feature id.
struct TrackEvent {
    enum class Kind { Birth, Death, Merge, Split };
    Kind kind = Kind::Birth;
    int step = 0;      // the step where it shows: birth and merge the later step, death and split the earlier
    int feature = 0;   // the feature of that step
    int track = 0;     // its track
    std::vector<int> others;  // merge: the earlier features; split: the later features
};
const char* trackEventName(TrackEvent::Kind kind);

// Stall times: how long a track stays at a depth. A track's feature is "at" depth D in a step when
// its measured depth (StallMeasure: its volume-weighted mean depth, its deepest point — a sinking
// slab's tip — or its shallowest — a rising plume's head) lies within ±halfWidthKm of D; each run of
// consecutive steps of the track at D is one stall, from its first to its last step (a stall of one
// step lasts 0 Myr: the steps are the resolution), with the mean of the feature's mean radial
// velocity over the run, and how it ended: "down" or "up" (the track's next step measures deeper or
// shallower than the band), "ended" (the track has no next step: it died or merged) or "" (still
// there at the last step).
enum class StallMeasure { MeanDepth, Deepest, Shallowest };
inline constexpr std::array<StallMeasure, 3> kStallMeasures{StallMeasure::MeanDepth, StallMeasure::Deepest,
                                                            StallMeasure::Shallowest};
std::string_view stallMeasureName(StallMeasure measure);  // "mean-depth", "deepest", "shallowest"
// Throws raypc::Error naming `name` and the measures.
StallMeasure parseStallMeasure(std::string_view name);

struct TrackPoint {
    int step = 0;
    double timeMyr = 0, meanDepthKm = 0;
    double radialVelocityCmPerYr = 0;  // NaN when the dataset has none
    double topDepthKm = 0, bottomDepthKm = 0;  // the feature's shallowest and deepest points
    double depthKm(StallMeasure measure) const;
};
struct Stall {
    double depthKm = 0;
    int firstStep = 0, lastStep = 0;
    double durationMyr = 0;
    double meanRadialVelocityCmPerYr = 0;
    std::string left;  // "down", "up", "ended" or ""
};
// `points` in step order, consecutive steps of one track; `seriesLastStep`: the last step asked.
std::vector<Stall> stallTimes(std::span<const TrackPoint> points, std::span<const double> depthsKm, double halfWidthKm,
                              int seriesLastStep, StallMeasure measure = StallMeasure::MeanDepth);

class FeatureTracker {
public:
    explicit FeatureTracker(double minOverlapShare = 0.1) : m_minShare(minOverlapShare) {}
    // Adds the next step's features, with the links from the previous step's (empty for the first).
    // Returns the track of each of its features (index id - 1).
    std::vector<int> add(int step, const StepFeatures& features, const std::vector<FeatureLink>& links);
    // Deaths are known once the next step is added: call after the last step (its features do not die).
    const std::vector<TrackEvent>& events() const { return m_events; }

private:
    double m_minShare;
    int m_tracks = 0;
    int m_previousStep = -1;
    std::vector<double> m_previousVolumes;  // by feature id - 1
    std::vector<int> m_previousTracks;
    std::vector<TrackEvent> m_events;
};

}  // namespace raypc::analysis
