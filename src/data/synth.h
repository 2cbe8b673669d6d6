// Synthetic mantle convection: a deterministic time series in the exact layout of the
// SciVis 2021 contest files, plausible enough for the contest's tasks (plumes, slabs,
// stagnation at 660 km and ~1600 km, a consistent velocity field). See docs/synthetic-data.md.
#pragma once

#include "data/snapshot.h"

#include <cstdint>
#include <filesystem>

namespace raypc {

enum class NetcdfFlavour { Classic64, Netcdf4 };

struct SynthOptions {
    int steps = 12;
    int nLat = 64, nR = 81, nLon = 128;  // the demo's default resolution
    uint64_t seed = 1;
    double dtMyr = 2.0;  // time between steps
    NetcdfFlavour flavour = NetcdfFlavour::Classic64;
};

// The model's state at time `timeMyr`, on a centred grid of the given size.
// Deterministic for (options.seed, timeMyr, grid size).
Snapshot synthesizeSnapshot(const SynthOptions& options, double timeMyr);

// Writes spherical001.nc ... sphericalNNN.nc into `outDir` (created if missing); each file is
// written atomically. Shows progress on a terminal. Throws raypc::Error on I/O failure.
void writeSyntheticSeries(const std::filesystem::path& outDir, const SynthOptions& options);

// Writes one snapshot in the contest layout: dims (lat, r, lon) with lat descending,
// float32 variables with `units` attributes, double coordinates lat/r/lon. Atomic.
void writeContestFile(const std::filesystem::path& path, const Snapshot& snapshot,
                      NetcdfFlavour flavour = NetcdfFlavour::Classic64);

}  // namespace raypc
