#include "dataset/shell_anomaly.h"

#include "core/error.h"
#include "grid/variable_names.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace raypc::dataset {

std::string_view shellAnomalyKindName(ShellAnomalyKind kind)
{
    return kind == ShellAnomalyKind::Difference ? "anomaly" : "anomaly %";
}

std::optional<ShellAnomalyKind> parseShellAnomalyKind(std::string_view text)
{
    for (const ShellAnomalyKind k : {ShellAnomalyKind::Difference, ShellAnomalyKind::Percent})
        if (text == shellAnomalyKindName(k))
            return k;
    return std::nullopt;
}

std::vector<ShellAnomalyVariable> shellAnomalyVariables(std::span<const BaseVariable> variables)
{
    const auto exists = [&](const std::string& name) {
        return std::any_of(variables.begin(), variables.end(), [&](const BaseVariable& v) { return v.name == name; });
    };
    // The temperature whose anomaly is named "temperature anomaly": the first of the table's sources
    // the model has, when it has no temperature anomaly of its own.
    std::string temperature;
    if (!exists(varname::kTemperatureAnomaly))
        for (const char* source : varname::kTemperatureAnomalyFrom)
            if (exists(source)) {
                temperature = source;
                break;
            }
    const std::string_view suffix = varname::kShellAnomalySuffix;
    std::vector<ShellAnomalyVariable> anomalies, percents;
    for (size_t i = 0; i < variables.size(); ++i) {
        const BaseVariable& v = variables[i];
        if (v.derived || varname::isVelocityComponent(v.name) || v.name.find("anomaly") != std::string::npos)
            continue;
        // The name the anomaly goes by ("temperature anomaly" for ASPECT's T), and so its percentage's.
        const std::string anomaly = v.name == temperature ? std::string(varname::kTemperatureAnomaly) : v.name + std::string(suffix);
        const std::string stem = anomaly.substr(0, anomaly.size() - suffix.size());
        if (!exists(anomaly))
            anomalies.push_back({anomaly, v.units, {i, ShellAnomalyKind::Difference}});
        const std::string percent = stem + varname::kShellAnomalyPercentSuffix;
        if (!exists(percent))
            percents.push_back({percent, varname::kShellAnomalyPercentUnits, {i, ShellAnomalyKind::Percent}});
    }
    anomalies.insert(anomalies.end(), percents.begin(), percents.end());
    return anomalies;
}

double shellMean(const grid::SphericalGrid::VolumeFactors& w, const float* shell, size_t rowStride)
{
    double sum = 0, area = 0;
    for (size_t iLat = 0; iLat < w.lat.size(); ++iLat) {
        const float* row = shell + iLat * rowStride;
        for (size_t iLon = 0; iLon < w.lon.size(); ++iLon)
            if (std::isfinite(row[iLon])) {
                const double a = w.lat[iLat] * w.lon[iLon];
                sum += a * row[iLon];
                area += a;
            }
    }
    return area > 0 ? sum / area : std::numeric_limits<double>::quiet_NaN();
}

