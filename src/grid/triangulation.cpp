#include "grid/triangulation.h"

#include "core/error.h"

#include <bit>

namespace raypc::grid::triangulation {
namespace {

bool isOffset(int dLat, int dR, int dLon)
{
    for (const auto& o : kOffsets)
        if (o.lat == dLat && o.r == dR && o.lon == dLon)
            return true;
    return false;
}

}  // namespace

LinkTables::LinkTables()
{
    for (int a = 0; a < kLinkSize; ++a)
        for (int b = 0; b < kLinkSize; ++b)
            if (a != b && isOffset(kOffsets[b].lat - kOffsets[a].lat, kOffsets[b].r - kOffsets[a].r,
                                   kOffsets[b].lon - kOffsets[a].lon))
                adjacency[a] |= uint16_t(1u << b);
    for (int a = 0; a < kLinkSize; ++a)
        for (int b = a + 1; b < kLinkSize; ++b)
            for (int c = b + 1; c < kLinkSize; ++c)
                if ((adjacency[a] >> b & 1) && (adjacency[a] >> c & 1) && (adjacency[b] >> c & 1))
                    triangles.push_back({a, b, c});
    std::array<uint32_t, kLinkSize> scratch;
    for (uint32_t mask = 0; mask < components.size(); ++mask)
        components[mask] = static_cast<uint8_t>(componentMasks(mask, scratch));
}

int LinkTables::componentMasks(uint32_t mask, std::array<uint32_t, kLinkSize>& out) const
{
    uint32_t left = mask;
    int count = 0;
    while (left) {
        // Flood one component from its lowest vertex.
        uint32_t frontier = left & (~left + 1), seen = 0;
        while (frontier) {
            seen |= frontier;
            uint32_t next = 0;
            for (uint32_t f = frontier; f; f &= f - 1)
                next |= adjacency[std::countr_zero(f)];
            frontier = next & mask & ~seen;
        }
        left &= ~seen;
        out[count++] = seen;
    }
    return count;
}

const LinkTables& linkTables()
{
    static const LinkTables tables;
    return tables;
}

void checkTriangulable(const SphericalGrid& grid, size_t valueCount, const char* what)
{
    if (valueCount != grid.cellCount())
        fail("{}: {} values for a grid of {} points", what, valueCount, grid.cellCount());
    if (grid.nLat() < 2 || grid.nR() < 2 || grid.nLon() < 3)
        fail("{}: grid {}x{}x{} (lat x r x lon) is too small, need at least 2x2x3", what, grid.nLat(), grid.nR(),
             grid.nLon());
}

}  // namespace raypc::grid::triangulation
