// The synthetic series's grid (synth.h): the contest-like grid of a size, and that size as the
// command line gives it.
#include "synth/synth.h"

#include "core/error.h"
#include "core/spherical.h"
#include "synth/synth_model.h"
#include "core/strings.h"

#include <charconv>

namespace raypc::synth {

grid::SphericalGrid syntheticGrid(int nLat, int nR, int nLon)
{
    if (nLat < 2 || nR < 2 || nLon < 3)
        fail("synthetic grid {}x{}x{}: expected at least 2 lat rows, 2 radii and 3 lon columns", nLat, nR, nLon);
    grid::SphericalGrid grid;
    grid.latDeg.resize(nLat);
    grid.rKm.resize(nR);
    grid.lonDeg.resize(nLon);
    for (int i = 0; i < nLat; ++i)
        grid.latDeg[i] = -90.0 + (i + 0.5) * 180.0 / nLat;
    for (int i = 0; i < nR; ++i)
        grid.rKm[i] = i + 1 == nR ? kSurfaceRadiusKm : kCoreRadiusKm + i * synth::kMantleThicknessKm / (nR - 1);
    for (int i = 0; i < nLon; ++i)
        grid.lonDeg[i] = i * 360.0 / nLon;
    return grid;
}

std::array<int, 3> parseSynthGridSize(const std::string& text, const std::string& option)
{
    const std::vector<std::string> parts = split(text, 'x');
    if (parts.size() != 3)
        fail("{} '{}': expected LATxRxLON, three sizes such as 64x81x128", option, text);
    std::array<int, 3> sizes{};
    for (size_t i = 0; i < 3; ++i) {
        const std::string& p = parts[i];
        const auto [end, ec] = std::from_chars(p.data(), p.data() + p.size(), sizes[i]);
        if (p.empty() || ec != std::errc() || end != p.data() + p.size())
            fail("{} '{}': '{}' is not a whole number; expected LATxRxLON such as 64x81x128", option, text, p);
    }
    if (sizes[0] < 2 || sizes[1] < 2 || sizes[2] < 3)
        fail("{} '{}': expected at least 2 lat rows, 2 radii and 3 lon columns", option, text);
    // Beyond this one variable no longer fits a 64-bit-offset file (4 GiB per variable).
    const double cells = static_cast<double>(sizes[0]) * sizes[1] * sizes[2];
    if (cells > 1.0e9)
        fail("{} '{}': {:.3g} cells, expected at most 1e9", option, text, cells);
    return sizes;
}

}  // namespace raypc::synth
