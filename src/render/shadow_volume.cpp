#include "render/shadow_volume.h"

#include "core/clock.h"
#include "render/pathline_scene.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <numbers>

namespace raypc::render {
namespace {

// FNV-1a over the bytes of what a grid depends on.
struct Hasher {
    uint64_t h = 1469598103934665603ull;
    void bytes(const void* p, size_t n)
    {
        const auto* b = static_cast<const unsigned char*>(p);
        for (size_t i = 0; i < n; ++i)
            h = (h ^ b[i]) * 1099511628211ull;
    }
    template <class T>
    void value(const T& v)
    {
        bytes(&v, sizeof v);
    }
};

}  // namespace

ShadowVolume::ShadowVolume(int nodes) : m_n(std::max(nodes, 4)) {}

ShadowBuildStats ShadowVolume::update(const kernel::KernelParams& k, float strength, const PathlineScene* tubes)
{
    ShadowBuildStats stats;
    const size_t count = size_t(m_n) * size_t(m_n) * size_t(m_n);
    // The grid: nodes one cell beyond the surface on every side.
    const float extentKm = k.rOuterKm * float(m_n - 1) / float(m_n - 3);
    const float cellKm = 2.0f * extentKm / float(m_n - 1);

    // What the volume's extinction depends on: the field, the transfer table, the brushes, the
    // selection's floor and the brick flags (which follow from those), the grid's shell.
    Hasher v;
    v.value(k.color.values);
    v.value(k.nLat);
    v.value(k.nR);
    v.value(k.nLon);
    v.value(k.rInnerKm);
    v.value(k.rOuterKm);
    v.value(m_n);
    v.bytes(k.table.sigmaPerKm, sizeof(float) * size_t(k.table.size));
    v.value(k.table.valueMin);
    v.value(k.table.indexScale);
    v.value(k.selectionSigmaPerKm);
    for (int b = 0; b < k.brushCount; ++b) {
        const kernel::KernelBrush& brush = k.brushes[b];
        v.value(brush.onCoordinate);
        v.value(brush.component);
        v.value(brush.scale);
        v.value(brush.offset);
        v.value(brush.variable.values);
        v.value(brush.min);
        v.value(brush.max);
        v.value(brush.rangeCount);
        if (brush.rangeCount > 1)
            v.bytes(brush.ranges, sizeof(dataset::ValueRange) * size_t(brush.rangeCount));
    }
    const bool rebuildVolume = !m_valid || v.h != m_volumeKey;
    if (rebuildVolume) {
        m_originKm = -extentKm;
        m_cellKm = cellKm;
        const auto start = std::chrono::steady_clock::now();
        m_volumeSigma.assign(count, 0.0f);
        buildExtinction(k);
        stats.extinctionMs = millisecondsSince(start);
        stats.extinctionBuilt = true;
        m_volumeKey = v.h;
    }

    // The visible tubes: which lines, their radius.
    Hasher t;
    if (tubes && tubes->visibleCount() > 0) {
        t.value(tubes);
        t.value(tubes->radiusKm());
        t.bytes(tubes->visibility().data(), tubes->visibility().size());
        t.value(m_n);
    }
    const bool rebuildTubes = rebuildVolume || !m_valid || t.h != m_tubeKey;
    if (rebuildTubes) {
        const auto start = std::chrono::steady_clock::now();
        splatTubes(tubes && tubes->visibleCount() > 0 ? tubes : nullptr);
        m_sigma = m_volumeSigma;
        if (!m_tubeSigma.empty())
            for (size_t i = 0; i < count; ++i)
                m_sigma[i] += m_tubeSigma[i];
        stats.tubesMs = millisecondsSince(start);
        stats.tubesBuilt = true;
        m_tubeKey = t.h;
    }

    Hasher l;
    l.value(m_volumeKey);
    l.value(m_tubeKey);
    l.value(strength);
    l.value(k.lightDir);
    l.value(k.drawCore);
    if (!m_valid || rebuildTubes || l.h != m_lightKey) {
        const auto start = std::chrono::steady_clock::now();
        buildLight(k, strength);
        stats.lightMs = millisecondsSince(start);
        stats.lightBuilt = true;
        m_lightKey = l.h;
    }

    Hasher a;
    a.value(m_volumeKey);
    a.value(m_tubeKey);
    a.value(strength);
    if (!m_valid || rebuildTubes || a.h != m_ambientKey) {
        const auto start = std::chrono::steady_clock::now();
        buildAmbient(strength);
        stats.ambientMs = millisecondsSince(start);
        stats.ambientBuilt = true;
        m_ambientKey = a.h;
    }
    m_valid = true;
    return stats;
}

void ShadowVolume::bind(kernel::KernelParams& k) const
{
    if (!m_valid)
        return;
    k.shadowLight = m_light.data();
    k.shadowAmbient = m_ambient.data();
    k.shadowN = m_n;
    k.shadowOriginKm = m_originKm;
    k.shadowInvKm = 1.0f / m_cellKm;
    k.shadowLightBiasKm = m_cellKm;
}

// The mean of the kernels' extinction at 2^3 points of each node's cell (at +-1/4 cell from the
// node on each axis), in parallel over z slices. Points the skip grid shows in inactive space, or
// outside the shell, are 0 without being located.
void ShadowVolume::buildExtinction(const kernel::KernelParams& k)
{
    const int n = m_n;
    const float h = m_cellKm, o = m_originKm;
    const float reach = 0.5f * std::sqrt(3.0f) * h;  // from a node to its cell's corners
    tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& zs) {
        std::vector<float> px, py, pz, sigma;
        std::vector<uint32_t> node;
        for (int iz = zs.begin(); iz != zs.end(); ++iz) {
            px.clear();
            py.clear();
            pz.clear();
            node.clear();
            for (int iy = 0; iy < n; ++iy)
                for (int ix = 0; ix < n; ++ix) {
                    const Vec3 c{o + float(ix) * h, o + float(iy) * h, o + float(iz) * h};
                    const float r = length(c);
                    if (r - reach > k.rOuterKm || r + reach < k.rInnerKm)
                        continue;
                    for (int s = 0; s < 8; ++s) {
                        const Vec3 p{c.x + ((s & 1) ? 0.25f : -0.25f) * h, c.y + ((s & 2) ? 0.25f : -0.25f) * h,
                                     c.z + ((s & 4) ? 0.25f : -0.25f) * h};
                        if (k.cellDistance) {
                            const float f[3] = {(p.x - k.cellOriginKm) * k.cellInvKm, (p.y - k.cellOriginKm) * k.cellInvKm,
                                                (p.z - k.cellOriginKm) * k.cellInvKm};
                            const float span = float(k.cellN);
                            if (!(f[0] >= 0 && f[1] >= 0 && f[2] >= 0 && f[0] < span && f[1] < span && f[2] < span))
                                continue;
                            const size_t cn = size_t(k.cellN);
                            if (k.cellDistance[(size_t(f[2]) * cn + size_t(f[1])) * cn + size_t(f[0])] != 0)
                                continue;
                        }
                        px.push_back(p.x);
                        py.push_back(p.y);
                        pz.push_back(p.z);
                        node.push_back(uint32_t((size_t(iz) * size_t(n) + size_t(iy)) * size_t(n) + size_t(ix)));
                    }
                }
            sigma.resize(px.size());
            if (!px.empty())
                kernel::extinctionBatchSimd(k, px.data(), py.data(), pz.data(), int(px.size()), sigma.data());
            for (size_t i = 0; i < node.size(); ++i)
                m_volumeSigma[node[i]] += 0.125f * sigma[i];
        }
    });
}

