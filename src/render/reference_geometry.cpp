#include "render/reference_geometry.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/install_paths.h"
#include "core/json_input.h"
#include "core/spherical.h"
#include "render/line_raster.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <mutex>

namespace raypc::render {
namespace fs = std::filesystem;

size_t Coastlines::pointCount() const
{
    size_t n = 0;
    for (const auto& l : lines)
        n += l.size();
    return n;
}

Coastlines readCoastlines(const fs::path& file)
{
    const nlohmann::json j = parseJsonInput(readFile(file), file.string());
    if (!j.is_object() || !j.contains("lines") || !j["lines"].is_array())
        fail("{}: expected an object with \"lines\": [[lon, lat, ...], ...]", file.string());
    Coastlines c;
    for (size_t i = 0; i < j["lines"].size(); ++i) {
        const auto& line = j["lines"][i];
        if (!line.is_array() || line.size() % 2 != 0 || line.size() < 4)
            fail("{}: lines[{}]: expected an even number (at least 4) of numbers lon, lat, ...", file.string(), i);
        std::vector<std::pair<float, float>> points;
        for (size_t k = 0; k < line.size(); k += 2) {
            if (!line[k].is_number() || !line[k + 1].is_number())
                fail("{}: lines[{}][{}]: expected numbers", file.string(), i, k);
            const double lon = line[k].get<double>(), lat = line[k + 1].get<double>();
            if (!(lat >= -90 && lat <= 90 && lon >= -360 && lon <= 360))
                fail("{}: lines[{}]: point ({}, {}) is not a longitude, latitude in degrees", file.string(), i, lon, lat);
            points.emplace_back(float(lon), float(lat));
        }
        c.lines.push_back(std::move(points));
    }
    return c;
}

std::shared_ptr<const Coastlines> defaultCoastlines()
{
    static std::mutex mutex;
    static std::shared_ptr<const Coastlines> loaded;
    const std::lock_guard lock(mutex);
    if (loaded)
        return loaded;
    std::error_code ec;
    if (const char* env = std::getenv("RAYPC_COASTLINES"); env && *env) {
        if (!fs::is_regular_file(env, ec))
            fail("reference.coastlines: RAYPC_COASTLINES={} is not a file", env);
        loaded = std::make_shared<const Coastlines>(readCoastlines(env));
        return loaded;
    }
    // The UI build writes coastlines.json beside the UI's files.
    std::string looked;
    for (const auto& dir : uiAssetCandidates()) {
        const fs::path file = dir / "coastlines.json";
        if (fs::is_regular_file(file, ec)) {
            loaded = std::make_shared<const Coastlines>(readCoastlines(file));
            return loaded;
        }
        looked += (looked.empty() ? "" : ", ") + file.string();
    }
    fail("reference.coastlines: no coastline file (the UI build writes coastlines.json: scripts/build-web.sh); "
         "looked in {}",
         looked);
}

namespace {

using Fragment = ReferenceLayer::Fragment;

Vec3 onSphere(float lonDeg, float latDeg, float radiusKm)
{
    const float lat = latDeg * float(M_PI / 180.0), lon = lonDeg * float(M_PI / 180.0);
    return {radiusKm * std::cos(lat) * std::cos(lon), radiusKm * std::cos(lat) * std::sin(lon), radiusKm * std::sin(lat)};
}

// A polyline on the sphere of radius `radiusKm`, subdivided to at most 1 degree per segment so that
// it follows the sphere; only segments wholly on the near side of the sphere are drawn.
void drawPolyline(LineLayer& layer, const CameraFrame& cam, const std::vector<std::pair<float, float>>& lonLat,
                  float radiusKm, float widthPx)
{
    auto visible = [&](Vec3 p) { return dot(p, cam.eye - p) > 0.0f; };
    for (size_t k = 1; k < lonLat.size(); ++k) {
        auto [lonA, latA] = lonLat[k - 1];
        auto [lonB, latB] = lonLat[k];
        if (lonB - lonA > 180.0f)
            lonB -= 360.0f;  // across the date line the short way
        else if (lonA - lonB > 180.0f)
            lonB += 360.0f;
        const int pieces = std::max(1, int(std::ceil(std::max(std::abs(lonB - lonA), std::abs(latB - latA)))));
        Vec3 prev = onSphere(lonA, latA, radiusKm);
        for (int s = 1; s <= pieces; ++s) {
            const float w = float(s) / float(pieces);
            const Vec3 next = onSphere(lonA + w * (lonB - lonA), latA + w * (latB - latA), radiusKm);
            float x0, y0, t0, x1, y1, t1;
            if (visible(prev) && visible(next) && cam.project(prev, x0, y0, t0) && cam.project(next, x1, y1, t1))
                drawSegment(layer, x0, y0, t0, x1, y1, t1, widthPx);
            prev = next;
        }
    }
}

// Whether a shell at `depthKm` lies inside the drawn shell of the planet.
bool shellDrawn(float depthKm, float surfaceRadiusKm, float coreRadiusKm)
{
    const float r = float(kSurfaceRadiusKm) - depthKm;
    return r > coreRadiusKm && r <= surfaceRadiusKm + 1e-3f;
}

std::string depthText(float depthKm) { return fmt::format("{:g} km", depthKm); }

// The shells' palette in the order of shells.depthsKm (see shellColor).
std::span<const Rgb> shellPalette()
{
    static constexpr std::array<Rgb, 5> kPalette{{{0.96f, 0.88f, 0.25f},    // yellow
                                                  {0.35f, 0.90f, 0.45f},    // green
                                                  {0.95f, 0.45f, 0.90f},    // magenta
                                                  {1.00f, 0.62f, 0.15f},    // orange
                                                  {0.70f, 0.62f, 1.00f}}};  // violet
    return kPalette;
}

}  // namespace

Rgb shellColor(const state::ReferenceState::Shells& shells, size_t index)
{
    const auto palette = shellPalette();
    const Rgb p = palette[index % palette.size()];
    return {p.r * shells.color.r, p.g * shells.color.g, p.b * shells.color.b};
}

std::vector<TextLabel> shellKey(const state::ReferenceState& reference, float surfaceRadiusKm, float coreRadiusKm)
{
    std::vector<TextLabel> key;
    const auto& shells = reference.shells;
    if (!shells.visible || shells.opacity <= 0)
        return key;
    for (size_t k = 0; k < shells.depthsKm.size(); ++k)
        if (shellDrawn(shells.depthsKm[k], surfaceRadiusKm, coreRadiusKm))
            key.push_back({depthText(shells.depthsKm[k]), 0, 0, shellColor(shells, k)});
    return key;
}

std::vector<TextLabel> shellLabels(const state::ReferenceState& reference, const OrbitCamera& camera, int width, int height,
                                   float surfaceRadiusKm, float coreRadiusKm)
{
    std::vector<TextLabel> labels;
    const auto& shells = reference.shells;
    if (!shells.visible || shells.opacity <= 0)
        return labels;
    const CameraFrame cam(camera, width, height);
    const float eyeDistance = std::sqrt(dot(cam.eye, cam.eye));
    if (eyeDistance <= 0)
        return labels;
    const Vec3 toEye = cam.eye * (1.0f / eyeDistance);
    // The image's right and up directions made orthogonal to the line from the centre to the eye:
    // the plane of the silhouette circles.
    const Vec3 u = normalize(cam.right - toEye * dot(cam.right, toEye));
    const Vec3 v = normalize(cam.up - toEye * dot(cam.up, toEye) - u * dot(cam.up, u));
    // Shells in depth order, each label 13° further clockwise from 40° above the right.
    std::vector<size_t> order;
    for (size_t k = 0; k < shells.depthsKm.size(); ++k)
        if (shellDrawn(shells.depthsKm[k], surfaceRadiusKm, coreRadiusKm))
            order.push_back(k);
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return shells.depthsKm[a] < shells.depthsKm[b]; });
    for (size_t n = 0; n < order.size(); ++n) {
        const size_t k = order[n];
        const float r = float(kSurfaceRadiusKm) - shells.depthsKm[k];
        if (eyeDistance <= r * 1.0001f)
            continue;  // inside the shell: no silhouette
        // The silhouette: the circle where the lines from the eye touch the sphere.
        const float q = r / eyeDistance;
        const Vec3 centre = toEye * (r * q);
        const float rho = r * std::sqrt(1.0f - q * q);
        const float angle = float((40.0 - 13.0 * double(n)) * M_PI / 180.0);
        const Vec3 p = centre + (u * std::cos(angle) + v * std::sin(angle)) * rho;
        float x, y, t;
        if (!cam.project(p, x, y, t) || x < 0 || y < 0 || x >= float(width) || y >= float(height))
            continue;
        labels.push_back({depthText(shells.depthsKm[k]), x, y, shellColor(shells, k)});
    }
    return labels;
}

