// Tests of the synthetic mantle-convection generator: physical properties that a wrong sign,
// factor or layout would break, checked with independent finite differences and netCDF-C.
#include "data/synth.h"

#include "core/error.h"
#include "core/spherical.h"

#include <gtest/gtest.h>
#include <netcdf.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <numeric>

namespace raypc {
namespace {

namespace fs = std::filesystem;

// Spherical components of the velocity at one grid point (m/s).
struct LocalVelocity {
    double ur, east, north;
};

LocalVelocity localVelocity(const Snapshot& s, size_t idx, double latDeg, double lonDeg)
{
    const double lat = degToRad(latDeg), lon = degToRad(lonDeg);
    const double vx = s.find("vx")->values[idx], vy = s.find("vy")->values[idx], vz = s.find("vz")->values[idx];
    const double ur = vx * std::cos(lat) * std::cos(lon) + vy * std::cos(lat) * std::sin(lon) + vz * std::sin(lat);
    const double east = -vx * std::sin(lon) + vy * std::cos(lon);
    const double north = -vx * std::sin(lat) * std::cos(lon) - vy * std::sin(lat) * std::sin(lon) + vz * std::cos(lat);
    return {ur, east, north};
}

double depthOf(const SphericalGrid& g, size_t iR) { return kSurfaceRadiusKm - g.rKm[iR]; }

// Area weight of a lat row's dual cell, computed here independently of the generator.
double rowArea(const SphericalGrid& g, size_t iLat)
{
    const size_t n = g.nLat();
    const double lo = iLat == 0 ? -90.0 : 0.5 * (g.latDeg[iLat - 1] + g.latDeg[iLat]);
    const double hi = iLat + 1 == n ? 90.0 : 0.5 * (g.latDeg[iLat] + g.latDeg[iLat + 1]);
    return std::sin(degToRad(hi)) - std::sin(degToRad(lo));
}

double correlation(const std::vector<double>& a, const std::vector<double>& b)
{
    const double n = static_cast<double>(a.size());
    const double ma = std::accumulate(a.begin(), a.end(), 0.0) / n, mb = std::accumulate(b.begin(), b.end(), 0.0) / n;
    double sab = 0, saa = 0, sbb = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        sab += (a[i] - ma) * (b[i] - mb);
        saa += (a[i] - ma) * (a[i] - ma);
        sbb += (b[i] - mb) * (b[i] - mb);
    }
    return sab / std::sqrt(saa * sbb);
}

// The demo-size grid is small enough to synthesize a few times per test run.
SynthOptions demoOptions(uint64_t seed = 1)
{
    SynthOptions o;
    o.seed = seed;
    return o;
}

const Snapshot& demoSnapshot()
{
    static const Snapshot s = synthesizeSnapshot(demoOptions(), 0.0);
    return s;
}

size_t nearestIndex(const std::vector<double>& values, double x)
{
    size_t best = 0;
    for (size_t i = 1; i < values.size(); ++i)
        if (std::abs(values[i] - x) < std::abs(values[best] - x))
            best = i;
    return best;
}

size_t nearestLon(const SphericalGrid& g, double lonDeg)
{
    size_t best = 0;
    double bestD = 1e9;
    for (size_t i = 0; i < g.nLon(); ++i) {
        double d = std::abs(g.lonDeg[i] - lonDeg);
        d = std::min(d, 360.0 - d);
        if (d < bestD) {
            bestD = d;
            best = i;
        }
    }
    return best;
}

// A tiny grid around (lat, lon, r) with spacing `stepDeg`, `stepKm`.
SphericalGrid localGrid(double latDeg, double lonDeg, double rKm, double stepDeg, double stepKm)
{
    SphericalGrid g;
    g.latDeg = {latDeg - stepDeg, latDeg, latDeg + stepDeg};
    g.rKm = {rKm - stepKm, rKm, rKm + stepKm};
    g.lonDeg = {lonDeg - stepDeg, lonDeg, lonDeg + stepDeg};
    return g;
}

TEST(SynthGrid, LayoutLikeTheContest)
{
    const SphericalGrid g = syntheticGrid(180, 201, 360);
    ASSERT_EQ(g.nLat(), 180u);
    EXPECT_DOUBLE_EQ(g.latDeg.front(), -89.5);
    EXPECT_DOUBLE_EQ(g.latDeg.back(), 89.5);
    EXPECT_DOUBLE_EQ(g.rKm.front(), 3485.0);
    EXPECT_DOUBLE_EQ(g.rKm.back(), 6371.0);
    EXPECT_NEAR(g.rKm[1] - g.rKm[0], 14.43, 1e-9);
    EXPECT_DOUBLE_EQ(g.lonDeg.front(), 0.0);
    EXPECT_DOUBLE_EQ(g.lonDeg.back(), 359.0);
    EXPECT_THROW(syntheticGrid(1, 5, 5), Error);
}

TEST(SynthGrid, ParsesSizesAndRejectsBadOnes)
{
    EXPECT_EQ(parseSynthGridSize("180x201x360"), (std::array<int, 3>{180, 201, 360}));
    for (const char* bad : {"10x20", "0x5x5", "4x5x2", "axbxc", "4x5x", "4x-5x8", "4x5x8x9", "4 x5x8", "3000x3000x3000"}) {
        try {
            parseSynthGridSize(bad, "--grid");
            ADD_FAILURE() << bad << " was accepted";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("--grid"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
        }
    }
}

TEST(SynthModel, FiniteWithPlausibleMagnitudes)
{
    const Snapshot& s = demoSnapshot();
    const SphericalGrid& g = s.grid;
    ASSERT_EQ(s.fields.size(), 8u);
    for (size_t v = 0; v < 8; ++v) {
        EXPECT_EQ(s.fields[v].name, contestVariableNames()[v]);
        for (float x : s.fields[v].values)
            ASSERT_TRUE(std::isfinite(x)) << s.fields[v].name;
    }
    const auto& t = s.find("temperature")->values;
    const auto& k = s.find("thermal conductivity")->values;
    const auto& alpha = s.find("thermal expansivity")->values;
    double maxSpeed = 0, sumSq = 0;
    for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
        for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
            EXPECT_NEAR(t[g.index(iLat, g.nR() - 1, iLon)], 300.0, 1.0);
            EXPECT_NEAR(t[g.index(iLat, 0, iLon)], 4000.0, 1.0);
            for (size_t iR = 0; iR < g.nR(); ++iR) {
                const size_t i = g.index(iLat, iR, iLon);
                const double vx = s.fields[1].values[i], vy = s.fields[2].values[i], vz = s.fields[3].values[i];
                const double speed = std::sqrt(vx * vx + vy * vy + vz * vz);
                maxSpeed = std::max(maxSpeed, speed);
                sumSq += speed * speed;
                ASSERT_GT(k[i], 2.5f);
                ASSERT_LT(k[i], 12.0f);
                ASSERT_GT(alpha[i], 0.7e-5f);
                ASSERT_LT(alpha[i], 4e-5f);
            }
        }
    const double rms = std::sqrt(sumSq / g.cellCount());
    std::printf("max speed %.3g m/s (%.2f cm/yr), rms %.3g m/s\n", maxSpeed, maxSpeed * kMpsToCmPerYr, rms);
    EXPECT_GT(maxSpeed, 1e-9);  // a few cm/yr
    EXPECT_LT(maxSpeed, 1e-8);
    EXPECT_GT(rms, 1e-10);
    // The mid-mantle temperature is an adiabat plus anomalies of a few hundred K.
    double minT = 1e9, maxT = 0;
    const size_t mid = nearestIndex(g.rKm, kSurfaceRadiusKm - 1200.0);
    for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
        for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
            minT = std::min<double>(minT, t[g.index(iLat, mid, iLon)]);
            maxT = std::max<double>(maxT, t[g.index(iLat, mid, iLon)]);
        }
    std::printf("T at 1200 km depth: %.0f .. %.0f K\n", minT, maxT);
    EXPECT_GT(minT, 1500.0);
    EXPECT_LT(maxT, 2600.0);
    EXPECT_GT(maxT - minT, 300.0);
}