namespace {

// shellMean of N shells, each adding its points in shellMean's order, interleaved point by point.
template <size_t N>
void shellMeansOf(const grid::SphericalGrid::VolumeFactors& w, const float* const* shells, size_t rowStride,
                  double* means)
{
    std::array<double, N> sum{}, area{};
    for (size_t iLat = 0; iLat < w.lat.size(); ++iLat)
        for (size_t iLon = 0; iLon < w.lon.size(); ++iLon)
            for (size_t k = 0; k < N; ++k) {
                const float x = shells[k][iLat * rowStride + iLon];
                if (std::isfinite(x)) {
                    const double a = w.lat[iLat] * w.lon[iLon];
                    sum[k] += a * x;
                    area[k] += a;
                }
            }
    for (size_t k = 0; k < N; ++k)
        means[k] = area[k] > 0 ? sum[k] / area[k] : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

void shellMeansSideBySide(const grid::SphericalGrid::VolumeFactors& w, const float* const* shells, size_t count,
                          size_t rowStride, double* means)
{
    size_t k = 0;
    for (; k + kShellsAtOnce <= count; k += kShellsAtOnce)
        shellMeansOf<kShellsAtOnce>(w, shells + k, rowStride, means + k);
    for (; k < count; ++k)
        shellMeansOf<1>(w, shells + k, rowStride, means + k);
}

std::vector<double> shellMeans(const grid::SphericalGrid& g, std::span<const float> values)
{
    RAYPC_CHECK_EQ(values.size(), g.cellCount());
    const auto w = g.volumeFactors();
    std::vector<double> means(g.nR());
    const size_t groups = (g.nR() + kShellsAtOnce - 1) / kShellsAtOnce;
    tbb::parallel_for(size_t(0), groups, [&](size_t group) {
        const size_t first = group * kShellsAtOnce, count = std::min(kShellsAtOnce, g.nR() - first);
        std::array<const float*, kShellsAtOnce> shells{};
        for (size_t k = 0; k < count; ++k)
            shells[k] = values.data() + g.index(0, first + k, 0);
        shellMeansSideBySide(w, shells.data(), count, g.nR() * g.nLon(), means.data() + first);
    });
    return means;
}

bool shellMeansPositive(std::span<const double> means)
{
    return std::all_of(means.begin(), means.end(), [](double m) { return std::isnan(m) || m > 0; });
}

float shellAnomalyValue(float x, double mean, ShellAnomalyKind kind)
{
    const double d = double(x) - mean;
    const double v = kind == ShellAnomalyKind::Difference ? d : 100.0 * d / mean;
    if (std::abs(v) > double(std::numeric_limits<float>::max()))
        return std::copysign(std::numeric_limits<float>::infinity(), v);
    return static_cast<float>(v);
}

void computeShellAnomaly(const grid::SphericalGrid& g, std::span<const float> values, std::span<const double> means,
                         ShellAnomalyKind kind, std::span<float> out)
{
    RAYPC_CHECK_EQ(values.size(), g.cellCount());
    RAYPC_CHECK_EQ(out.size(), g.cellCount());
    RAYPC_CHECK_EQ(means.size(), g.nR());
    RAYPC_CHECK(values.data() != out.data());  // a row may be computed again from its values
    tbb::parallel_for(size_t(0), g.nLat(), [&](size_t iLat) {
        for (size_t iR = 0; iR < g.nR(); ++iR) {
            const size_t first = g.index(iLat, iR, 0);
            const float* x = values.data() + first;
            float* row = out.data() + first;
            // shellAnomalyValue's arithmetic in a loop the compiler vectorises, for the row's one
            // mean and kind; a row with a value beyond float32 goes through shellAnomalyValue
            // itself (its infinity, where a plain conversion may round down to the largest float).
            const double mean = means[iR];
            int beyond = 0;
            if (kind == ShellAnomalyKind::Difference)
                for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                    const double v = double(x[iLon]) - mean;
                    beyond |= std::abs(v) > double(std::numeric_limits<float>::max());
                    row[iLon] = static_cast<float>(v);
                }
            else
                for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                    const double v = 100.0 * (double(x[iLon]) - mean) / mean;
                    beyond |= std::abs(v) > double(std::numeric_limits<float>::max());
                    row[iLon] = static_cast<float>(v);
                }
            if (beyond)
                for (size_t iLon = 0; iLon < g.nLon(); ++iLon)
                    row[iLon] = shellAnomalyValue(x[iLon], mean, kind);
        }
    });
}

void shellAnomalyBrickBounds(const grid::SphericalGrid& g, const grid::BrickLayout& layout,
                             std::span<const float> baseBounds, std::span<const double> means, ShellAnomalyKind kind,
                             std::span<float> out)
{
    RAYPC_CHECK_EQ(baseBounds.size(), 2 * layout.brickCount());
    RAYPC_CHECK_EQ(out.size(), 2 * layout.brickCount());
    RAYPC_CHECK_EQ(means.size(), g.nR());
    const size_t s = layout.size, nR = g.nR();
    for (size_t b = 0; b < layout.brickCount(); ++b) {
        const size_t bR = (b / layout.count[2]) % layout.count[1];
        const float lo = baseBounds[2 * b], hi = baseBounds[2 * b + 1];
        float outLo = std::numeric_limits<float>::infinity(), outHi = -outLo;
        // Radii [bR*s, (bR+1)*s] inclusive, clamped at the grid's end: the shells the brick covers.
        for (size_t iR = bR * s; lo <= hi && iR <= std::min((bR + 1) * s, nR - 1); ++iR) {
            if (std::isnan(means[iR]))
                continue;  // the shell's anomaly is NaN: never selected
            // Increasing in x for a positive mean (and a difference), decreasing for a negative one.
            const float a = shellAnomalyValue(lo, means[iR], kind), c = shellAnomalyValue(hi, means[iR], kind);
            outLo = std::min({outLo, a, c});
            outHi = std::max({outHi, a, c});
        }
        out[2 * b] = outLo;
        out[2 * b + 1] = outHi;
    }
}

}  // namespace raypc::dataset