std::vector<std::array<float, 2>> sphereOutline(const OrbitCamera& camera, int width, int height, float radiusKm,
                                                int points)
{
    std::vector<std::array<float, 2>> outline;
    const CameraFrame cam(camera, width, height);
    const float eyeDistance = std::sqrt(dot(cam.eye, cam.eye));
    if (eyeDistance <= radiusKm * 1.0001f || points < 3)
        return outline;
    // The silhouette circle, as for the shells' labels (shellLabels).
    const Vec3 toEye = cam.eye * (1.0f / eyeDistance);
    const Vec3 u = normalize(cam.right - toEye * dot(cam.right, toEye));
    const Vec3 v = normalize(cam.up - toEye * dot(cam.up, toEye) - u * dot(cam.up, u));
    const float q = radiusKm / eyeDistance;
    const Vec3 centre = toEye * (radiusKm * q);
    const float rho = radiusKm * std::sqrt(1.0f - q * q);
    for (int i = 0; i < points; ++i) {
        const float angle = float(2.0 * M_PI * i / points);
        float x, y, t;
        if (!cam.project(centre + (u * std::cos(angle) + v * std::sin(angle)) * rho, x, y, t))
            return {};
        outline.push_back({x, y});
    }
    return outline;
}

ReferenceLayer::ReferenceLayer(const state::ReferenceState& reference, const OrbitCamera& camera, int width,
                               int height, float surfaceRadiusKm, float coreRadiusKm, const Coastlines* coastlines,
                               const SliceMarks* marks)
    : m_width(width), m_height(height)
{
    if (width < 0 || height < 0)
        fail("reference geometry: an image of {}x{} pixels", width, height);
    const size_t pixels = size_t(width) * size_t(height);
    const auto& shells = reference.shells;
    const auto& graticule = reference.graticule;
    const bool drawCoast = reference.coastlines.visible;
    if (!shells.visible && !graticule.visible && !drawCoast && !marks) {
        m_first.assign(pixels + 1, 0);
        return;
    }
    if (drawCoast && !coastlines)
        fail("reference.coastlines: visible, but no coastlines were given");
    const CameraFrame cam(camera, width, height);

    // Lines: rasterised once into one layer per kind (graticule, coastlines).
    std::optional<LineLayer> graticuleLayer, coastLayer;
    if (graticule.visible && graticule.opacity > 0) {
        graticuleLayer.emplace(width, height);
        const float step = graticule.spacingDeg;
        for (float lat = -90.0f + step; lat < 90.0f - 1e-3f; lat += step) {
            std::vector<std::pair<float, float>> parallel;
            for (int lon = 0; lon <= 360; ++lon)
                parallel.emplace_back(float(lon), lat);
            drawPolyline(*graticuleLayer, cam, parallel, surfaceRadiusKm, reference.lineWidthPx);
        }
        for (float lon = 0.0f; lon < 360.0f - 1e-3f; lon += step) {
            std::vector<std::pair<float, float>> meridian;
            for (int lat = -90; lat <= 90; ++lat)
                meridian.emplace_back(lon, float(lat));
            drawPolyline(*graticuleLayer, cam, meridian, surfaceRadiusKm, reference.lineWidthPx);
        }
    }
    if (drawCoast && reference.coastlines.opacity > 0) {
        coastLayer.emplace(width, height);
        for (const auto& line : coastlines->lines)
            drawPolyline(*coastLayer, cam, line, surfaceRadiusKm, reference.lineWidthPx);
    }

    // The section's curtain: its arc at the surface (the near side only) and at the innermost
    // radius, and the radial lines at its ends (inside the planet: composited by depth).
    std::optional<LineLayer> markLayer;
    if (marks) {
        markLayer.emplace(width, height);
        const Vec3 a = onSphere(marks->from.lonDeg, marks->from.latDeg, 1.0f), b = onSphere(marks->to.lonDeg, marks->to.latDeg, 1.0f);
        const float angle = std::acos(std::clamp(dot(a, b), -1.0f, 1.0f));
        if (angle > 1e-4f && angle < float(M_PI) - 1e-4f) {
            const Vec3 ortho = normalize(b - a * dot(a, b));
            auto at = [&](float f, float r) { return (a * std::cos(f * angle) + ortho * std::sin(f * angle)) * r; };
            auto segment = [&](Vec3 p, Vec3 q, bool nearSideOnly) {
                float x0, y0, t0, x1, y1, t1;
                if (nearSideOnly && (dot(p, cam.eye - p) <= 0 || dot(q, cam.eye - q) <= 0))
                    return;
                if (cam.project(p, x0, y0, t0) && cam.project(q, x1, y1, t1))
                    drawSegment(*markLayer, x0, y0, t0, x1, y1, t1, 1.5f * reference.lineWidthPx);
            };
            const int n = std::max(2, int(std::ceil(angle * 180 / float(M_PI))));
            for (int k = 0; k < n; ++k) {
                const float f0 = float(k) / n, f1 = float(k + 1) / n;
                segment(at(f0, surfaceRadiusKm), at(f1, surfaceRadiusKm), true);
                segment(at(f0, coreRadiusKm), at(f1, coreRadiusKm), false);
            }
            for (const float f : {0.0f, 1.0f})
                for (int k = 0; k < 16; ++k)
                    segment(at(f, coreRadiusKm + (surfaceRadiusKm - coreRadiusKm) * k / 16.0f),
                            at(f, coreRadiusKm + (surfaceRadiusKm - coreRadiusKm) * (k + 1) / 16.0f), false);
        }
    }

    // Shell radii inside the drawn shell of the planet, each with its colour; the map's depth in its own.
    std::vector<std::pair<float, Rgb>> shellRadii;
    if (shells.visible && shells.opacity > 0)
        for (size_t k = 0; k < shells.depthsKm.size(); ++k)
            if (shellDrawn(shells.depthsKm[k], surfaceRadiusKm, coreRadiusKm))
                shellRadii.emplace_back(float(kSurfaceRadiusKm) - shells.depthsKm[k], shellColor(shells, k));
    if (marks && shellDrawn(marks->depthKm, surfaceRadiusKm, coreRadiusKm))
        shellRadii.emplace_back(float(kSurfaceRadiusKm) - marks->depthKm, kSliceMarkColor);
    // Transmittance of a shell seen face-on; along a path 1/|cos| as long, its power.
    const float faceOnTransmittance = 1.0f - std::min(shells.opacity, 0.999f);

    // Each row's fragments, sorted per pixel (rows in parallel), then joined into one array.
    std::vector<std::vector<Fragment>> rows(static_cast<size_t>(height));
    std::vector<uint32_t> counts(pixels);
    tbb::parallel_for(0, height, [&](int y) {
        std::vector<Fragment> fragments;
        std::vector<Fragment>& row = rows[size_t(y)];
        for (int x = 0; x < width; ++x) {
            const size_t i = size_t(y) * size_t(width) + size_t(x);
            fragments.clear();
            if (!shellRadii.empty()) {
                const Vec3 d = cam.direction(float(x) + 0.5f, float(y) + 0.5f);
                for (const auto& [r, color] : shellRadii) {
                    float t0, t1;
                    if (!intersectSphere(cam.eye, d, r, t0, t1))
                        continue;
                    for (float t : {t0, t1}) {
                        if (t <= 0)
                            continue;
                        const Vec3 n = (cam.eye + d * t) * (1.0f / r);
                        const float cosAngle = std::max(std::abs(dot(n, d)), 0.02f);
                        const float a = 1.0f - std::pow(faceOnTransmittance, 1.0f / cosAngle);
                        fragments.push_back({t, color.r * a, color.g * a, color.b * a, a});
                    }
                }
            }
            auto addLine = [&](const std::optional<LineLayer>& layer, float opacity, Rgb c) {
                if (layer && layer->coverage[i] > 0) {
                    const float a = layer->coverage[i] * opacity;
                    fragments.push_back({layer->t[i], c.r * a, c.g * a, c.b * a, a});
                }
            };
            addLine(graticuleLayer, graticule.opacity, graticule.color);
            addLine(coastLayer, reference.coastlines.opacity, reference.coastlines.color);
            addLine(markLayer, 0.95f, kSliceMarkColor);
            std::sort(fragments.begin(), fragments.end(), [](const Fragment& a, const Fragment& b) { return a.t < b.t; });
            counts[i] = uint32_t(fragments.size());
            row.insert(row.end(), fragments.begin(), fragments.end());
        }
    });
    m_first.resize(pixels + 1);
    m_first[0] = 0;
    for (size_t i = 0; i < pixels; ++i)
        m_first[i + 1] = m_first[i] + counts[i];
    m_fragments.resize(m_first[pixels]);
    tbb::parallel_for(0, height, [&](int y) {
        std::copy(rows[size_t(y)].begin(), rows[size_t(y)].end(), m_fragments.begin() + m_first[size_t(y) * size_t(width)]);
    });
}

