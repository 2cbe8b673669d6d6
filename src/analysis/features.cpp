#include "analysis/features.h"

#include "core/error.h"
#include "core/spherical.h"
#include "grid/coordinates.h"
#include "grid/sampler.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <string>
#include <utility>

namespace raypc::analysis {
namespace {

// Union-find over the selected points, numbered 0, 1, ... in index order (selectedNumbers): the root
// of a set is its smallest number, so its smallest index; memory in the selected points, not the grid's.
class DisjointSets {
public:
    explicit DisjointSets(size_t n) : m_parent(n) { std::iota(m_parent.begin(), m_parent.end(), int64_t(0)); }

    int64_t find(int64_t x)
    {
        while (m_parent[size_t(x)] != x) {
            m_parent[size_t(x)] = m_parent[size_t(m_parent[size_t(x)])];  // path halving
            x = m_parent[size_t(x)];
        }
        return x;
    }
    void unite(int64_t a, int64_t b)
    {
        a = find(a);
        b = find(b);
        if (a == b)
            return;
        if (a < b)
            std::swap(a, b);
        m_parent[size_t(a)] = b;
    }

private:
    std::vector<int64_t> m_parent;
};

// Each selected point's number + 1 in `numbers` (0 where not selected), in index order; returns how many.
size_t selectedNumbers(const HugePageVector<uint8_t>& selected, HugePageVector<int32_t>& numbers)
{
    numbers.assign(selected.size(), 0);
    size_t n = 0;
    for (size_t i = 0; i < selected.size(); ++i)
        if (selected[i]) {
            if (n >= size_t(std::numeric_limits<int32_t>::max()))
                fail("features: more than {} selected points", std::numeric_limits<int32_t>::max());
            numbers[i] = int32_t(++n);
        }
    return n;
}

struct Sums {
    size_t points = 0;
    double volume = 0, x = 0, y = 0, z = 0, depth = 0;
    double top = std::numeric_limits<double>::infinity(), bottom = -std::numeric_limits<double>::infinity();
    std::vector<double> sum, weight, min, max;  // per variable
    std::vector<double> band;                   // per band depth
};

// Connected components of the selected points (`numbers`: selectedNumbers): each selected point joins
// its 13 forward neighbours of the 26-neighbourhood (the other 13 join it), the lon index wrapping at
// the seam.
DisjointSets connectNeighbours(const grid::SphericalGrid& g, const HugePageVector<int32_t>& numbers, size_t count)
{
    const size_t nLat = g.nLat(), nR = g.nR(), nLon = g.nLon();
    DisjointSets sets(count);
    for (size_t iLat = 0; iLat < nLat; ++iLat)
        for (size_t iR = 0; iR < nR; ++iR)
            for (size_t iLon = 0; iLon < nLon; ++iLon) {
                const size_t i = g.index(iLat, iR, iLon);
                if (!numbers[i])
                    continue;
                for (int dLat = 0; dLat <= 1; ++dLat)
                    for (int dR = -1; dR <= 1; ++dR)
                        for (int dLon = -1; dLon <= 1; ++dLon) {
                            if (dLat == 0 && (dR < 0 || (dR == 0 && dLon <= 0)))
                                continue;  // backward neighbours and the point itself
                            const int64_t jLat = int64_t(iLat) + dLat, jR = int64_t(iR) + dR;
                            if (jLat >= int64_t(nLat) || jR < 0 || jR >= int64_t(nR))
                                continue;
                            const size_t jLon = size_t((int64_t(iLon) + dLon + int64_t(nLon)) % int64_t(nLon));
                            const size_t j = g.index(size_t(jLat), size_t(jR), jLon);
                            if (numbers[j])
                                sets.unite(numbers[i] - 1, numbers[j] - 1);
                        }
            }
    return sets;
}

// Around each pole: the outermost row's points at one radius and the next are one region.
void joinPoleRings(const grid::SphericalGrid& g, const HugePageVector<int32_t>& numbers, DisjointSets& sets)
{
    const size_t nLat = g.nLat(), nR = g.nR(), nLon = g.nLon();
    for (const size_t iLat : {size_t(0), nLat - 1}) {
        int64_t previous = -1;  // a selected point of the ring at the radius below
        for (size_t iR = 0; iR < nR; ++iR) {
            int64_t anchor = -1;
            for (size_t iLon = 0; iLon < nLon; ++iLon) {
                const size_t i = g.index(iLat, iR, iLon);
                if (!numbers[i])
                    continue;
                if (anchor < 0)
                    anchor = numbers[i] - 1;
                sets.unite(anchor, numbers[i] - 1);
            }
            if (anchor >= 0 && previous >= 0)
                sets.unite(anchor, previous);
            previous = anchor;
        }
    }
}

// Labels in index order (a set's root, its smallest index, is met first): each selected point's set
// numbered from 1 in `labels` (which hold selectedNumbers before), and the sums of each set (by
// label - 1) over its points.
std::vector<Sums> labelAndSum(const dataset::StepVolume& volume, DisjointSets& sets, size_t count,
                              const FeatureOptions& options, HugePageVector<int32_t>& labels)
{
    const grid::SphericalGrid& g = volume.grid();
    const size_t nLat = g.nLat(), nR = g.nR(), nLon = g.nLon();
    std::vector<int32_t> rootLabel(count, 0);  // by a root's number
    std::vector<Sums> sums;
    const auto w = g.volumeFactors();
    const size_t nVar = volume.variableCount();
    // Read at the selected points alone: what no selected point holds is not decoded or computed.
    std::vector<dataset::StepVolume::PointValues> values;
    for (size_t k = 0; k < nVar; ++k)
        values.push_back(volume.pointValues(k));
    const size_t nBands = options.bandDepthsKm.size();
    for (size_t iLat = 0; iLat < nLat; ++iLat)
        for (size_t iR = 0; iR < nR; ++iR) {
            const double depth = grid::coordinateValue(grid::Coordinate::Depth, 0.0, 0.0, g.rKm[iR]);
            for (size_t iLon = 0; iLon < nLon; ++iLon) {
                const size_t i = g.index(iLat, iR, iLon);
                if (!labels[i])
                    continue;
                const int64_t number = labels[i] - 1, root = sets.find(number);
                if (root == number) {
                    sums.emplace_back();
                    Sums& s = sums.back();
                    s.sum.assign(nVar, 0.0);
                    s.weight.assign(nVar, 0.0);
                    s.min.assign(nVar, std::numeric_limits<double>::infinity());
                    s.max.assign(nVar, -std::numeric_limits<double>::infinity());
                    s.band.assign(nBands, 0.0);
                    rootLabel[size_t(number)] = int32_t(sums.size());
                }
                labels[i] = rootLabel[size_t(root)];
                Sums& s = sums[size_t(labels[i]) - 1];
                const double v = w.at(iLat, iR, iLon);
                const Vec3d p = sphericalToCartesianKm(g.latDeg[iLat], g.lonDeg[iLon], g.rKm[iR]);
                ++s.points;
                s.volume += v;
                s.x += v * p.x;
                s.y += v * p.y;
                s.z += v * p.z;
                s.depth += v * depth;
                s.top = std::min(s.top, depth);
                s.bottom = std::max(s.bottom, depth);
                for (size_t k = 0; k < nVar; ++k) {
                    const double x = values[k].at(i, iLat, iR, iLon);
                    if (!std::isfinite(x))
                        continue;
                    s.sum[k] += v * x;
                    s.weight[k] += v;
                    s.min[k] = std::min(s.min[k], x);
                    s.max[k] = std::max(s.max[k], x);
                }
                for (size_t b = 0; b < nBands; ++b)
                    if (std::abs(depth - options.bandDepthsKm[b]) <= options.bandHalfWidthKm)
                        s.band[b] += v;
            }
        }
    return sums;
}

// Features by decreasing volume (ties: the one met first in index order first), specks dropped, into
// `out`; its labels renumbered to the features' ids (0 where a speck was).
void rankFeatures(const std::vector<Sums>& sums, const grid::SphericalGrid& g, size_t nVar, const FeatureOptions& options,
                  StepFeatures& out)
{
    const size_t nBands = options.bandDepthsKm.size();
    std::vector<size_t> order(sums.size());
    std::iota(order.begin(), order.end(), size_t(0));
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return sums[a].volume > sums[b].volume; });
    std::vector<int32_t> newId(sums.size() + 1, 0);
    const double total = g.totalVolumeKm3();
    for (const size_t k : order) {
        const Sums& s = sums[k];
        if (s.volume < options.minVolumeKm3)
            continue;
        Feature f;
        f.id = int(out.features.size()) + 1;
        newId[k + 1] = f.id;
        f.points = s.points;
        f.volumeKm3 = s.volume;
        f.fractionOfMantle = s.volume / total;
        f.topDepthKm = s.top;
        f.bottomDepthKm = s.bottom;
        const SphericalPoint c = cartesianToSpherical({s.x / s.volume, s.y / s.volume, s.z / s.volume});
        f.centroidLatDeg = c.latDeg;
        f.centroidLonDeg = c.lonDeg;
        f.centroidDepthKm = grid::coordinateValue(grid::Coordinate::Depth, 0.0, 0.0, c.rKm);
        f.meanDepthKm = s.depth / s.volume;
        for (size_t v = 0; v < nVar; ++v)
            f.variables.push_back(s.weight[v] > 0 ? VariableSummary{s.sum[v] / s.weight[v], s.min[v], s.max[v]}
                                                  : VariableSummary{std::nan(""), std::nan(""), std::nan("")});
        for (size_t b = 0; b < nBands; ++b)
            f.bandFractions.push_back(s.band[b] / s.volume);
        out.features.push_back(std::move(f));
    }
    for (int32_t& label : out.labels)
        label = newId[size_t(label)];
}

}  // namespace

