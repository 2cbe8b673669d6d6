#include "grid/regrid.h"

#include "grid/sampler.h"

#include <tbb/parallel_for.h>

#include <limits>
#include <optional>

namespace raypc::grid {

std::vector<float> regrid(const SphericalGrid& source, const GridValueAt& valueAt, const SphericalGrid& target)
{
    std::vector<float> out(target.cellCount(), std::numeric_limits<float>::quiet_NaN());
    if (source.sameAs(target)) {
        tbb::parallel_for(size_t(0), target.nLat(), [&](size_t iLat) {
            for (size_t iR = 0; iR < target.nR(); ++iR)
                for (size_t iLon = 0; iLon < target.nLon(); ++iLon)
                    out[target.index(iLat, iR, iLon)] = valueAt(iLat, iR, iLon);
        });
        return out;
    }
    const GridSampler sampler(source);
    // Each target shell's radial part and each target column's lateral part are found once.
    std::vector<std::optional<GridSampler::RadialPart>> radial(target.nR());
    for (size_t iR = 0; iR < target.nR(); ++iR)
        radial[iR] = sampler.locateRadius(target.rKm[iR]);
    tbb::parallel_for(size_t(0), target.nLat(), [&](size_t iLat) {
        for (size_t iLon = 0; iLon < target.nLon(); ++iLon) {
            const double latDeg = target.latDeg[iLat], lonDeg = target.lonDeg[iLon];
            if (!source.latHoldsData(latDeg) || !source.lonHoldsData(lonDeg))
                continue;
            const auto lateral = sampler.locateLatLon(latDeg, lonDeg);
            if (!lateral)
                continue;
            for (size_t iR = 0; iR < target.nR(); ++iR)
                if (radial[iR])
                    out[target.index(iLat, iR, iLon)] =
                        float(sampler.sample(valueAt, GridSampler::combine(*lateral, *radial[iR])));
        }
    });
    return out;
}

std::vector<float> regrid(const SphericalGrid& source, const float* values, const SphericalGrid& target)
{
    return regrid(source, [&](size_t iLat, size_t iR, size_t iLon) { return values[source.index(iLat, iR, iLon)]; },
                  target);
}

double coveredFraction(const SphericalGrid& source, const SphericalGrid& target)
{
    const GridSampler sampler(source);
    const auto factors = target.volumeFactors();
    double covered = 0, total = 0;
    for (size_t iLat = 0; iLat < target.nLat(); ++iLat)
        for (size_t iR = 0; iR < target.nR(); ++iR)
            for (size_t iLon = 0; iLon < target.nLon(); ++iLon) {
                const double v = factors.at(iLat, iR, iLon);
                total += v;
                const double latDeg = target.latDeg[iLat], lonDeg = target.lonDeg[iLon];
                if (source.latHoldsData(latDeg) && source.lonHoldsData(lonDeg) &&
                    sampler.locate(latDeg, lonDeg, target.rKm[iR]))
                    covered += v;
            }
    return total > 0 ? covered / total : 0;
}

}  // namespace raypc::grid
