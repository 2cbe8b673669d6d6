#include "analysis/selection.h"

#include "core/error.h"
#include "core/error_kinds.h"
#include "core/spherical.h"

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <type_traits>

namespace raypc::analysis {

std::vector<NamedRanges> groupRanges(std::span<const NamedRange> ranges, const std::string& what)
{
    std::vector<NamedRanges> groups;
    for (size_t i = 0; i < ranges.size(); ++i) {
        const NamedRange& r = ranges[i];
        if (!(r.min <= r.max))
            fail("{}[{}] ({}): min {} is greater than max {}", what, i, r.name, r.min, r.max);
        auto it = std::find_if(groups.begin(), groups.end(), [&](const NamedRanges& g) { return g.name == r.name; });
        if (it == groups.end())
            it = groups.insert(groups.end(), NamedRanges{r.name, {}});
        it->ranges.push_back({r.min, r.max});
    }
    return groups;
}

std::string selectionKey(std::span<const RangeFilter> filters)
{
    std::vector<std::string> axes;
    for (const RangeFilter& f : filters) {
        std::vector<dataset::ValueRange> ranges = f.ranges;
        std::sort(ranges.begin(), ranges.end(),
                  [](const auto& a, const auto& b) { return a.min < b.min || (a.min == b.min && a.max < b.max); });
        // Variables before coordinates, each by index; zero-padded so that text order is index order.
        std::string axis = f.coordinate ? fmt::format("c{:04}", int(*f.coordinate)) : fmt::format("v{:04}", f.variable);
        for (const dataset::ValueRange& r : ranges)
            axis += fmt::format(":{},{}", r.min, r.max);
        axes.push_back(std::move(axis));
    }
    std::sort(axes.begin(), axes.end());
    std::string key;
    for (const std::string& a : axes)
        key += a + '|';
    return key;
}

std::vector<RangeFilter> resolveRangeFilters(std::span<const std::string> variableNames,
                                             std::span<const NamedRange> ranges, const std::string& what)
{
    std::vector<RangeFilter> filters;
    for (NamedRanges& group : groupRanges(ranges, what)) {
        RangeFilter f;
        f.ranges = std::move(group.ranges);
        const std::string& name = group.name;
        if (const auto it = std::find(variableNames.begin(), variableNames.end(), name); it != variableNames.end()) {
            f.variable = int(it - variableNames.begin());
        } else if (const auto c = grid::findCoordinate(name)) {
            f.coordinate = c;
        } else {
            const size_t i = size_t(std::find_if(ranges.begin(), ranges.end(),
                                                 [&](const NamedRange& r) { return r.name == name; }) -
                                    ranges.begin());
            std::vector<std::string> coordinates;
            for (const auto& info : grid::coordinateInfos())
                coordinates.push_back(info.name);
            failUnknownName("{}[{}] ({}): unknown variable or coordinate '{}'; variables: {}; coordinates: {}", what, i, name,
                            name, fmt::join(variableNames, ", "), fmt::join(coordinates, ", "));
        }
        filters.push_back(std::move(f));
    }
    return filters;
}

std::vector<RangeFilter> resolveRangeFilters(const dataset::Dataset& dataset, std::span<const NamedRange> ranges,
                                             const std::string& what)
{
    const std::vector<std::string> names = dataset.variableNames();
    return resolveRangeFilters(std::span<const std::string>(names), ranges, what);
}

namespace {

void checkFilters(const dataset::StepVolume& volume, std::span<const RangeFilter> filters)
{
    for (const auto& f : filters) {
        if (!f.coordinate && (f.variable < 0 || static_cast<size_t>(f.variable) >= volume.variableCount()))
            fail("selection: variable index {} out of range 0..{}", f.variable, volume.variableCount() - 1);
        if (f.ranges.empty())
            fail("selection: a filter without ranges");
        for (const dataset::ValueRange& r : f.ranges)
            if (!(r.min <= r.max))
                fail("selection: range [{}, {}] has min > max", r.min, r.max);
    }
}

// Whether the grid point (iLat, iR, iLon) is selected: every filter holds at it.
bool pointSelected(const dataset::StepVolume& volume, std::span<const RangeFilter> filters, size_t iLat, size_t iR, size_t iLon)
{
    const auto& g = volume.grid();
    const size_t i = g.index(iLat, iR, iLon);
    for (const auto& f : filters) {
        const double v = f.coordinate ? grid::coordinateValue(*f.coordinate, g.latDeg[iLat], g.lonDeg[iLon], g.rKm[iR])
                                      : volume.values(f.variable)[i];
        if (!f.contains(v))
            return false;
    }
    return true;
}

}  // namespace

SelectionStats selectedVolume(const dataset::StepVolume& volume, std::span<const RangeFilter> filters,
                              std::optional<size_t> meanVariable)
{
    checkFilters(volume, filters);
    const auto& g = volume.grid();
    if (meanVariable && *meanVariable >= volume.variableCount())
        fail("mean variable: index {} of {} variables", *meanVariable, volume.variableCount());
    const float* values = meanVariable ? volume.values(*meanVariable) : nullptr;
    const auto w = g.volumeFactors();
    const double total = g.totalVolumeKm3();
    // Per radius: the selected volume and, with a mean variable, the volume-weighted sums of its
    // finite values over the selected points and over the shell, and the volumes they weigh.
    struct Sums {
        std::vector<double> volume, selectedSum, shellSum, selectedWeight, shellWeight;
    };
    const size_t n = g.nR(), m = values ? n : 0;
    // Sums per latitude row, added in row order afterwards: the same numbers whichever thread did
    // which row, so that an answer is the same bytes each time it is computed (kept answers equal
    // fresh ones: server/analysis_caches.h).
    std::vector<Sums> perRow(g.nLat());
    // The selection's loop as it was without a mean variable (the brushes' hot path: /api/selection
    // and the frame header ask on every release); the sums of the mean only when asked for.
    auto sumRow = [&](size_t iLat, auto withMean) {
        Sums& sums = perRow[iLat];
        sums = Sums{std::vector<double>(n, 0.0), std::vector<double>(m, 0.0), std::vector<double>(m, 0.0),
                    std::vector<double>(m, 0.0), std::vector<double>(m, 0.0)};
        for (size_t iR = 0; iR < n; ++iR)
            for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                const bool selected = pointSelected(volume, filters, iLat, iR, iLon);
                if constexpr (!withMean) {
                    if (selected)
                        sums.volume[iR] += w.at(iLat, iR, iLon);
                } else {
                    const double cell = w.at(iLat, iR, iLon);
                    if (selected)
                        sums.volume[iR] += cell;
                    const float v = values[g.index(iLat, iR, iLon)];
                    if (std::isfinite(v)) {
                        sums.shellSum[iR] += v * cell;
                        sums.shellWeight[iR] += cell;
                        if (selected) {
                            sums.selectedSum[iR] += v * cell;
                            sums.selectedWeight[iR] += cell;
                        }
                    }
                }
            }
    };
    tbb::parallel_for(size_t(0), g.nLat(), [&](size_t iLat) {
        if (values)
            sumRow(iLat, std::true_type{});
        else
            sumRow(iLat, std::false_type{});
    });
    SelectionStats stats;
    stats.volumeByRadiusKm3.assign(n, 0.0);
    Sums all{{}, std::vector<double>(m, 0.0), std::vector<double>(m, 0.0), std::vector<double>(m, 0.0),
             std::vector<double>(m, 0.0)};
    for (const Sums& sums : perRow) {
        for (size_t iR = 0; iR < n; ++iR)
            stats.volumeByRadiusKm3[iR] += sums.volume[iR];
        for (size_t iR = 0; iR < m; ++iR) {
            all.selectedSum[iR] += sums.selectedSum[iR];
            all.shellSum[iR] += sums.shellSum[iR];
            all.selectedWeight[iR] += sums.selectedWeight[iR];
            all.shellWeight[iR] += sums.shellWeight[iR];
        }
    }
    for (double v : stats.volumeByRadiusKm3)
        stats.volumeKm3 += v;
    double latSum = 0, lonSum = 0;
    for (double v : w.lat)
        latSum += v;
    for (double v : w.lon)
        lonSum += v;
    for (double rFactor : w.r)
        stats.shellVolumeByRadiusKm3.push_back(rFactor * latSum * lonSum);
    stats.fractionOfMantle = stats.volumeKm3 / total;
    for (size_t iR = 0; iR < m; ++iR) {
        stats.selectedMeanByRadius.push_back(all.selectedWeight[iR] > 0 ? all.selectedSum[iR] / all.selectedWeight[iR] : NAN);
        stats.shellMeanByRadius.push_back(all.shellWeight[iR] > 0 ? all.shellSum[iR] / all.shellWeight[iR] : NAN);
    }
    return stats;
}

