#include "grid/snapshot.h"

#include "core/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <cmath>

namespace raypc::grid {

const Field* Snapshot::find(const std::string& name) const
{
    for (const auto& f : fields)
        if (f.name == name)
            return &f;
    return nullptr;
}

Field* Snapshot::find(const std::string& name)
{
    for (auto& f : fields)
        if (f.name == name)
            return &f;
    return nullptr;
}

void checkGridFitsMemory(const SphericalGrid& grid, uint64_t neededBytes, const std::string& file,
                         const std::string& purpose, const AvailableMemory& available)
{
    const uint64_t points = uint64_t(grid.nLat()) * grid.nR() * grid.nLon();
    if (points > kMaxGridPoints)
        fail("{}: grid {}x{}x{} (lat x r x lon) has {} points, more than the {} RayPC can index", file, grid.nLat(),
             grid.nR(), grid.nLon(), points, kMaxGridPoints);
    if (neededBytes > available.bytes)
        fail("{}: grid {}x{}x{} (lat x r x lon) needs {} of memory to {}, {} available ({})", file, grid.nLat(),
             grid.nR(), grid.nLon(), formatBytes(neededBytes), purpose, formatBytes(available.bytes),
             available.limitedBy);
}

void fillMissingByShellMean(const SphericalGrid& grid, std::vector<float>& values, const std::string& what,
                            const std::function<bool(size_t iLat, size_t iLon)>& holdsData)
{
    for (size_t iR = 0; iR < grid.nR(); ++iR) {
        double sum = 0;
        size_t count = 0, missing = 0;
        for (size_t iLat = 0; iLat < grid.nLat(); ++iLat)
            for (size_t iLon = 0; iLon < grid.nLon(); ++iLon) {
                if (holdsData && !holdsData(iLat, iLon))
                    continue;
                const float v = values[grid.index(iLat, iR, iLon)];
                std::isnan(v) ? ++missing : (sum += v, ++count);
            }
        if (missing == 0)
            continue;
        if (count == 0)
            fail("{}: every value on the shell r = {} km is missing", what, grid.rKm[iR]);
        const float mean = static_cast<float>(sum / double(count));
        for (size_t iLat = 0; iLat < grid.nLat(); ++iLat)
            for (size_t iLon = 0; iLon < grid.nLon(); ++iLon)
                if (float& v = values[grid.index(iLat, iR, iLon)]; std::isnan(v) && (!holdsData || holdsData(iLat, iLon)))
                    v = mean;
    }
}

std::string describeGridPoint(const SphericalGrid& grid, size_t index)
{
    const size_t iLon = index % grid.nLon(), iR = index / grid.nLon() % grid.nR(), iLat = index / grid.nLon() / grid.nR();
    return fmt::format("lat {:g}°, r {:g} km, lon {:g}° (point {}, {}, {} of lat, r, lon ascending)", grid.latDeg[iLat],
                       grid.rKm[iR], grid.lonDeg[iLon], iLat, iR, iLon);
}

void checkFinite(const Snapshot& snapshot, const Field& field, const std::string& source)
{
    // NaN is a missing value (of the input, or of a derived field's input there); an infinity, or a NaN
    // computed from inputs that all have values, is a failure.
    std::vector<const Field*> sources;
    for (const auto& name : field.derivedFrom)
        if (const Field* f = snapshot.find(name))
            sources.push_back(f);
    // Finite values never fail: whole chunks of them are passed over by a branch-free (vectorised)
    // test, and the first chunk holding another value is searched from its start.
    constexpr size_t kChunk = 4096;
    const size_t n = field.values.size();
    size_t start = 0;
    for (; start < n; start += kChunk) {
        int nonFinite = 0;
        for (size_t i = start; i < std::min(start + kChunk, n); ++i)
            nonFinite |= !(std::abs(field.values[i]) <= std::numeric_limits<float>::max());
        if (nonFinite)
            break;
    }
    const auto bad = std::find_if(field.values.begin() + ptrdiff_t(std::min(start, n)), field.values.end(), [&](const float& v) {
        if (std::isinf(v))
            return true;
        if (!std::isnan(v) || sources.empty())
            return false;
        const size_t i = static_cast<size_t>(&v - field.values.data());
        return std::all_of(sources.begin(), sources.end(), [&](const Field* f) { return std::isfinite(f->values[i]); });
    });
    if (bad == field.values.end())
        return;
    const size_t i = static_cast<size_t>(bad - field.values.begin());
    std::string inputs;
    for (const auto& name : field.derivedFrom)
        if (const Field* f = snapshot.find(name))
            inputs += fmt::format("{}{} = {:g} {}", inputs.empty() ? "" : ", ", name, f->values[i], f->units);
    if (inputs.empty())
        fail("{}: {}: value {} at {}", source, field.name, *bad, describeGridPoint(snapshot.grid, i));
    fail("{}: {}: {} (beyond float32) at {}, computed from {}; check the input values there", source, field.name,
         *bad, describeGridPoint(snapshot.grid, i), inputs);
}

}  // namespace raypc::grid
