// Internal to raypc_synth: the model at one time (synth_model.h) evaluated on a grid's columns, as
// the snapshot (synth_fields.cpp) and the ground truth (synth_truth.cpp) both walk them: each
// feature's angular factors once per (lat, lon) column, then a loop over the column's radii that
// touches only the features present there.
//
// Thread safety: forEachColumn runs lat rows in parallel (oneTBB), each thread with its own terms.
#pragma once

#include "synth/synth_model.h"

#include "grid/grid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <array>
#include <cmath>
#include <vector>

namespace raypc::synth::synth {

// Per-column values of one feature.
struct ColumnTerms {
    // Plumes: G's surface Laplacian and gradient.
    double lapG = 0;
    Vec3d gradG{};
    // Slabs: angular latitude about the pole and its gradient, the trench taper A(psi) and its
    // psi-derivatives times grad psi, 1 / cos^2(beta), tan(beta).
    double beta = 0, along = 0, alongD1 = 0, alongD2 = 0, invCos2 = 0, tanBeta = 0;
    Vec3d gradBeta{}, gradPsi{};
    std::array<double, kMaxTerms> angular{};
    bool active = false;
};

// Far from a feature every factor is below ~1e-13 of its peak; skipping it there is invisible
// in float32 and makes the per-cell loop touch only nearby features.
inline constexpr double kNegligibleExponent = 30.0;

// The features at the grid column (latDeg, lonDeg): every feature's terms there (with east and north
// as an orthonormal tangent basis even at the poles) and in `active` the features present (indices
// into model.features). `terms` holds one entry per feature. Returns the column's outward unit vector.
Vec3d featuresOfColumn(const ModelAtTime& model, double latDeg, double lonDeg, std::vector<ColumnTerms>& terms,
                       std::vector<int>& active);

// The slab sheet's profile across its (dipping) centre at radius index iR: a Gaussian of the
// angular offset `xi` from the centre, 0 where it is negligible. Inline: evaluated for every cell
// near a slab.
inline double sheetProfile(const FeatureAtTime& fa, double xi, size_t iR)
{
    const double wt = fa.sheetWidthRad[iR];
    return xi * xi < 2.0 * kNegligibleExponent * wt * wt ? std::exp(-0.5 * xi * xi / (wt * wt)) : 0.0;
}

// Calls column(iLat, iLon, n, terms, active) for every column of `grid`, with featuresOfColumn's
// outward unit vector, terms and active features there, and rowDone(iLat) after the columns of each
// lat row. Rows run in parallel; a row's columns in order on one thread.
template <class Column, class RowDone>
void forEachColumn(const ModelAtTime& model, const grid::SphericalGrid& grid, Column column, RowDone rowDone)
{
    const size_t nFeatures = model.features.size();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, grid.nLat()), [&](const tbb::blocked_range<size_t>& rows) {
        std::vector<ColumnTerms> terms(nFeatures);
        std::vector<int> active;
        active.reserve(nFeatures);
        for (size_t iLat = rows.begin(); iLat != rows.end(); ++iLat) {
            for (size_t iLon = 0; iLon < grid.nLon(); ++iLon) {
                const Vec3d n = featuresOfColumn(model, grid.latDeg[iLat], grid.lonDeg[iLon], terms, active);
                column(iLat, iLon, n, terms, active);
            }
            rowDone(iLat);
        }
    });
}

}  // namespace raypc::synth::synth