HugePageVector<uint8_t> selectedPoints(const dataset::StepVolume& volume, std::span<const RangeFilter> filters,
                                       std::span<const uint8_t> radii)
{
    checkFilters(volume, filters);
    RAYPC_CHECK(radii.empty() || radii.size() == volume.grid().nR());
    const auto& g = volume.grid();
    const grid::BrickLayout& bricks = volume.bricks();
    // The rule of pointSelected, read so that what no point of a brick can pass is not decoded: a
    // stored variable's brick bounds (stored, or of its values) hold every value of the brick's points
    // (for u16 the decoded ones: value_encoding.h), so a brick whose bounds meet none of a filter's
    // ranges has no selected point; the other points read their values one by one (PointValues), so
    // that a variable is decoded only where its bricks may be selected. Coordinates first: cheaper.
    struct Axis {
        const RangeFilter* filter;
        std::optional<dataset::StepVolume::PointValues> values;
        const float* bounds = nullptr;  // a stored variable's
    };
    std::vector<Axis> axes;
    for (const RangeFilter& f : filters)
        if (f.coordinate)
            axes.push_back({&f, std::nullopt, nullptr});
    // A shell anomaly not computed yet: bounds from its base's and the shells' means
    // (shellAnomalyBrickBounds), when the means need no decoding of the base.
    std::vector<std::vector<float>> anomalyBounds;
    anomalyBounds.reserve(filters.size());  // pointers into it stay valid
    for (const RangeFilter& f : filters)
        if (!f.coordinate) {
            const size_t var = size_t(f.variable);
            const dataset::ShellAnomalyOf* of = volume.computedFrom(var);
            const float* bounds = nullptr;
            if (!of || volume.valuesReady(var)) {
                bounds = volume.brickBounds(var);
            } else if (volume.shellMeansReady(of->base)) {
                std::vector<float>& b = anomalyBounds.emplace_back(2 * bricks.brickCount());
                dataset::shellAnomalyBrickBounds(g, bricks, {volume.brickBounds(of->base), b.size()},
                                                 volume.shellMeansOf(of->base), of->kind, b);
                bounds = b.data();
            }
            axes.push_back({&f, volume.pointValues(var), bounds});
        }
    const auto mayHold = [&](size_t brick) {
        for (const Axis& a : axes) {
            if (!a.bounds)
                continue;
            const float lo = a.bounds[2 * brick], hi = a.bounds[2 * brick + 1];
            bool any = false;
            for (const dataset::ValueRange& r : a.filter->ranges)
                any = any || (hi >= r.min && lo <= r.max);
            if (!any)
                return false;
        }
        return true;
    };
    HugePageVector<uint8_t> out(g.cellCount(), 0);
    const size_t s = bricks.size;
    tbb::parallel_for(size_t(0), g.nLat(), [&](size_t iLat) {
        for (size_t iR = 0; iR < g.nR(); ++iR)
            for (uint32_t c = 0; c < bricks.count[2]; ++c) {
                if ((!radii.empty() && !radii[iR]) || !mayHold(bricks.index(uint32_t(iLat / s), uint32_t(iR / s), c)))
                    continue;
                const size_t end = std::min(size_t(c + 1) * s, g.nLon());
                for (size_t iLon = size_t(c) * s; iLon < end; ++iLon) {
                    const size_t i = g.index(iLat, iR, iLon);
                    bool selected = true;
                    for (const Axis& a : axes) {
                        const double v = a.values ? double(a.values->at(i, iLat, iR, iLon))
                                                  : grid::coordinateValue(*a.filter->coordinate, g.latDeg[iLat],
                                                                          g.lonDeg[iLon], g.rKm[iR]);
                        if (!a.filter->contains(v)) {
                            selected = false;
                            break;
                        }
                    }
                    out[i] = selected ? 1 : 0;
                }
            }
    });
    return out;
}