size_t ReferenceLayer::bytes() const
{
    return m_first.capacity() * sizeof(uint32_t) + m_fragments.capacity() * sizeof(Fragment);
}

void ReferenceLayer::composite(std::vector<float>& rgba, const std::vector<float>& depthKm) const
{
    const size_t pixels = size_t(m_width) * size_t(m_height);
    if (rgba.size() != pixels * 4 || depthKm.size() != pixels)
        fail("reference geometry: image of {} values and depth of {} for {}x{} pixels", rgba.size(), depthKm.size(),
             m_width, m_height);
    if (m_fragments.empty())
        return;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels, 4096), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t i = range.begin(); i < range.end(); ++i) {
            if (m_first[i] == m_first[i + 1])
                continue;
            // Front to back: fragments before the volume's depth, the volume, the fragments behind it.
            float* px = &rgba[i * 4];
            const std::array<float, 4> volume{px[0], px[1], px[2], px[3]};
            std::array<float, 4> acc{0, 0, 0, 0};
            auto over = [&](float r, float g, float b, float a) {
                const float k = 1.0f - acc[3];
                acc[0] += k * r;
                acc[1] += k * g;
                acc[2] += k * b;
                acc[3] += k * a;
            };
            bool volumeDone = false;
            for (uint32_t f = m_first[i]; f < m_first[i + 1]; ++f) {
                const Fragment& fragment = m_fragments[f];
                if (!volumeDone && fragment.t >= depthKm[i]) {
                    over(volume[0], volume[1], volume[2], volume[3]);
                    volumeDone = true;
                }
                over(fragment.r, fragment.g, fragment.b, fragment.a);
            }
            if (!volumeDone)
                over(volume[0], volume[1], volume[2], volume[3]);
            std::copy(acc.begin(), acc.end(), px);
        }
    });
}

void drawReferenceGeometry(const state::ReferenceState& reference, const OrbitCamera& camera, int width, int height,
                           float surfaceRadiusKm, float coreRadiusKm, std::vector<float>& rgba,
                           const std::vector<float>& depthKm, const Coastlines* coastlines, const SliceMarks* marks)
{
    const size_t pixels = size_t(width) * size_t(height);
    if (rgba.size() != pixels * 4 || depthKm.size() != pixels)
        fail("reference geometry: image of {} values and depth of {} for {}x{} pixels", rgba.size(), depthKm.size(),
             width, height);
    ReferenceLayer(reference, camera, width, height, surfaceRadiusKm, coreRadiusKm, coastlines, marks)
        .composite(rgba, depthKm);
}

}  // namespace raypc::render