TEST(SynthModel, TemperatureAnomalyHasZeroMeanOnEveryShell)
{
    const Snapshot& s = demoSnapshot();
    const SphericalGrid& g = s.grid;
    const auto& t = s.find("temperature")->values;
    const auto& dT = s.find("temperature anomaly")->values;
    for (size_t iR = 0; iR < g.nR(); ++iR) {
        double sum = 0, area = 0, sumT = 0, maxAbs = 0;
        for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
            for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                const size_t i = g.index(iLat, iR, iLon);
                sum += rowArea(g, iLat) * dT[i];
                sumT += rowArea(g, iLat) * t[i];
                area += rowArea(g, iLat);
                maxAbs = std::max(maxAbs, std::abs(static_cast<double>(dT[i])));
            }
        EXPECT_NEAR(sum / area, 0.0, 1e-3) << "shell " << iR;
        // And it is temperature minus that mean, not something else.
        const size_t i0 = g.index(g.nLat() / 2, iR, 7);
        EXPECT_NEAR(dT[i0], t[i0] - sumT / area, 1e-3 * std::max(1.0, maxAbs));
    }
}

// Up where hot, down where cold: at each plume's axis in its tail and in each slab.
TEST(SynthModel, RadialVelocityFollowsTemperature)
{
    const Snapshot& s = demoSnapshot();
    const SphericalGrid& g = s.grid;
    const auto& dT = s.find("temperature anomaly")->values;
    for (const SynthFeature& f : syntheticFeatures(demoOptions(), 0.0)) {
        const bool plume = f.kind == SynthFeature::Kind::Plume;
        // Halfway along the feature, away from the stagnation layers where ur is held back.
        double rKm = plume ? 0.5 * (kCoreRadiusKm + 300.0 + f.frontRadiusKm) : 0.5 * (kSurfaceRadiusKm - 150.0 + f.frontRadiusKm);
        for (double layer : {660.0, 1600.0})
            if (std::abs(kSurfaceRadiusKm - layer - rKm) < 200.0)
                rKm = kSurfaceRadiusKm - layer + (plume ? -220.0 : 220.0);
        const size_t iLat = nearestIndex(g.latDeg, f.latDeg), iLon = nearestLon(g, f.lonDeg);
        const size_t iR = nearestIndex(g.rKm, rKm);
        const size_t i = g.index(iLat, iR, iLon);
        const LocalVelocity u = localVelocity(s, i, g.latDeg[iLat], g.lonDeg[iLon]);
        std::printf("%s at (%.1f, %.1f) depth %.0f km (front %.0f km): ur %.3g m/s, dT %.0f K\n", plume ? "plume" : "slab",
                    f.latDeg, f.lonDeg, depthOf(g, iR), kSurfaceRadiusKm - f.frontRadiusKm, u.ur, dT[i]);
        if (plume) {
            EXPECT_GT(u.ur, 2e-10);
            EXPECT_GT(dT[i], 50.0);
        } else {
            EXPECT_LT(u.ur, -2e-10);
            EXPECT_LT(dT[i], -50.0);
        }
    }
    // Over the whole mid mantle, radial velocity and temperature anomaly are positively correlated.
    std::vector<double> ur, anomaly;
    for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
        for (size_t iR = 0; iR < g.nR(); ++iR) {
            if (depthOf(g, iR) < 800.0 || depthOf(g, iR) > 2600.0)
                continue;
            for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                const size_t i = g.index(iLat, iR, iLon);
                ur.push_back(localVelocity(s, i, g.latDeg[iLat], g.lonDeg[iLon]).ur);
                anomaly.push_back(dT[i]);
            }
        }
    const double c = correlation(ur, anomaly);
    std::printf("corr(ur, dT) in the mid mantle: %.3f\n", c);
    EXPECT_GT(c, 0.3);
}