ClassVolumes selectedVolumeByClass(const dataset::StepVolume& volume, std::span<const RangeFilter> filters,
                                   std::span<const uint32_t> classes, size_t classCount)
{
    checkFilters(volume, filters);
    const auto& g = volume.grid();
    if (classes.size() != g.cellCount())
        fail("selection by class: {} classes for a grid of {} points, expected one per point", classes.size(),
             g.cellCount());
    for (size_t i = 0; i < classes.size(); ++i)
        if (classes[i] >= classCount)
            fail("selection by class: point {} has class {}, expected < {}", i, classes[i], classCount);
    const auto w = g.volumeFactors();
    struct Sums {
        std::vector<double> total, selected;
    };
    tbb::enumerable_thread_specific<Sums> perThread(Sums{std::vector<double>(classCount, 0.0), std::vector<double>(classCount, 0.0)});
    tbb::parallel_for(size_t(0), g.nLat(), [&](size_t iLat) {
        Sums& sums = perThread.local();
        for (size_t iR = 0; iR < g.nR(); ++iR)
            for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                const uint32_t c = classes[g.index(iLat, iR, iLon)];
                const double v = w.at(iLat, iR, iLon);
                sums.total[c] += v;
                if (pointSelected(volume, filters, iLat, iR, iLon))
                    sums.selected[c] += v;
            }
    });
    ClassVolumes out{std::vector<double>(classCount, 0.0), std::vector<double>(classCount, 0.0)};
    for (const Sums& sums : perThread)
        for (size_t c = 0; c < classCount; ++c) {
            out.totalKm3[c] += sums.total[c];
            out.selectedKm3[c] += sums.selected[c];
        }
    return out;
}

}  // namespace raypc::analysis

namespace raypc::analysis {

std::vector<StepSelection> selectionOverTime(const dataset::Dataset& dataset, std::span<const RangeFilter> filters, int level,
                                             int firstStep, int lastStep, const VolumeLoader& load,
                                             const std::function<void()>& onStep, std::optional<size_t> meanVariable)
{
    dataset.checkLevel(level);
    dataset.checkStep(firstStep);
    dataset.checkStep(lastStep);
    std::vector<StepSelection> out;
    for (int step = firstStep; step <= lastStep; ++step) {
        const auto volume = load ? load(step, level) : dataset.load(step, level);
        out.push_back({step, dataset.steps()[size_t(step)].timeMyr, selectedVolume(*volume, filters, meanVariable)});
        if (onStep)
            onStep();
    }
    return out;
}

}  // namespace raypc::analysis
