// The features of a selection followed through a series of steps: each step's features
// linked to the previous step's (linkFeatures), their tracks (FeatureTracker), events and stall
// times, kept in one object that `raypc features` writes as CSV and the server's POST /api/features
// answers as JSON. docs/features.md gives the rules.
//
// Thread safety: none; one series is built by one thread, step after step.
#pragma once

#include "dataset/dataset.h"
#include "analysis/features.h"

#include <map>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

namespace raypc::analysis {

// The variable indices of vx, vy, vz (m/s), which linking moves the features with. Throws
// raypc::Error naming `what` and the missing component.
VelocityVariables velocityVariables(const dataset::Dataset& dataset, const char* what);

class FeatureSeries {
public:
    // `dataset` must outlive the series. Throws raypc::Error (velocityVariables, naming `what`) when
    // it has no velocity to link steps with.
    FeatureSeries(const dataset::Dataset& dataset, double minOverlapShare, const char* what = "tracking");

    // Adds the next step's features (steps in increasing order, each once; labels not used) with the
    // links from the previous step's features (forEachBlockStep's: linkFeatures over the steps'
    // interval with velocity(); empty for the first step), found by this process or another.
    void addLinked(int step, const StepFeatures& features, const std::vector<FeatureLink>& links);
    const VelocityVariables& velocity() const { return m_velocity; }

    // A feature of a track in one step.
    struct Row {
        int track = 0, step = 0;
        double timeMyr = 0;
        Feature feature;
    };
    // In the order added: step after step, each step's features by id.
    const std::vector<Row>& rows() const { return m_rows; }
    // Births, deaths, merges and splits found so far (FeatureTracker::events).
    const std::vector<TrackEvent>& events() const { return m_tracker.events(); }
    // The feature `id` of `step` as added. Throws raypc::Error when there is none.
    const Feature& feature(int step, int id) const;
    // Each track's points in step order, by track id.
    const std::map<int, std::vector<TrackPoint>>& trackPoints() const { return m_points; }
    // The stalls of every track at `depthsKm` (stallTimes), in track order: (track, stall).
    std::vector<std::pair<int, Stall>> stalls(std::span<const double> depthsKm, double halfWidthKm,
                                              int seriesLastStep,
                                              StallMeasure measure = StallMeasure::MeanDepth) const;

private:
    const dataset::Dataset& m_dataset;
    VelocityVariables m_velocity;
    std::optional<size_t> m_radialVelocity;  // variable index, for the stalls' speeds
    FeatureTracker m_tracker;
    std::vector<Row> m_rows;
    std::map<std::pair<int, int>, size_t> m_rowOf;  // (step, feature id) -> index into m_rows
    std::map<int, std::vector<TrackPoint>> m_points;
};

}  // namespace raypc::analysis