// Divergence (m/s per km) and the size of its radial term at the centre of a 3x3x3 grid,
// by central differences in spherical coordinates:
// div v = 1/r^2 d(r^2 ur)/dr + 1/(r cos lat) d(un cos lat)/dlat + 1/(r cos lat) d(ue)/dlon.
std::pair<double, double> centralDivergence(const Snapshot& s)
{
    const SphericalGrid& g = s.grid;
    auto u = [&](size_t a, size_t b, size_t c) { return localVelocity(s, g.index(a, b, c), g.latDeg[a], g.lonDeg[c]); };
    const double r = g.rKm[1], lat = degToRad(g.latDeg[1]);
    const double dr = g.rKm[2] - g.rKm[0], dLat = degToRad(g.latDeg[2] - g.latDeg[0]), dLon = degToRad(g.lonDeg[2] - g.lonDeg[0]);
    const double radial = (g.rKm[2] * g.rKm[2] * u(1, 2, 1).ur - g.rKm[0] * g.rKm[0] * u(1, 0, 1).ur) / (dr * r * r);
    const double northward = (std::cos(degToRad(g.latDeg[2])) * u(2, 1, 1).north - std::cos(degToRad(g.latDeg[0])) * u(0, 1, 1).north) /
                             (dLat * r * std::cos(lat));
    const double eastward = (u(1, 1, 2).east - u(1, 1, 0).east) / (dLon * r * std::cos(lat));
    return {radial + northward + eastward, std::max({std::abs(radial), std::abs(northward), std::abs(eastward)})};
}