// Tubes as opaque cylinders (extinction 1 / radius: a crossing through the axis has optical depth
// 2), splatted trilinearly as pieces at most half a cell long, each adding its volume x 1 / radius
// spread over a cell's volume, so that the mean optical depth through a cell is kept.
void ShadowVolume::splatTubes(const PathlineScene* tubes)
{
    m_tubeSigma.clear();
    if (!tubes)
        return;
    const int n = m_n;
    m_tubeSigma.assign(size_t(n) * size_t(n) * size_t(n), 0.0f);
    const float h = m_cellKm, o = m_originKm, r = tubes->radiusKm();
    const float perKm = std::numbers::pi_v<float> * r / (h * h * h);
    const std::vector<uint8_t>& visible = tubes->visibility();
    size_t line = 0;
    for (const analysis::PathlineSet& set : tubes->sets()) {
        for (size_t i = 0; i < set.lineCount(); ++i, ++line) {
            if (line >= visible.size() || !visible[line])
                continue;
            for (size_t p = set.offsets[i]; p + 1 < set.offsets[i + 1]; ++p) {
                const Vec3 a{set.points[4 * p], set.points[4 * p + 1], set.points[4 * p + 2]};
                const Vec3 b{set.points[4 * p + 4], set.points[4 * p + 5], set.points[4 * p + 6]};
                const float len = length(b - a);
                const int pieces = std::max(1, int(std::ceil(len / (0.5f * h))));
                for (int q = 0; q < pieces; ++q) {
                    const Vec3 c = a + (b - a) * ((float(q) + 0.5f) / float(pieces));
                    const float f[3] = {(c.x - o) / h, (c.y - o) / h, (c.z - o) / h};
                    int i0[3];
                    float w[3];
                    bool inside = true;
                    for (int ax = 0; ax < 3; ++ax) {
                        inside = inside && f[ax] >= 0.0f && f[ax] < float(n - 1);
                        i0[ax] = int(f[ax]);
                        w[ax] = f[ax] - float(i0[ax]);
                    }
                    if (!inside)
                        continue;
                    const float amount = perKm * len / float(pieces);
                    for (int corner = 0; corner < 8; ++corner) {
                        float weight = amount;
                        size_t idx = 0, stride = 1;
                        for (int ax = 0; ax < 3; ++ax) {
                            const int up = (corner >> ax) & 1;
                            weight *= up ? w[ax] : 1.0f - w[ax];
                            idx += size_t(i0[ax] + up) * stride;
                            stride *= size_t(n);
                        }
                        m_tubeSigma[idx] += weight;
                    }
                }
            }
        }
    }
}