FeatureOptions featureOptions(double minVolumeKm3, std::vector<double> depthsKm, double bandHalfWidthKm)
{
    FeatureOptions o;
    o.minVolumeKm3 = minVolumeKm3;
    o.bandDepthsKm = std::move(depthsKm);
    o.bandHalfWidthKm = bandHalfWidthKm;
    return o;
}

StepFeatures extractFeatures(const dataset::StepVolume& volume, std::span<const RangeFilter> filters, const FeatureOptions& options)
{
    if (!(options.minVolumeKm3 >= 0))
        fail("features: minimum volume {} km³ is negative", options.minVolumeKm3);
    if (!(options.bandHalfWidthKm >= 0))
        fail("features: band half-width {} km is negative", options.bandHalfWidthKm);
    const HugePageVector<uint8_t> selected = selectedPoints(volume, filters);  // checks the filters
    const grid::SphericalGrid& g = volume.grid();
    StepFeatures out;
    const size_t count = selectedNumbers(selected, out.labels);
    DisjointSets sets = connectNeighbours(g, out.labels, count);
    joinPoleRings(g, out.labels, sets);
    const std::vector<Sums> sums = labelAndSum(volume, sets, count, options, out.labels);
    rankFeatures(sums, g, volume.variableCount(), options, out);
    return out;
}

