#include "render/reference_geometry.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/install_paths.h"
#include "core/json_input.h"
#include "core/spherical.h"

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

// One premultiplied layer of colour at a distance along the pixel's ray.
struct Fragment {
    float t;
    float r, g, b, a;
};

// A line layer: per pixel the strongest coverage drawn and its distance along the ray.
struct LineLayer {
    int width, height;
    std::vector<float> coverage, t;
    LineLayer(int w, int h) : width(w), height(h), coverage(size_t(w) * size_t(h), 0.0f), t(size_t(w) * size_t(h), INFINITY) {}
};

Vec3 onSphere(float lonDeg, float latDeg, float radiusKm)
{
    const float lat = latDeg * float(M_PI / 180.0), lon = lonDeg * float(M_PI / 180.0);
    return {radiusKm * std::cos(lat) * std::cos(lon), radiusKm * std::cos(lat) * std::sin(lon), radiusKm * std::sin(lat)};
}

// An anti-aliased segment: coverage falls off over one pixel beyond half the width.
void drawSegment(LineLayer& layer, float x0, float y0, float t0, float x1, float y1, float t1, float widthPx)
{
    const float half = 0.5f * widthPx;
    const float pad = half + 1.0f;
    const int ix0 = std::max(0, int(std::floor(std::min(x0, x1) - pad)));
    const int ix1 = std::min(layer.width - 1, int(std::ceil(std::max(x0, x1) + pad)));
    const int iy0 = std::max(0, int(std::floor(std::min(y0, y1) - pad)));
    const int iy1 = std::min(layer.height - 1, int(std::ceil(std::max(y0, y1) + pad)));
    const float dx = x1 - x0, dy = y1 - y0;
    const float len2 = dx * dx + dy * dy;
    for (int y = iy0; y <= iy1; ++y)
        for (int x = ix0; x <= ix1; ++x) {
            const float cx = float(x) + 0.5f, cy = float(y) + 0.5f;
            const float u = len2 > 0 ? std::clamp(((cx - x0) * dx + (cy - y0) * dy) / len2, 0.0f, 1.0f) : 0.0f;
            const float ex = x0 + u * dx - cx, ey = y0 + u * dy - cy;
            const float dist = std::sqrt(ex * ex + ey * ey);
            const float c = std::clamp(half + 0.5f - dist, 0.0f, 1.0f);
            if (c <= 0)
                continue;
            const size_t i = size_t(y) * size_t(layer.width) + size_t(x);
            if (c > layer.coverage[i]) {
                layer.coverage[i] = c;
                layer.t[i] = t0 + u * (t1 - t0);
            }
        }
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

}  // namespace

void drawReferenceGeometry(const ReferenceState& reference, const OrbitCamera& camera, int width, int height,
                           float surfaceRadiusKm, float coreRadiusKm, std::vector<float>& rgba,
                           const std::vector<float>& depthKm, const Coastlines* coastlines)
{
    const size_t pixels = size_t(width) * size_t(height);
    if (rgba.size() != pixels * 4 || depthKm.size() != pixels)
        fail("reference geometry: image of {} values and depth of {} for {}x{} pixels", rgba.size(), depthKm.size(),
             width, height);
    const auto& shells = reference.shells;
    const auto& graticule = reference.graticule;
    const bool drawCoast = reference.coastlines.visible;
    if (!shells.visible && !graticule.visible && !drawCoast)
        return;
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

    // Shell radii inside the drawn shell of the planet.
    std::vector<float> shellRadii;
    if (shells.visible && shells.opacity > 0)
        for (float d : shells.depthsKm) {
            const float r = float(kSurfaceRadiusKm) - d;
            if (r > coreRadiusKm && r <= surfaceRadiusKm + 1e-3f)
                shellRadii.push_back(r);
        }
    // Transmittance of a shell seen face-on; along a path 1/|cos| as long, its power.
    const float faceOnTransmittance = 1.0f - std::min(shells.opacity, 0.999f);

    tbb::parallel_for(0, height, [&](int y) {
        std::vector<Fragment> fragments;
        for (int x = 0; x < width; ++x) {
            const size_t i = size_t(y) * size_t(width) + size_t(x);
            fragments.clear();
            if (!shellRadii.empty()) {
                const Vec3 d = cam.direction(float(x) + 0.5f, float(y) + 0.5f);
                for (float r : shellRadii) {
                    float t0, t1;
                    if (!intersectSphere(cam.eye, d, r, t0, t1))
                        continue;
                    for (float t : {t0, t1}) {
                        if (t <= 0)
                            continue;
                        const Vec3 n = (cam.eye + d * t) * (1.0f / r);
                        const float cosAngle = std::max(std::abs(dot(n, d)), 0.02f);
                        const float a = 1.0f - std::pow(faceOnTransmittance, 1.0f / cosAngle);
                        fragments.push_back({t, shells.color.r * a, shells.color.g * a, shells.color.b * a, a});
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
            if (fragments.empty())
                continue;
            std::sort(fragments.begin(), fragments.end(), [](const Fragment& a, const Fragment& b) { return a.t < b.t; });
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
            for (const Fragment& f : fragments) {
                if (!volumeDone && f.t >= depthKm[i]) {
                    over(volume[0], volume[1], volume[2], volume[3]);
                    volumeDone = true;
                }
                over(f.r, f.g, f.b, f.a);
            }
            if (!volumeDone)
                over(volume[0], volume[1], volume[2], volume[3]);
            std::copy(acc.begin(), acc.end(), px);
        }
    });
}

}  // namespace raypc::render
