// Synthetic mantle convection: a deterministic time series in the exact layout of the
// SciVis 2021 contest files, plausible enough for the contest's tasks (plumes, slabs,
// stagnation at 660 km and ~1600 km, a consistent velocity field). See docs/synthetic-data.md.
#pragma once

#include "grid/snapshot.h"
#include "io/netcdf_writer.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace raypc::synth {

struct SynthOptions {
    int steps = 12;
    int nLat = 64, nR = 81, nLon = 128;  // the demo's default resolution
    uint64_t seed = 1;
    double dtMyr = 2.0;  // time between steps
    io::NetcdfFlavour flavour = io::NetcdfFlavour::Classic64;
    // An avalanche (docs/synthetic-data.md): from avalancheMyr, for avalancheDurationMyr, the first
    // slab that stalls at 660 km (in syntheticFeatures' order) breaks through it — its flow crosses
    // the layer at twice its speed, carrying its tip below it — then stalls again where its tip is.
    // NaN (the default): no avalanche.
    double avalancheMyr = std::numeric_limits<double>::quiet_NaN();
    double avalancheDurationMyr = 2.0;
};

// The contest-like grid of the given size: lat cell-centred (nLat = 180 gives -89.5 ... 89.5,
// ascending in memory), r uniform from the core-mantle boundary (3485 km) to the surface
// (6371 km) inclusive, lon = i * 360 / nLon (0, 1, ..., 359 for 360; no repeated seam).
// Throws raypc::Error unless nLat >= 2, nR >= 2 and nLon >= 3.
grid::SphericalGrid syntheticGrid(int nLat, int nR, int nLon);

// The model's state at time `timeMyr`, on syntheticGrid(options.nLat, options.nR, options.nLon).
// Deterministic for (options.seed, timeMyr, grid size). Uses oneTBB over lat rows.
grid::Snapshot synthesizeSnapshot(const SynthOptions& options, double timeMyr);

// The same model sampled on any grid (options' grid size is ignored): every field except
// "temperature anomaly" is a pointwise function of (seed, time, position), so a small local
// grid gives exactly the values of a global one at the same points. "temperature anomaly" is
// temperature minus its area-weighted mean over each r shell *of the given grid*, which is
// only the physical anomaly on a global grid.
grid::Snapshot synthesizeSnapshot(const SynthOptions& options, double timeMyr, const grid::SphericalGrid& grid);

// Parses a grid size "LATxRxLON" (e.g. "180x201x360") for the option named `option`.
// Throws raypc::Error naming the option and the text unless it is three whole numbers with
// nLat >= 2, nR >= 2, nLon >= 3 and at most 1e9 cells.
std::array<int, 3> parseSynthGridSize(const std::string& text, const std::string& option = "--grid");

// The large-scale features of the model at `timeMyr`, for tests and documentation: where the
// plumes and slabs are, how far they have risen or sunk, and where they stall.
struct SynthFeature {
    enum class Kind { Plume, Slab };
    Kind kind = Kind::Plume;
    // Plume: axis position. Slab: the midpoint of its trench (a small-circle arc; degrees).
    // Slabs dip: below the surface the sheet is elsewhere, see syntheticFeatureCentreDeg.
    double latDeg = 0, lonDeg = 0;
    // Slab only: the ends of its trench (degrees).
    double startLatDeg = 0, startLonDeg = 0, endLatDeg = 0, endLonDeg = 0;
    // Plume: radius of the head centre. Slab: radius of the tip (km).
    double frontRadiusKm = 0;
    // Depth (km) of the layer where the feature stalls (660 or 1600); 0 when it passes through.
    double stallDepthKm = 0;
    // Slab only: it is breaking through that layer at this time (SynthOptions::avalancheMyr).
    bool breakingThrough = false;
    // Peak vertical speed of the feature's flow (m/s, > 0 for both kinds) and its temperature
    // amplitude (K, > 0 for plumes, < 0 for slabs).
    double speedMps = 0, temperatureK = 0;
    // Plume only: Gaussian sigma of the conduit (km, at 4400 km radius; angular width fixed).
    double conduitSigmaKm = 0;
    // Slab only: dip at the trench (degrees); it steepens to near-vertical with depth.
    double dipAtTrenchDeg = 0;
};
std::vector<SynthFeature> syntheticFeatures(const SynthOptions& options, double timeMyr);