std::vector<FeatureLink> linkFeatures(const dataset::StepVolume& earlier, const StepFeatures& a, const StepFeatures& b,
                                      const VelocityVariables& velocity, double intervalMyr)
{
    const grid::SphericalGrid& g = earlier.grid();
    if (a.labels.size() != g.cellCount() || b.labels.size() != g.cellCount())
        fail("features: linking steps of {} and {} points on a grid of {}", a.labels.size(), b.labels.size(),
             g.cellCount());
    for (const size_t v : {velocity.x, velocity.y, velocity.z})
        if (v >= earlier.variableCount())
            fail("features: velocity variable index {} out of range 0..{}", v, earlier.variableCount() - 1);
    const grid::GridSampler sampler(g);
    const double kmPerMps = intervalMyr * kSecondsPerMyr * 1e-3;  // displacement (km) of 1 m/s over the interval
    // The velocity read in the bricks the features' displacements sample alone: no component decoded
    // whole, and a point the sampler's corners come back to decoded once (per thread).
    struct Velocity {
        dataset::BrickCachedValues x, y, z;
    };
    tbb::enumerable_thread_specific<Velocity> velocities([&] {
        return Velocity{{earlier, velocity.x}, {earlier, velocity.y}, {earlier, velocity.z}};
    });
    auto at = [](dataset::BrickCachedValues& v) {
        return [p = &v](size_t iLat, size_t iR, size_t iLon) { return p->at(iLat, iR, iLon); };
    };
    // The velocity (km over the interval) at a Cartesian point, or nullopt outside the shell.
    auto displacement = [&](Velocity& v, const Vec3d& p) -> std::optional<Vec3d> {
        const SphericalPoint s = cartesianToSpherical(p);
        const auto where = sampler.locate(s.latDeg, s.lonDeg, s.rKm);
        if (!where)
            return std::nullopt;
        return Vec3d{sampler.sample(at(v.x), *where), sampler.sample(at(v.y), *where), sampler.sample(at(v.z), *where)} *
               kmPerMps;
    };
    // Where each feature point of `a` lands in `b` (its label there, 0 for none), rows in parallel;
    // then the overlaps summed in index order, as one thread would: the same bits.
    std::vector<std::vector<int32_t>> landsIn(g.nLat());
    tbb::parallel_for(size_t(0), g.nLat(), [&](size_t iLat) {
        Velocity& v = velocities.local();
        std::vector<int32_t>& row = landsIn[iLat];
        for (size_t iR = 0; iR < g.nR(); ++iR)
            for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                const size_t i = g.index(iLat, iR, iLon);
                if (a.labels[i] == 0)
                    continue;
                row.push_back(0);
                const Vec3d p = sphericalToCartesianKm(g.latDeg[iLat], g.lonDeg[iLon], g.rKm[iR]);
                const auto d0 = displacement(v, p);
                if (!d0)
                    continue;
                const auto d1 = displacement(v, p + *d0 * 0.5);
                if (!d1)
                    continue;
                const SphericalPoint q = cartesianToSpherical(p + *d1);
                const auto to = sampler.locate(q.latDeg, q.lonDeg, q.rKm);
                if (!to)
                    continue;
                const size_t jLat = to->tLat < 0.5 ? to->lat0 : to->lat1, jR = to->tR < 0.5 ? to->r0 : to->r1,
                             jLon = to->tLon < 0.5 ? to->lon0 : to->lon1;
                row.back() = b.labels[g.index(jLat, jR, jLon)];
            }
    });
    const auto w = g.volumeFactors();
    std::map<std::pair<int, int>, double> overlap;
    for (size_t iLat = 0; iLat < g.nLat(); ++iLat) {
        auto next = landsIn[iLat].begin();
        for (size_t iR = 0; iR < g.nR(); ++iR)
            for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                const size_t i = g.index(iLat, iR, iLon);
                if (a.labels[i] == 0)
                    continue;
                const int to = *next++;
                if (to != 0)
                    overlap[{a.labels[i], to}] += w.at(iLat, iR, iLon);
            }
    }
    std::vector<FeatureLink> links;
    for (const auto& [key, km3] : overlap)
        links.push_back({key.first, key.second, km3});
    return links;
}