// The flow is built divergence-free; finite differences with small steps must see that, where
// each term of the divergence alone is large (the plume and slab flanks near a layer).
TEST(SynthModel, VelocityIsDivergenceFree)
{
    const SynthOptions o = demoOptions();
    int checked = 0;
    for (const SynthFeature& f : syntheticFeatures(o, 0.0)) {
        for (double offsetDeg : {1.5, 3.0, 5.0}) {
            for (double depth : {560.0, 760.0, 1500.0, 2200.0}) {
                const Snapshot s = synthesizeSnapshot(o, 0.0, localGrid(f.latDeg + offsetDeg, f.lonDeg + 0.7 * offsetDeg, kSurfaceRadiusKm - depth, 0.01, 0.5));
                const auto [div, scale] = centralDivergence(s);
                // Where nothing but the rigid rotation flows, the terms are at float32 rounding level.
                if (scale < 1e-13)
                    continue;
                ++checked;
                EXPECT_LT(std::abs(div), 2e-3 * scale) << "near feature at " << f.latDeg << ", " << f.lonDeg << " depth " << depth;
            }
        }
    }
    EXPECT_GT(checked, 60);
}

// On the demo grid itself the discrete divergence is a discretization error, small against
// each of its terms, with the terms themselves as large as |v| / (feature width).
TEST(SynthModel, DiscreteDivergenceOnTheGridIsSmall)
{
    const Snapshot& s = demoSnapshot();
    const SphericalGrid& g = s.grid;
    double sumDiv = 0, sumRadial = 0;
    for (size_t iLat = 1; iLat + 1 < g.nLat(); ++iLat) {
        const double lat = degToRad(g.latDeg[iLat]);
        for (size_t iR = 1; iR + 1 < g.nR(); ++iR) {
            const double r = g.rKm[iR];
            for (size_t iLon = 1; iLon + 1 < g.nLon(); ++iLon) {
                auto u = [&](size_t a, size_t b, size_t c) { return localVelocity(s, g.index(a, b, c), g.latDeg[a], g.lonDeg[c]); };
                const double dr = g.rKm[iR + 1] - g.rKm[iR - 1];
                const double dLat = degToRad(g.latDeg[iLat + 1] - g.latDeg[iLat - 1]);
                const double dLon = degToRad(g.lonDeg[iLon + 1] - g.lonDeg[iLon - 1]);
                const double radial = (g.rKm[iR + 1] * g.rKm[iR + 1] * u(iLat, iR + 1, iLon).ur -
                                       g.rKm[iR - 1] * g.rKm[iR - 1] * u(iLat, iR - 1, iLon).ur) / (dr * r * r);
                const double northward = (std::cos(degToRad(g.latDeg[iLat + 1])) * u(iLat + 1, iR, iLon).north -
                                          std::cos(degToRad(g.latDeg[iLat - 1])) * u(iLat - 1, iR, iLon).north) /
                                         (dLat * r * std::cos(lat));
                const double eastward = (u(iLat, iR, iLon + 1).east - u(iLat, iR, iLon - 1).east) / (dLon * r * std::cos(lat));
                sumDiv += std::pow(radial + northward + eastward, 2);
                sumRadial += radial * radial;
            }
        }
    }
    const double ratio = std::sqrt(sumDiv / sumRadial);
    std::printf("rms(div) / rms(radial term) on the demo grid: %.3f\n", ratio);
    EXPECT_LT(ratio, 0.25);
}

}  // namespace
}  // namespace raypc