// The optical depth towards the light, slice by slice along the light's dominant axis a: a node
// continues the optical depth of the point one slice towards the light (its other coordinates
// moved by l_b / |l_a| and l_c / |l_a| nodes, interpolated bilinearly; outside the grid nothing),
// adding the trapezoid of the extinction over the h / |l_a| between them.
void ShadowVolume::buildLight(const kernel::KernelParams& k, float strength)
{
    const int n = m_n;
    const size_t count = size_t(n) * size_t(n) * size_t(n);
    m_light.assign(count, 0.0f);
    const float l[3] = {k.lightDir.x, k.lightDir.y, k.lightDir.z};
    int a = 0;
    for (int ax = 1; ax < 3; ++ax)
        if (std::abs(l[ax]) > std::abs(l[a]))
            a = ax;
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    const size_t stride[3] = {1, size_t(n), size_t(n) * size_t(n)};
    const float la = std::abs(l[a]);
    const int towards = l[a] > 0.0f ? 1 : -1;  // slice index step towards the light
    const float ob = l[b] / la, oc = l[c] / la, segmentKm = m_cellKm / la;
    std::vector<float>& tau = m_light;  // optical depth first, visibility at the end
    const std::vector<float>& sigma = m_sigma;
    // Only nodes within kNeededKm of the centre are computed (the rest stay 0, their visibility 1):
    // lookups happen in the shell, moved at most two cells towards the light (tubes), and read the
    // nodes of their cell; a node inside continues one towards the light, which outside this ball
    // lies on the light's side of the planet, where the optical depth is 0.
    const float h = m_cellKm, o = m_originKm;
    const float neededKm = k.rOuterKm + 4.0f * h, needed2 = neededKm * neededKm;
    // Nodes [mFirst, mLast] of a row at squared distance d2 from the centre within the other two axes.
    auto rowSpan = [&](float d2, int& mFirst, int& mLast) {
        const float half = std::sqrt(std::max(0.0f, needed2 - d2));
        mFirst = std::max(0, int(std::floor((-half - o) / h)));
        mLast = std::min(n - 1, int(std::ceil((half - o) / h)));
        if (!(d2 <= needed2))
            mLast = -1;
    };
    auto coord = [&](int i) { return o + float(i) * h; };
    const int first = towards > 0 ? n - 1 : 0;
    for (int step = 1; step < n; ++step) {
        const int slice = first - towards * step, up = slice + towards;
        const size_t sliceBase = size_t(slice) * stride[a], upBase = size_t(up) * stride[a];
        const float sliceD2 = coord(slice) * coord(slice);
        tbb::parallel_for(tbb::blocked_range<int>(0, n, 16), [&](const tbb::blocked_range<int>& rows) {
            for (int j = rows.begin(); j != rows.end(); ++j) {
                int mFirst, mLast;
                rowSpan(sliceD2 + coord(j) * coord(j), mFirst, mLast);
                const float fb = float(j) + ob;
                if (!(fb >= 0.0f && fb <= float(n - 1))) {
                    for (int m = mFirst; m <= mLast; ++m) {
                        const size_t i = sliceBase + size_t(j) * stride[b] + size_t(m) * stride[c];
                        tau[i] = 0.5f * sigma[i] * segmentKm;
                    }
                    continue;
                }
                const int jb = std::min(int(fb), n - 2);
                const float wb = fb - float(jb);
                for (int m = mFirst; m <= mLast; ++m) {
                    const size_t i = sliceBase + size_t(j) * stride[b] + size_t(m) * stride[c];
                    const float fc = float(m) + oc;
                    float tauUp = 0, sigmaUp = 0;
                    if (fc >= 0.0f && fc <= float(n - 1)) {
                        const int mc = std::min(int(fc), n - 2);
                        const float wc = fc - float(mc);
                        const size_t u = upBase + size_t(jb) * stride[b] + size_t(mc) * stride[c];
                        const size_t u10 = u + stride[b], u01 = u + stride[c], u11 = u10 + stride[c];
                        const float w00 = (1 - wb) * (1 - wc), w10 = wb * (1 - wc), w01 = (1 - wb) * wc, w11 = wb * wc;
                        tauUp = w00 * tau[u] + w10 * tau[u10] + w01 * tau[u01] + w11 * tau[u11];
                        sigmaUp = w00 * sigma[u] + w10 * sigma[u10] + w01 * sigma[u01] + w11 * sigma[u11];
                    }
                    tau[i] = tauUp + 0.5f * (sigma[i] + sigmaUp) * segmentKm;
                }
            }
        });
    }
    // Visibility: exp(-optical depth), times the core's shadow, with the strength applied.
    const float rCore = k.rInnerKm;
    const Vec3 light = k.lightDir;
    const bool core = k.drawCore;
    tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& zs) {
        for (int iz = zs.begin(); iz != zs.end(); ++iz)
            for (int iy = 0; iy < n; ++iy) {
                int xFirst, xLast;
                rowSpan(coord(iz) * coord(iz) + coord(iy) * coord(iy), xFirst, xLast);
                for (int ix = 0; ix < n; ++ix) {
                    if (ix < xFirst || ix > xLast) {
                        tau[(size_t(iz) * size_t(n) + size_t(iy)) * size_t(n) + size_t(ix)] = 1.0f;
                        continue;
                    }
                    const size_t i = (size_t(iz) * size_t(n) + size_t(iy)) * size_t(n) + size_t(ix);
                    float visible = std::exp(-tau[i]);
                    if (core) {
                        // Behind the core's centre plane, within its cylinder (edge one cell wide).
                        const Vec3 p{o + float(ix) * h, o + float(iy) * h, o + float(iz) * h};
                        const float along = dot(p, light);
                        if (along < 0.0f) {
                            const float off = std::sqrt(std::max(0.0f, dot(p, p) - along * along));
                            visible *= std::clamp((off - rCore) / h + 0.5f, 0.0f, 1.0f);
                        }
                    }
                    tau[i] = 1.0f - strength * (1.0f - visible);
                }
            }
    });
}