const char* trackEventName(TrackEvent::Kind kind)
{
    switch (kind) {
    case TrackEvent::Kind::Birth: return "birth";
    case TrackEvent::Kind::Death: return "death";
    case TrackEvent::Kind::Merge: return "merge";
    case TrackEvent::Kind::Split: return "split";
    }
    return "birth";
}

std::vector<int> FeatureTracker::add(int step, const StepFeatures& features, const std::vector<FeatureLink>& allLinks)
{
    const size_t n = features.features.size(), m = m_previousVolumes.size();
    // The links that count.
    std::vector<FeatureLink> links;
    for (const FeatureLink& l : allLinks) {
        if (l.from < 1 || size_t(l.from) > m || l.to < 1 || size_t(l.to) > n)
            fail("features: a link from feature {} to {} with {} and {} features", l.from, l.to, m, n);
        const double share = std::max(l.overlapKm3 / m_previousVolumes[size_t(l.from) - 1],
                                      l.overlapKm3 / features.features[size_t(l.to) - 1].volumeKm3);
        if (share >= m_minShare)
            links.push_back(l);
    }
    // Each side's links and best partner (largest overlap; ties: the smaller id, as links are sorted).
    std::vector<std::vector<int>> incoming(n), outgoing(m);
    std::vector<int> bestIn(n, 0), bestOut(m, 0);
    std::vector<double> bestInKm3(n, 0), bestOutKm3(m, 0);
    for (const FeatureLink& l : links) {
        const size_t to = size_t(l.to) - 1, from = size_t(l.from) - 1;
        incoming[to].push_back(l.from);
        outgoing[from].push_back(l.to);
        if (l.overlapKm3 > bestInKm3[to]) {
            bestInKm3[to] = l.overlapKm3;
            bestIn[to] = l.from;
        }
        if (l.overlapKm3 > bestOutKm3[from]) {
            bestOutKm3[from] = l.overlapKm3;
            bestOut[from] = l.to;
        }
    }
    std::vector<int> tracks(n, 0);
    for (size_t k = 0; k < n; ++k) {
        const int id = int(k) + 1;
        const int from = bestIn[k];
        if (from != 0 && bestOut[size_t(from) - 1] == id)
            tracks[k] = m_previousTracks[size_t(from) - 1];
        else
            tracks[k] = ++m_tracks;
        if (incoming[k].empty() && m_previousStep >= 0)
            m_events.push_back({TrackEvent::Kind::Birth, step, id, tracks[k], {}});
        if (incoming[k].size() >= 2)
            m_events.push_back({TrackEvent::Kind::Merge, step, id, tracks[k], incoming[k]});
    }
    for (size_t k = 0; k < m; ++k) {
        if (outgoing[k].empty())
            m_events.push_back({TrackEvent::Kind::Death, m_previousStep, int(k) + 1, m_previousTracks[k], {}});
        if (outgoing[k].size() >= 2)
            m_events.push_back({TrackEvent::Kind::Split, m_previousStep, int(k) + 1, m_previousTracks[k], outgoing[k]});
    }
    m_previousStep = step;
    m_previousVolumes.clear();
    for (const Feature& f : features.features)
        m_previousVolumes.push_back(f.volumeKm3);
    m_previousTracks = tracks;
    return tracks;
}

