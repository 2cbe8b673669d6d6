#include "preprocess/preprocess_numerics.h"
#include "grid/variable_names.h"

#include "core/error.h"
#include "core/spherical.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <random>

namespace raypc::preprocess {

float toFloat32(double value)
{
    if (std::abs(value) > std::numeric_limits<float>::max())
        return std::copysign(std::numeric_limits<float>::infinity(), value);
    return static_cast<float>(value);
}

namespace {

// Appends "radial velocity" and "velocity magnitude" (cm/yr) from vx, vy, vz (m/s), which must exist.
void addVelocityVariables(grid::Snapshot& snapshot)
{
    const grid::Field* vx = snapshot.find(varname::kVelocity[0]);
    const grid::Field* vy = snapshot.find(varname::kVelocity[1]);
    const grid::Field* vz = snapshot.find(varname::kVelocity[2]);
    RAYPC_CHECK(vx && vy && vz);
    const auto& g = snapshot.grid;
    grid::Field radial{varname::kRadialVelocity, varname::kRadialVelocityUnits, std::vector<float>(g.cellCount()),
                 {varname::kRadialVelocityFrom.begin(), varname::kRadialVelocityFrom.end()}};
    grid::Field magnitude{varname::kVelocityMagnitude, varname::kVelocityMagnitudeUnits, std::vector<float>(g.cellCount()),
                    {varname::kVelocityMagnitudeFrom.begin(), varname::kVelocityMagnitudeFrom.end()}};
    const size_t nLon = g.nLon();
    tbb::parallel_for(size_t(0), g.nLat(), [&](size_t iLat) {
        const double lat = degToRad(g.latDeg[iLat]);
        // The outward unit vector is the same on every shell of a column: found once per column,
        // then the shells row by row (points in memory order).
        std::vector<double> ux(nLon), uy(nLon), uz(nLon);
        for (size_t iLon = 0; iLon < nLon; ++iLon) {
            const double lon = degToRad(g.lonDeg[iLon]);
            ux[iLon] = std::cos(lat) * std::cos(lon);
            uy[iLon] = std::cos(lat) * std::sin(lon);
            uz[iLon] = std::sin(lat);
        }
        for (size_t iR = 0; iR < g.nR(); ++iR) {
            const size_t first = g.index(iLat, iR, 0);
            const float *x = vx->values.data() + first, *y = vy->values.data() + first, *z = vz->values.data() + first;
            float *r = radial.values.data() + first, *m = magnitude.values.data() + first;
            for (size_t iLon = 0; iLon < nLon; ++iLon) {
                const double a = x[iLon], b = y[iLon], c = z[iLon];
                r[iLon] = toFloat32((a * ux[iLon] + b * uy[iLon] + c * uz[iLon]) * kMpsToCmPerYr);
                m[iLon] = toFloat32(std::sqrt(a * a + b * b + c * c) * kMpsToCmPerYr);
            }
        }
    });
    snapshot.fields.push_back(std::move(radial));
    snapshot.fields.push_back(std::move(magnitude));
}

}  // namespace

void addStoredDerivedVariables(grid::Snapshot& snapshot)
{
    if (varname::hasVelocity([&](const char* c) { return snapshot.find(c) != nullptr; }))
        addVelocityVariables(snapshot);
}

std::vector<dataset::BaseVariable> baseVariables(const grid::Snapshot& snapshot)
{
    std::vector<dataset::BaseVariable> out;
    for (const grid::Field& f : snapshot.fields)
        out.push_back({f.name, f.units, !f.derivedFrom.empty()});
    return out;
}

void addDerivedVariables(grid::Snapshot& snapshot)
{
    addStoredDerivedVariables(snapshot);
    const auto& g = snapshot.grid;
    const size_t stored = snapshot.fields.size();
    std::map<size_t, std::vector<double>> means;
    for (const dataset::ShellAnomalyVariable& v : dataset::shellAnomalyVariables(baseVariables(snapshot))) {
        const grid::Field& base = snapshot.fields[v.of.base];
        auto m = means.find(v.of.base);
        if (m == means.end())
            m = means.emplace(v.of.base, dataset::shellMeans(g, base.values)).first;
        if (v.of.kind == dataset::ShellAnomalyKind::Percent && !dataset::shellMeansPositive(m->second))
            continue;
        grid::Field field{v.name, v.units, std::vector<float>(g.cellCount()), {base.name}};
        dataset::computeShellAnomaly(g, snapshot.fields[v.of.base].values, m->second, v.of.kind, field.values);
        snapshot.fields.push_back(std::move(field));
    }
    RAYPC_CHECK(snapshot.fields.size() >= stored);
}

namespace {

// coarsenField's means of one coarse row (cLat, cR) whose fine points come from the N fine rows
// `rows` (lat, then r order) with weights wRow (w.lat · w.r of each): each coarse point adds its
// fine points in coarsenField's order (lat, r, lon) with the same weights, w.lat · w.r · w.lon.
// Why by rows: the weights of a row are found once, not three lookups and two products per point.
template <size_t N>
void coarsenRow(const std::array<const float*, 4>& rows, const std::array<double, 4>& wRow, const double* wLon,
                size_t nLon, size_t coarseLon, float* out)
{
    // The coarse points of two fine columns each, in a loop of a fixed body that the compiler
    // vectorises; then a last one of one column (an odd count).
    const size_t pairs = nLon / 2;
    for (size_t cLon = 0; cLon < pairs; ++cLon) {
        double sum = 0, weight = 0;
        for (size_t j = 0; j < N; ++j) {
            const double w0 = wRow[j] * wLon[2 * cLon], w1 = wRow[j] * wLon[2 * cLon + 1];
            sum += w0 * rows[j][2 * cLon];
            weight += w0;
            sum += w1 * rows[j][2 * cLon + 1];
            weight += w1;
        }
        out[cLon] = static_cast<float>(sum / weight);
    }
    for (size_t cLon = pairs; cLon < coarseLon; ++cLon) {
        const size_t lon0 = 2 * cLon, lon1 = std::min(lon0 + 2, nLon);
        double sum = 0, weight = 0;
        for (size_t j = 0; j < N; ++j)
            for (size_t iLon = lon0; iLon < lon1; ++iLon) {
                const double wi = wRow[j] * wLon[iLon];
                sum += wi * rows[j][iLon];
                weight += wi;
            }
        out[cLon] = static_cast<float>(sum / weight);
    }
}

}  // namespace

std::vector<float> coarsenField(const grid::SphericalGrid& fine, std::span<const float> values)
{
    RAYPC_CHECK_EQ(values.size(), fine.cellCount());
    const grid::SphericalGrid coarse = fine.coarsened();
    const auto w = fine.volumeFactors();
    std::vector<float> out(coarse.cellCount());
    tbb::parallel_for(size_t(0), coarse.nLat(), [&](size_t cLat) {
        const size_t lat0 = 2 * cLat, lat1 = std::min(lat0 + 2, fine.nLat());
        for (size_t cR = 0; cR < coarse.nR(); ++cR) {
            const size_t r0 = 2 * cR, r1 = std::min(r0 + 2, fine.nR());
            // The fine rows this coarse row merges, in the order their points are added.
            std::array<const float*, 4> rows{};
            std::array<double, 4> wRow{};
            size_t n = 0;
            for (size_t iLat = lat0; iLat < lat1; ++iLat)
                for (size_t iR = r0; iR < r1; ++iR) {
                    rows[n] = values.data() + fine.index(iLat, iR, 0);
                    wRow[n++] = w.lat[iLat] * w.r[iR];
                }
            float* row = out.data() + coarse.index(cLat, cR, 0);
            switch (n) {
            case 4: coarsenRow<4>(rows, wRow, w.lon.data(), fine.nLon(), coarse.nLon(), row); break;
            case 2: coarsenRow<2>(rows, wRow, w.lon.data(), fine.nLon(), coarse.nLon(), row); break;
            default: coarsenRow<1>(rows, wRow, w.lon.data(), fine.nLon(), coarse.nLon(), row); break;
            }
        }
    });
    return out;
}

namespace {

// A lat row's sums in computeStats.
struct StatsPartial {
    double weighted = 0, weight = 0, missing = 0;
    size_t missingPoints = 0;
};

// How many lat rows statsOfRows sums side by side.
constexpr size_t kStatsRowsAtOnce = 4;

// computeStats' sums of the N lat rows from firstLat on, into rows[iLat] and the row's histogram
// (kHistogramBins doubles from histograms + iLat · kHistogramBins). Each row adds its points in its
// own order (r, then lon), as one row alone would: the same bits for any N. Why N rows at once: a
// row's sums are chains of dependent additions (a histogram bin's through a store and a load), so
// one row alone waits on each addition; N rows' chains, interleaved point by point, overlap.
template <size_t N>
void statsOfRows(const grid::SphericalGrid& grid, const grid::SphericalGrid::VolumeFactors& w, const float* values,
                 float lo, double scale, size_t firstLat, StatsPartial* rows, double* histograms)
{
    const size_t nR = grid.nR(), nLon = grid.nLon(), rowSize = nR * nLon;
    std::array<StatsPartial, N> p{};
    std::array<double*, N> histogram;
    for (size_t j = 0; j < N; ++j)
        histogram[j] = histograms + (firstLat + j) * dataset::kHistogramBins;
    for (size_t iR = 0; iR < nR; ++iR) {
        std::array<double, N> wRow;
        std::array<const float*, N> row;
        for (size_t j = 0; j < N; ++j) {
            wRow[j] = w.lat[firstLat + j] * w.r[iR];
            row[j] = values + (firstLat + j) * rowSize + iR * nLon;
        }
        for (size_t iLon = 0; iLon < nLon; ++iLon)
            for (size_t j = 0; j < N; ++j) {
                const float x = row[j][iLon];
                const double wi = wRow[j] * w.lon[iLon];
                if (std::isnan(x)) {
                    p[j].missing += wi;  // the statistics are of the values there are
                    ++p[j].missingPoints;
                    continue;
                }
                // In double: the difference of two finite floats may overflow float.
                const int bin = std::min(dataset::kHistogramBins - 1, static_cast<int>((double(x) - lo) * scale));
                histogram[j][bin] += wi;
                p[j].weighted += wi * x;
                p[j].weight += wi;
            }
    }
    for (size_t j = 0; j < N; ++j)
        rows[firstLat + j] = p[j];
}

}  // namespace

dataset::VariableStats computeStats(const grid::SphericalGrid& grid, std::span<const float> values)
{
    RAYPC_CHECK_EQ(values.size(), grid.cellCount());
    const auto w = grid.volumeFactors();
    const auto extremes = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, values.size(), 1 << 16), std::pair<float, float>(INFINITY, -INFINITY),
        [&](const auto& range, std::pair<float, float> acc) {
            // Four running extremes (chains a quarter as long); their lowest and highest have the
            // bits of one std::min/std::max after another unless they are a zero, whose sign
            // depends on the order: then the range is gone over again in order.
            std::array<float, 4> lo, hi;
            lo.fill(acc.first);
            hi.fill(acc.second);
            size_t i = range.begin();
            for (; i + 4 <= range.end(); i += 4)
                for (size_t j = 0; j < 4; ++j) {
                    const float x = values[i + j];
                    lo[j] = x < lo[j] ? x : lo[j];
                    hi[j] = hi[j] < x ? x : hi[j];
                }
            for (; i != range.end(); ++i) {
                lo[0] = std::min(lo[0], values[i]);
                hi[0] = std::max(hi[0], values[i]);
            }
            const float first = acc.first, second = acc.second;
            for (size_t j = 0; j < 4; ++j) {
                acc.first = std::min(acc.first, lo[j]);
                acc.second = std::max(acc.second, hi[j]);
            }
            if (acc.first == 0 || acc.second == 0) {
                acc = {first, second};
                for (size_t k = range.begin(); k != range.end(); ++k) {
                    acc.first = std::min(acc.first, values[k]);
                    acc.second = std::max(acc.second, values[k]);
                }
            }
            return acc;
        },
        [](auto a, auto b) { return std::pair(std::min(a.first, b.first), std::max(a.second, b.second)); });
    // Named copies, not structured bindings: clang 14 (the fuzzing build) cannot capture those.
    const float lo = extremes.first, hi = extremes.second;

    // Callers check that values are finite or missing (checkFinite): an infinite range has no bins. A
    // field missing everywhere (a derived one whose inputs are) has no statistics.
    if (!(lo <= hi))
        fail("every value is missing: no statistics");
    RAYPC_CHECK(std::isfinite(lo) && std::isfinite(hi));
    dataset::VariableStats stats;
    stats.range = {lo, hi};
    const double span = static_cast<double>(hi) - lo;
    const double scale = span > 0 ? dataset::kHistogramBins / span : 0.0;
    // One partial sum per lat row, added in row order: the sums do not depend on how rows were
    // spread over threads, so a rerun writes the same bytes (dataset.json is reproducible).
    std::vector<StatsPartial> rows(grid.nLat());
    std::vector<double> rowHistograms(grid.nLat() * dataset::kHistogramBins, 0.0);
    // Rows kStatsRowsAtOnce at a time (statsOfRows); a last group of fewer one at a time.
    const size_t groups = (grid.nLat() + kStatsRowsAtOnce - 1) / kStatsRowsAtOnce;
    tbb::parallel_for(size_t(0), groups, [&](size_t group) {
        const size_t first = group * kStatsRowsAtOnce;
        if (first + kStatsRowsAtOnce <= grid.nLat()) {
            statsOfRows<kStatsRowsAtOnce>(grid, w, values.data(), lo, scale, first, rows.data(), rowHistograms.data());
            return;
        }
        for (size_t iLat = first; iLat < grid.nLat(); ++iLat)
            statsOfRows<1>(grid, w, values.data(), lo, scale, iLat, rows.data(), rowHistograms.data());
    });
    stats.histogram.assign(dataset::kHistogramBins, 0.0);
    double weighted = 0, weight = 0, missing = 0;
    for (size_t iLat = 0; iLat < grid.nLat(); ++iLat) {
        for (int b = 0; b < dataset::kHistogramBins; ++b)
            stats.histogram[b] += rowHistograms[iLat * dataset::kHistogramBins + b];
        weighted += rows[iLat].weighted;
        weight += rows[iLat].weight;
        missing += rows[iLat].missing;
        stats.missingPoints += rows[iLat].missingPoints;
    }
    stats.missingFraction = missing / (missing + weight);
    for (double& h : stats.histogram)
        h /= weight;
    stats.mean = weighted / weight;
    return stats;
}