// Where feature `index` (as in syntheticFeatures) is centred at radius `rKm` and `timeMyr`:
// a plume's axis, or the centre of a slab's (dipping) sheet below the middle of its trench.
// Returns {latDeg, lonDeg}.
std::array<double, 2> syntheticFeatureCentreDeg(const SynthOptions& options, double timeMyr, size_t index, double rKm);

// The parts of a feature: each is one term of the temperature anomaly the generator sums
// (docs/synthetic-data.md, "Features").
enum class SynthPart : uint8_t {
    Background,        // no part of any feature reaches its extent here
    PlumeConduit,      // the column from the CMB up to the head
    PlumeHead,
    PlumePile,         // the hot pile at the conduit's base on the CMB
    PlumePancake660,   // hot material spreading ~70 km below 660 km
    PlumePancake1600,  // ... below the spin layer (1600 km)
    SlabSheet,         // the dipping sheet from the trench down to the tip
    SlabPancake660,    // cold material spreading ~70 km above 660 km
    SlabPancake1600,   // ... above the spin layer
    SlabPool,          // the cold pool where a slab lies on the CMB
};
inline constexpr size_t kSynthPartCount = 10;
// "plume conduit", "slab pancake 660", ... (for tables and messages).
const char* synthPartName(SynthPart part);

// What the generator put at each point of a grid: the ground truth that tests of the task presets
// measure selections against (docs/synthetic-data.md, "Ground truth"). Every part is an analytic
// shape times an amplitude; its *envelope* at a point is that shape's value there, in [0, 1]: the
// part's anomaly divided by its peak anomaly at full development (the product of its Gaussians,
// smooth steps, trench taper, growth of pancakes and pool, and the taper at the isothermal
// boundaries; the pile and the pool relative to the peak of their tapered profile on the CMB;
// conduits and sheets relative to their amplitude at the same radius, which changes slowly). A point
// belongs to the part whose anomaly (K) is largest among the parts whose envelope reaches
// kSynthExtent there (two sigma of one Gaussian); its core is where the envelope is at least
// kSynthCore (one sigma). Elsewhere it is Background.
inline constexpr double kSynthCore = 0.60653065971263342;    // exp(-1/2)
inline constexpr double kSynthExtent = 0.13533528323661270;  // exp(-2)
struct SynthTruth {
    // One entry per grid point, canonical order (SphericalGrid::index).
    std::vector<int16_t> feature;  // index into syntheticFeatures(options, timeMyr); -1 for Background
    std::vector<SynthPart> part;
    std::vector<float> envelope;   // of that part, >= kSynthExtent; 0 for Background
    bool inCore(size_t i) const { return envelope[i] >= kSynthCore; }
};
// The truth on `grid` (any grid, like synthesizeSnapshot) at `timeMyr`. Deterministic; parallel
// over lat rows. Throws raypc::Error for a non-finite time.
SynthTruth syntheticTruth(const SynthOptions& options, double timeMyr, const grid::SphericalGrid& grid);

// The generator's features in every step of a series (`raypc synth --truth FILE`, what a user compares
// `raypc features` with; docs/synthetic-data.md, "Ground truth"): CSV, a row per step and feature of
// syntheticFeatures — step, time_myr, feature (its index), kind (plume, slab), front_depth_km (a
// plume's head, a slab's tip), stall_depth_km (660, 1600, or 0 when it passes through),
// front_at_stall (1 when the front lies within 50 km of that depth), lat_deg and lon_deg (a plume's
// axis, the middle of a slab's trench), and on `options`' grid the dual-cell volumes (km³) of its core
// (syntheticTruth: points where its envelope is at least kSynthCore), of its core in the pancake at
// 660 km and at 1600 km, and breaking_through (1 while its avalanche is under way). Deterministic. Throws raypc::Error as synthesizeSnapshot does.
std::string syntheticTruthTable(const SynthOptions& options);

// The slow rigid rotation that carries the whole pattern (part of the velocity field):
// v_rotation = omega x p with p in metres, omega (rad/s) in the Cartesian frame of spherical.h.
std::array<double, 3> syntheticRotationRadPerSecond(const SynthOptions& options);

// Writes spherical001.nc ... sphericalNNN.nc into `outDir` (created if missing); each file is
// written atomically. Shows progress on a terminal. Throws raypc::Error on I/O failure.
void writeSyntheticSeries(const std::filesystem::path& outDir, const SynthOptions& options);

}  // namespace raypc::synth