// The mean over the six axis directions of exp(-optical depth over kAmbientReachKm), the optical
// depth by the trapezoid rule over the nodes from prefix sums along each axis.
void ShadowVolume::buildAmbient(float strength)
{
    const int n = m_n;
    const size_t count = size_t(n) * size_t(n) * size_t(n);
    m_ambient.assign(count, 0.0f);
    const int reach = std::max(1, int(std::lround(kAmbientReachKm / m_cellKm)));
    const float h = m_cellKm;  // the reach is rounded to whole cells
    const std::vector<float>& sigma = m_sigma;
    const size_t stride[3] = {1, size_t(n), size_t(n) * size_t(n)};
    for (int a = 0; a < 3; ++a) {
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& js) {
            std::vector<double> prefix(static_cast<size_t>(n) + 1);
            std::vector<float> line(static_cast<size_t>(n));
            for (int j = js.begin(); j != js.end(); ++j)
                for (int m = 0; m < n; ++m) {
                    const size_t base = size_t(j) * stride[b] + size_t(m) * stride[c];
                    prefix[0] = 0;
                    for (int i = 0; i < n; ++i) {
                        line[size_t(i)] = sigma[base + size_t(i) * stride[a]];
                        prefix[size_t(i) + 1] = prefix[size_t(i)] + line[size_t(i)];
                    }
                    if (prefix[size_t(n)] == 0.0) {
                        for (int i = 0; i < n; ++i)
                            m_ambient[base + size_t(i) * stride[a]] += 2.0f;
                        continue;
                    }
                    auto at = [&](int i) { return i >= 0 && i < n ? line[size_t(i)] : 0.0f; };
                    for (int i = 0; i < n; ++i) {
                        // Trapezoid over [i, i + reach] and [i - reach, i] (0 beyond the grid).
                        const int hi = std::min(i + reach, n - 1), lo = std::max(i - reach, 0);
                        const double up = prefix[size_t(hi) + 1] - prefix[size_t(i)] - 0.5 * (at(i) + at(i + reach));
                        const double down = prefix[size_t(i) + 1] - prefix[size_t(lo)] - 0.5 * (at(i) + at(i - reach));
                        m_ambient[base + size_t(i) * stride[a]] +=
                            std::exp(-float(up) * h) + std::exp(-float(down) * h);
                    }
                }
        });
    }
    for (float& v : m_ambient)
        v = 1.0f - strength * (1.0f - v / 6.0f);
}

}  // namespace raypc::render