dataset::VariableStats statsOverSteps(std::span<const dataset::VariableStats> perStep)
{
    RAYPC_CHECK(!perStep.empty());
    dataset::VariableStats global;
    global.range = perStep.front().range;
    double mean = 0;
    for (const auto& st : perStep) {
        global.range.min = std::min(global.range.min, st.range.min);
        global.range.max = std::max(global.range.max, st.range.max);
        mean += st.mean / perStep.size();
        global.missingFraction += st.missingFraction / double(perStep.size());
        global.missingPoints = std::max(global.missingPoints, st.missingPoints);
    }
    global.mean = mean;
    global.histogram.assign(dataset::kHistogramBins, 0.0);
    for (const auto& st : perStep)
        rebinHistogram(st, global.range, global.histogram);
    for (double& h : global.histogram)
        h /= perStep.size();
    return global;
}

std::vector<uint32_t> drawVolumeWeightedSample(const grid::SphericalGrid& grid, size_t rows, uint64_t seed)
{
    // Dual-cell volumes factor into lat, r and lon parts, so drawing each index independently
    // from its own factor draws grid points with probability proportional to volume.
    const auto w = grid.volumeFactors();
    std::mt19937_64 rng(seed);
    std::discrete_distribution<size_t> lat(w.lat.begin(), w.lat.end());
    std::discrete_distribution<size_t> r(w.r.begin(), w.r.end());
    std::discrete_distribution<size_t> lon(w.lon.begin(), w.lon.end());
    std::vector<uint32_t> cells(rows);
    for (auto& c : cells) {
        const size_t iLat = lat(rng), iR = r(rng), iLon = lon(rng);
        c = static_cast<uint32_t>(grid.index(iLat, iR, iLon));
    }
    std::sort(cells.begin(), cells.end());
    return cells;
}

