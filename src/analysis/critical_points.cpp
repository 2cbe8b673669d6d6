#include "analysis/critical_points.h"

#include "core/error.h"
#include "grid/triangulation.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>

namespace raypc::analysis {
namespace {

using grid::triangulation::kLinkSize;
using grid::triangulation::linkTables;
using grid::triangulation::VertexMasks;
using grid::triangulation::vertexMasks;

void checkInput(const grid::SphericalGrid& grid, std::span<const float> values)
{
    grid::triangulation::checkTriangulable(grid, values.size(), "critical points");
}

}  // namespace

std::optional<CriticalKind> classifyLink(int lower, int upper)
{
    if (lower == 0)
        return CriticalKind::Minimum;
    if (upper == 0)
        return CriticalKind::Maximum;
    if (lower == 1 && upper == 1)
        return std::nullopt;
    if (upper == 1)
        return CriticalKind::Saddle1;
    if (lower == 1)
        return CriticalKind::Saddle2;
    return CriticalKind::MultiSaddle;
}

const char* criticalKindName(CriticalKind kind)
{
    switch (kind) {
    case CriticalKind::Minimum: return "minimum";
    case CriticalKind::Saddle1: return "1-saddle";
    case CriticalKind::Saddle2: return "2-saddle";
    case CriticalKind::Maximum: return "maximum";
    case CriticalKind::MultiSaddle: return "multi-saddle";
    }
    return "?";
}

std::vector<CriticalPoint> findCriticalPoints(const grid::SphericalGrid& grid, std::span<const float> values)
{
    checkInput(grid, values);
    const auto& tables = linkTables();
    tbb::enumerable_thread_specific<std::vector<CriticalPoint>> found;
    tbb::parallel_for(size_t(0), grid.nLat(), [&](size_t iLat) {
        auto& out = found.local();
        for (size_t iR = 0; iR < grid.nR(); ++iR)
            for (size_t iLon = 0; iLon < grid.nLon(); ++iLon) {
                const VertexMasks m = vertexMasks(grid, values.data(), iLat, iR, iLon);
                const int lower = tables.components[m.lower];
                const int upper = tables.components[m.valid & ~m.lower];
                const auto kind = classifyLink(lower, upper);
                if (!kind)
                    continue;
                CriticalPoint p;
                p.index = grid.index(iLat, iR, iLon);
                p.kind = *kind;
                p.value = values[p.index];
                p.lowerComponents = static_cast<uint8_t>(lower);
                p.upperComponents = static_cast<uint8_t>(upper);
                p.latDeg = grid.latDeg[iLat];
                p.rKm = grid.rKm[iR];
                p.lonDeg = grid.lonDeg[iLon];
                out.push_back(p);
            }
    });
    std::vector<CriticalPoint> all;
    for (auto& part : found)
        all.insert(all.end(), part.begin(), part.end());
    std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.index < b.index; });
    return all;
}

const char* seedRuleName(SeedRule rule)
{
    return rule == SeedRule::Persistence ? "persistence" : "value";
}

SeedRule parseSeedRule(const std::string& text)
{
    for (const SeedRule rule : {SeedRule::Persistence, SeedRule::Value})
        if (text == seedRuleName(rule))
            return rule;
    fail("--cp-select: unknown rule '{}', expected persistence or value", text);
}

void parsePersistenceThreshold(const std::string& text, CriticalPointFilter& filter)
{
    const bool percent = !text.empty() && text.back() == '%';
    const std::string number = percent ? text.substr(0, text.size() - 1) : text;
    double value = 0;
    const auto [end, ec] = std::from_chars(number.data(), number.data() + number.size(), value);
    if (number.empty() || ec != std::errc() || end != number.data() + number.size() || !(value >= 0) ||
        (percent && value > 100))
        fail("--cp-persistence: '{}' is not a persistence threshold; expected a number >= 0 in the field's units "
             "(e.g. 30) or a percentage of the step's range from 0% to 100% (e.g. 5%)",
             text);
    filter.minPersistence = percent ? value / 100 : value;
    filter.persistenceIsFraction = percent;
}

void checkCriticalPointFilter(const CriticalPointFilter& filter)
{
    if (!(filter.minPersistence >= 0) || (filter.persistenceIsFraction && filter.minPersistence > 1))
        fail("--cp-persistence: need a threshold >= 0 (and at most 100% of the range), got {}{}",
             filter.persistenceIsFraction ? filter.minPersistence * 100 : filter.minPersistence,
             filter.persistenceIsFraction ? "%" : "");
    if (!(filter.minAbsValue >= 0) || !(filter.minFractionOfMaxAbs >= 0 && filter.minFractionOfMaxAbs <= 1))
        fail("critical-point threshold: need --cp-min-abs >= 0 and --cp-min-fraction within [0, 1], got {} and {}",
             filter.minAbsValue, filter.minFractionOfMaxAbs);
    if (filter.maxCount == 0)
        fail("--cp-max-count: must be at least 1");
}

double significanceThreshold(const CriticalPointFilter& filter, double maxAbs)
{
    return std::max(filter.minAbsValue, filter.minFractionOfMaxAbs * maxAbs);
}

std::vector<CriticalPoint> selectSignificant(std::vector<CriticalPoint> points, double maxAbs,
                                             const CriticalPointFilter& filter)
{
    const double threshold = significanceThreshold(filter, maxAbs);
    std::erase_if(points, [&](const CriticalPoint& p) {
        switch (p.kind) {
        case CriticalKind::Maximum: return !(p.value >= threshold);
        case CriticalKind::Minimum: return !(p.value <= -threshold);
        default: return !filter.saddles || !(std::abs(p.value) >= threshold);
        }
    });
    std::sort(points.begin(), points.end(), [](const CriticalPoint& a, const CriticalPoint& b) {
        const float x = std::abs(a.value), y = std::abs(b.value);
        return x != y ? x > y : a.index < b.index;
    });
    if (points.size() > filter.maxCount)
        points.resize(filter.maxCount);
    return points;
}

int lowerStarEulerContribution(const grid::SphericalGrid& grid, std::span<const float> values, size_t index)
{
    checkInput(grid, values);
    const auto& tables = linkTables();
    const size_t iLon = index % grid.nLon(), iR = (index / grid.nLon()) % grid.nR(),
                 iLat = index / (grid.nLon() * grid.nR());
    const uint32_t lower = vertexMasks(grid, values.data(), iLat, iR, iLon).lower;
    int vertices = std::popcount(lower), edges = 0, triangles = 0;
    for (int a = 0; a < kLinkSize; ++a)
        if (lower >> a & 1)
            edges += std::popcount(uint32_t(tables.adjacency[a]) & lower);
    edges /= 2;
    for (const auto& t : tables.triangles)
        if ((lower >> t[0] & 1) && (lower >> t[1] & 1) && (lower >> t[2] & 1))
            ++triangles;
    return 1 - (vertices - edges + triangles);
}

}  // namespace raypc::analysis