std::string_view stallMeasureName(StallMeasure measure)
{
    switch (measure) {
    case StallMeasure::MeanDepth: return "mean-depth";
    case StallMeasure::Deepest: return "deepest";
    case StallMeasure::Shallowest: return "shallowest";
    }
    return "?";
}

StallMeasure parseStallMeasure(std::string_view name)
{
    for (const StallMeasure m : kStallMeasures)
        if (name == stallMeasureName(m))
            return m;
    fail("stall measure '{}': expected mean-depth, deepest or shallowest", name);
}

double TrackPoint::depthKm(StallMeasure measure) const
{
    switch (measure) {
    case StallMeasure::Deepest: return bottomDepthKm;
    case StallMeasure::Shallowest: return topDepthKm;
    case StallMeasure::MeanDepth: break;
    }
    return meanDepthKm;
}

std::vector<Stall> stallTimes(std::span<const TrackPoint> points, std::span<const double> depthsKm, double halfWidthKm,
                              int seriesLastStep, StallMeasure measure)
{
    std::vector<Stall> stalls;
    for (const double depth : depthsKm) {
        auto at = [&](size_t k) { return std::abs(points[k].depthKm(measure) - depth) <= halfWidthKm; };
        for (size_t k = 0; k < points.size();) {
            if (!at(k)) {
                ++k;
                continue;
            }
            size_t end = k;
            double velocity = 0;
            while (end < points.size() && at(end))
                velocity += points[end++].radialVelocityCmPerYr;
            Stall s;
            s.depthKm = depth;
            s.firstStep = points[k].step;
            s.lastStep = points[end - 1].step;
            s.durationMyr = points[end - 1].timeMyr - points[k].timeMyr;
            s.meanRadialVelocityCmPerYr = velocity / double(end - k);
            if (end < points.size())
                s.left = points[end].depthKm(measure) > depth ? "down" : "up";
            else if (s.lastStep < seriesLastStep)
                s.left = "ended";
            stalls.push_back(s);
            k = end;
        }
    }
    return stalls;
}

}  // namespace raypc::analysis