std::vector<float> sampleCoordinates(const grid::SphericalGrid& grid, std::span<const uint32_t> cells)
{
    const auto& coordinates = grid::coordinateInfos();
    const size_t nc = coordinates.size();
    std::vector<float> out(cells.size() * nc);
    for (size_t i = 0; i < cells.size(); ++i) {
        const size_t c = cells[i];
        const size_t iLon = c % grid.nLon(), iR = (c / grid.nLon()) % grid.nR(), iLat = c / (grid.nLon() * grid.nR());
        for (size_t k = 0; k < nc; ++k)
            out[i * nc + k] =
                static_cast<float>(grid::coordinateValue(coordinates[k].id, grid.latDeg[iLat], grid.lonDeg[iLon], grid.rKm[iR]));
    }
    return out;
}

void rebinHistogram(const dataset::VariableStats& stats, dataset::ValueRange range, std::span<double> histogram)
{
    const size_t nOut = histogram.size();
    const size_t nIn = stats.histogram.size();
    const double outLo = range.min, outSpan = static_cast<double>(range.max) - range.min;
    const double inLo = stats.range.min, inSpan = static_cast<double>(stats.range.max) - stats.range.min;
    auto outBin = [&](double v) {
        if (outSpan <= 0)
            return size_t(0);
        return std::min(nOut - 1, static_cast<size_t>(std::max(0.0, (v - outLo) / outSpan * nOut)));
    };
    for (size_t b = 0; b < nIn; ++b) {
        const double mass = stats.histogram[b];
        if (mass == 0)
            continue;
        if (inSpan <= 0 || outSpan <= 0) {
            histogram[outBin(inLo)] += mass;
            continue;
        }
        const double a = inLo + inSpan * b / nIn, c = inLo + inSpan * (b + 1) / nIn;
        const size_t first = outBin(a), last = outBin(c);
        for (size_t o = first; o <= last; ++o) {
            const double oLo = outLo + outSpan * o / nOut, oHi = outLo + outSpan * (o + 1) / nOut;
            const double overlap = std::min(c, oHi) - std::max(a, oLo);
            if (overlap > 0)
                histogram[o] += mass * overlap / (c - a);
        }
    }
}

}  // namespace raypc::preprocess
