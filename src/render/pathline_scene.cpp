#include "render/pathline_scene.h"

#include "core/error.h"
#include "core/spherical.h"
#include "render/render_kernel.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>

namespace raypc::render {
namespace {

// One Embree device for the process: devices are heavy (thread pools), scenes are cheap.
RTCDevice sharedDevice()
{
    static RTCDevice device = [] {
        RTCDevice d = rtcNewDevice(nullptr);
        if (!d)
            fail("Embree: cannot create a device (error {})", int(rtcGetDeviceError(nullptr)));
        return d;
    }();
    return device;
}

constexpr int kColorTableSize = 1024;

std::string columnList(const std::vector<std::string>& columns)
{
    std::string s;
    for (const auto& c : columns)
        s += (s.empty() ? "" : ", ") + c;
    return s;
}

}  // namespace

struct PathlineScene::Impl {
    explicit Impl(std::shared_ptr<const std::vector<analysis::PathlineSet>> sets) : lines(std::move(sets)) {}

    PathlineLines lines;
    // Per segment (Embree primID): its line; per vertex: the point's time (Myr).
    std::vector<uint32_t> segmentLine;
    std::vector<float> vertexTimeMyr;
    std::vector<uint32_t> segmentStart;  // first vertex of each segment (the index buffer's contents)
    float boundRadiusKm = 0;             // all vertices lie within this distance of the origin

    RTCScene scene = nullptr;
    RTCGeometry geometry = nullptr;
    float* vertices = nullptr;  // Embree-owned: x, y, z, radius per vertex
    size_t vertexCount = 0;
    float radiusKm = 12;

    std::vector<uint8_t> mask;
    size_t visible = 0;
    PathlineStyle style;
    float colorTable[kColorTableSize][3]{};

    ~Impl()
    {
        if (geometry)
            rtcReleaseGeometry(geometry);
        if (scene)
            rtcReleaseScene(scene);
    }

    void bakeColors()
    {
        for (int i = 0; i < kColorTableSize; ++i) {
            const Rgb c = sampleColorMap(style.colorMap, float(i) / float(kColorTableSize - 1));
            colorTable[i][0] = c.r;
            colorTable[i][1] = c.g;
            colorTable[i][2] = c.b;
        }
    }

    // Rejects hits on hidden lines, for primary and occlusion rays alike.
    static void filter(const RTCFilterFunctionNArguments* args)
    {
        const Impl& im = *static_cast<const Impl*>(args->geometryUserPtr);
        for (unsigned i = 0; i < args->N; ++i) {
            if (args->valid[i] != -1)
                continue;
            const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
            if (!im.mask[im.segmentLine[prim]])
                args->valid[i] = 0;
        }
    }
};

namespace {

// Cosine-weighted direction around the unit normal n from two uniform numbers (Malley's method).
Vec3 cosineDirection(Vec3 n, float u1, float u2)
{
    const Vec3 a = std::abs(n.x) < 0.9f ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    const Vec3 t = normalize(cross(n, a));
    const Vec3 b = cross(n, t);
    const float r = std::sqrt(u1), phi = 2.0f * std::numbers::pi_v<float> * u2;
    const float z = std::sqrt(std::max(0.0f, 1.0f - u1));
    return t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + n * z;
}

// The closest visible tube along the ray, shaded: colour map of age or attribute, Lambert with the
// volume's light and weights, times ambient occlusion from a few rays against the tubes and the core.
kernel::TubeHit traceTubes(const void* ctx, const kernel::KernelParams& k, Vec3 o, Vec3 d, float tMaxKm, int px,
                           int py) noexcept
{
    const PathlineScene::Impl& im = *static_cast<const PathlineScene::Impl*>(ctx);
    float tIn, tOut;
    if (!intersectSphere(o, d, im.boundRadiusKm, tIn, tOut) || tOut < 0.0f)
        return {};
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh{};
    rh.ray.org_x = o.x;
    rh.ray.org_y = o.y;
    rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x;
    rh.ray.dir_y = d.y;
    rh.ray.dir_z = d.z;
    rh.ray.tnear = std::max(0.0f, tIn);
    rh.ray.tfar = std::min(tMaxKm, tOut);
    rh.ray.mask = 0xffffffffu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    if (!(rh.ray.tnear < rh.ray.tfar))
        return {};
    rtcIntersect1(im.scene, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return {};

    kernel::TubeHit hit;
    hit.tKm = rh.ray.tfar;
    const uint32_t prim = rh.hit.primID;
    const uint32_t line = im.segmentLine[prim];
    float value;
    if (im.style.colorColumn < 0) {
        const uint32_t v0 = im.segmentStart[prim];
        const float u = std::clamp(rh.hit.u, 0.0f, 1.0f);
        value = im.vertexTimeMyr[v0] + u * (im.vertexTimeMyr[v0 + 1] - im.vertexTimeMyr[v0]) -
                float(im.lines.injectionTimeMyr(line));
    } else {
        value = im.lines.attribute(line, size_t(im.style.colorColumn));
    }
    const float span = im.style.range.max - im.style.range.min;
    const float pos = std::isfinite(value) ? std::clamp((value - im.style.range.min) / span, 0.0f, 1.0f) : 0.0f;
    const float* c = im.colorTable[int(pos * float(kColorTableSize - 1) + 0.5f)];

    Vec3 n{rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
    const float nl = length(n);
    n = nl > 0.0f ? n * (1.0f / nl) : d * -1.0f;
    if (dot(n, d) > 0.0f)
        n = n * -1.0f;
    // The volume (and other tubes) shadow the tube: the light's visibility looked up two shadow
    // cells towards the light, beyond the cells this tube's own splat reaches (shadow_volume.h).
    float lightVisible = 1.0f;
    if (k.shadowLight) {
        const Vec3 q = o + d * hit.tKm + k.lightDir * (2.0f * k.shadowLightBiasKm);
        lightVisible = kernel::shadowGridAt(k, k.shadowLight, (q.x - k.shadowOriginKm) * k.shadowInvKm,
                                            (q.y - k.shadowOriginKm) * k.shadowInvKm,
                                            (q.z - k.shadowOriginKm) * k.shadowInvKm);
    }
    float shade = k.ambient + k.diffuse * std::max(0.0f, dot(n, k.lightDir)) * lightVisible;

    if (im.style.ambientOcclusion && im.style.aoRays > 0) {
        const Vec3 p = o + d * hit.tKm + n * std::max(0.01f * im.radiusKm, 0.01f);
        const float reach = im.style.aoDistanceFactor * im.radiusKm;
        int occluded = 0;
        for (int i = 0; i < im.style.aoRays; ++i) {
            const uint32_t h1 = kernel::hash32(uint32_t(px) * 73856093u ^ uint32_t(py) * 19349663u ^
                                               uint32_t(k.pass * im.style.aoRays + i) * 83492791u ^ k.seed);
            const uint32_t h2 = kernel::hash32(h1 ^ 0x68bc21ebu);
            const Vec3 dir = cosineDirection(n, float(h1 >> 8) * (1.0f / 16777216.0f),
                                             float(h2 >> 8) * (1.0f / 16777216.0f));
            float c0, c1;
            if (k.drawCore && intersectSphere(p, dir, k.rInnerKm, c0, c1) && c1 > 0.0f && c0 < reach) {
                ++occluded;
                continue;
            }
            RTCRay ray{};
            ray.org_x = p.x;
            ray.org_y = p.y;
            ray.org_z = p.z;
            ray.dir_x = dir.x;
            ray.dir_y = dir.y;
            ray.dir_z = dir.z;
            ray.tnear = 0.0f;
            ray.tfar = reach;
            ray.mask = 0xffffffffu;
            RTCIntersectContext oc;
            rtcInitIntersectContext(&oc);
            rtcOccluded1(im.scene, &oc, &ray);
            occluded += ray.tfar < 0.0f;  // Embree sets tfar = -inf on an occlusion
        }
        const float open = 1.0f - float(occluded) / float(im.style.aoRays);
        shade *= 0.25f + 0.75f * open;
    }
    hit.color = {c[0] * shade, c[1] * shade, c[2] * shade};
    return hit;
}

}  // namespace

PathlineLines::PathlineLines(std::shared_ptr<const std::vector<analysis::PathlineSet>> sets) : m_sets(std::move(sets))
{
    const std::vector<analysis::PathlineSet>& all = *m_sets;
    for (size_t s = 0; s < all.size(); ++s) {
        const analysis::PathlineSet& set = all[s];
        if (s == 0)
            m_columns = set.columns;
        else if (set.columns != m_columns)
            fail("pathlines: the set of step {} has columns ({}), the set of step {} has ({})", set.injectionStep,
                 columnList(set.columns), all[0].injectionStep, columnList(m_columns));
        if (set.lineCount() > 0 && (set.offsets.back() != set.pointCount() || set.offsets.front() != 0))
            fail("pathlines: the set of step {} has offsets ending at {} for {} points", set.injectionStep,
                 set.offsets.back(), set.pointCount());
        if (set.attributes.size() != set.lineCount() * set.columns.size())
            fail("pathlines: the set of step {} has {} attribute values, expected {} lines x {} columns",
                 set.injectionStep, set.attributes.size(), set.lineCount(), set.columns.size());
        for (uint32_t i = 0; i < set.lineCount(); ++i) {
            if (set.offsets[i + 1] < set.offsets[i])
                fail("pathlines: the set of step {} has decreasing offsets at line {}", set.injectionStep, i);
            m_lineSet.push_back(uint32_t(s));
            m_lineLocal.push_back(i);
            for (size_t p = set.offsets[i]; p < set.offsets[i + 1]; ++p)
                m_maxAgeMyr = std::max(m_maxAgeMyr, set.points[4 * p + 3] - float(set.injectionTimeMyr));
        }
    }

    // Step length: from the injection times of distinct steps, else from the lines that reached
    // their end step in a single set.
    int s0 = std::numeric_limits<int>::max(), s1 = std::numeric_limits<int>::min();
    double t0 = 0, t1 = 0;
    for (const analysis::PathlineSet& set : all) {
        if (set.injectionStep < s0)
            s0 = set.injectionStep, t0 = set.injectionTimeMyr;
        if (set.injectionStep > s1)
            s1 = set.injectionStep, t1 = set.injectionTimeMyr;
    }
    if (!all.empty() && s1 > s0) {
        m_stepMyr = (t1 - t0) / double(s1 - s0);
    } else if (!all.empty()) {
        const analysis::PathlineSet& set = all.front();
        const int duration = set.column(columns::pathline::kDuration), reason = set.column(columns::pathline::kEndReason);
        double longest = 0;
        for (size_t i = 0; duration >= 0 && i < set.lineCount(); ++i)
            if (reason < 0 || set.attribute(i, size_t(reason)) == float(analysis::PathlineEnd::ReachedEndTime))
                longest = std::max(longest, double(set.attribute(i, size_t(duration))));
        if (set.endStep > set.injectionStep && longest > 0)
            m_stepMyr = longest / double(set.endStep - set.injectionStep);
    }
}

std::span<const float> PathlineLines::points(size_t line) const
{
    const analysis::PathlineSet& s = set(line);
    const size_t first = s.offsets[m_lineLocal[line]], last = s.offsets[m_lineLocal[line] + 1];
    return std::span<const float>(s.points).subspan(4 * first, 4 * (last - first));
}

float PathlineLines::colorValue(const PathlineStyle& style, size_t line, size_t point) const
{
    if (style.colorColumn >= 0)
        return attribute(line, size_t(style.colorColumn));
    return points(line)[4 * point + 3] - float(injectionTimeMyr(line));
}

LegendSpec pathlineLegend(const PathlineStyle& style, const std::vector<std::string>& columns)
{
    const std::string what = style.colorColumn < 0 ? std::string("pathline age [Myr]")
                                                   : "pathlines: " + columns.at(size_t(style.colorColumn));
    // The tubes map their range linearly, not centred on 0: the map's stops.
    TransferFunction colors;
    const auto stops = state::colorMapStops(style.colorMap);
    colors.colorPoints.assign(stops.begin(), stops.end());
    colors.range = style.range;
    return {what, colors, {}};
}

PathlineScene::PathlineScene(std::vector<analysis::PathlineSet> sets, float radiusKm)
    : PathlineScene(std::make_shared<const std::vector<analysis::PathlineSet>>(std::move(sets)), radiusKm)
{
}

PathlineScene::PathlineScene(std::shared_ptr<const std::vector<analysis::PathlineSet>> sets, float radiusKm)
{
    if (!(radiusKm > 0.0f) || !std::isfinite(radiusKm))
        fail("pathlines: tube radius {} km, expected a positive number", radiusKm);
    m_impl = std::make_unique<Impl>(std::move(sets));
    Impl& im = *m_impl;
    im.radiusKm = radiusKm;
    const PathlineLines& lines = im.lines;

    // Global numbering of segments and vertices.
    size_t segments = 0, vertices = 0;
    for (size_t line = 0; line < lines.lineCount(); ++line) {
        const size_t n = lines.points(line).size() / 4;
        if (n >= 2) {
            segments += n - 1;
            vertices += n;
        }
    }
    im.mask.assign(lines.lineCount(), 1);
    im.visible = lines.lineCount();
    im.vertexCount = vertices;

    im.scene = rtcNewScene(sharedDevice());
    rtcSetSceneBuildQuality(im.scene, RTC_BUILD_QUALITY_MEDIUM);
    if (segments > 0) {
        im.geometry = rtcNewGeometry(sharedDevice(), RTC_GEOMETRY_TYPE_ROUND_LINEAR_CURVE);
        im.vertices = static_cast<float*>(rtcSetNewGeometryBuffer(im.geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                                  RTC_FORMAT_FLOAT4, 4 * sizeof(float), vertices));
        auto* index = static_cast<uint32_t*>(
            rtcSetNewGeometryBuffer(im.geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, sizeof(uint32_t), segments));
        if (!im.vertices || !index)
            fail("Embree: cannot allocate buffers for {} tube segments (error {})", segments,
                 int(rtcGetDeviceError(sharedDevice())));
        im.vertexTimeMyr.reserve(vertices);
        im.segmentLine.reserve(segments);
        im.segmentStart.reserve(segments);
        float bound = 0;
        size_t v = 0;
        for (uint32_t line = 0; line < lines.lineCount(); ++line) {
            const std::span<const float> points = lines.points(line);
            const size_t n = points.size() / 4;
            if (n < 2)
                continue;
            for (size_t p = 0; p < n; ++p, ++v) {
                const float* q = &points[4 * p];
                im.vertices[4 * v] = q[0];
                im.vertices[4 * v + 1] = q[1];
                im.vertices[4 * v + 2] = q[2];
                im.vertices[4 * v + 3] = radiusKm;
                im.vertexTimeMyr.push_back(q[3]);
                bound = std::max(bound, std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]));
                if (p + 1 < n) {
                    index[im.segmentStart.size()] = uint32_t(v);
                    im.segmentStart.push_back(uint32_t(v));
                    im.segmentLine.push_back(line);
                }
            }
        }
        im.boundRadiusKm = bound;
        rtcSetGeometryUserData(im.geometry, &im);
        rtcSetGeometryIntersectFilterFunction(im.geometry, &Impl::filter);
        rtcSetGeometryOccludedFilterFunction(im.geometry, &Impl::filter);
        rtcCommitGeometry(im.geometry);
        rtcAttachGeometry(im.scene, im.geometry);
    }
    rtcCommitScene(im.scene);
    if (const RTCError e = rtcGetDeviceError(sharedDevice()); e != RTC_ERROR_NONE)
        fail("Embree: building the tube scene of {} segments failed (error {})", segments, int(e));
    im.boundRadiusKm += radiusKm;
    im.style.range = {0.0f, float(lines.stepMyr() > 0 ? 10.0 * lines.stepMyr() : std::max(1.0f, lines.maxAgeMyr()))};
    im.bakeColors();
}

PathlineScene::~PathlineScene() = default;

const std::vector<analysis::PathlineSet>& PathlineScene::sets() const { return m_impl->lines.sets(); }
const PathlineLines& PathlineScene::lines() const { return m_impl->lines; }
size_t PathlineScene::lineCount() const { return m_impl->lines.lineCount(); }
const std::vector<std::string>& PathlineScene::columns() const { return m_impl->lines.columns(); }
float PathlineScene::attribute(size_t line, size_t column) const { return m_impl->lines.attribute(line, column); }
int PathlineScene::injectionStep(size_t line) const { return m_impl->lines.injectionStep(line); }
double PathlineScene::stepMyr() const { return m_impl->lines.stepMyr(); }

std::vector<uint8_t> PathlineScene::visibilityFor(const state::RenderState& state) const { return m_impl->lines.visibilityFor(state); }

PathlineStyle PathlineScene::styleFor(const state::PathlineState& state) const
{
    // The tracer's settings (occlusion rays and reach) are the scene's own.
    PathlineStyle style = m_impl->lines.styleFor(state);
    style.aoRays = m_impl->style.aoRays;
    style.aoDistanceFactor = m_impl->style.aoDistanceFactor;
    return style;
}

std::vector<uint8_t> PathlineLines::visibilityFor(const state::RenderState& state) const
{
    const state::PathlineState& pl = state.pathlines;
    std::vector<uint8_t> mask(lineCount(), 0);
    if (!pl.visible)
        return mask;
    auto columnOf = [&](const std::string& name, const std::string& role) {
        const auto it = std::find(m_columns.begin(), m_columns.end(), name);
        if (it == m_columns.end())
            fail("pathlines: {}: the lines have no attribute '{}'; they have: {}", role, name, columnList(m_columns));
        return size_t(it - m_columns.begin());
    };
    // Each test: a column, or a coordinate computed from the start position (filter.coordinate),
    // and the filter's ranges, OR-ed.
    struct Test {
        int column = -1;  // -1: filter.coordinate
        analysis::RangeFilter filter;
    };
    std::vector<Test> tests;
    if (pl.filterByBrushes) {
        for (analysis::NamedRanges& b : analysis::groupRanges(state.brushes, "brushes")) {
            Test t{-1, {-1, grid::findCoordinate(b.name), std::move(b.ranges)}};
            if (!t.filter.coordinate)
                t.column = int(columnOf("start " + b.name, "brush '" + b.name + "'"));
            tests.push_back(std::move(t));
        }
    }
    for (analysis::NamedRanges& f : analysis::groupRanges(pl.filters, "filters")) {
        const auto first = std::find_if(pl.filters.begin(), pl.filters.end(),
                                        [&](const state::PathlineFilter& x) { return x.name == f.name; });
        tests.push_back({int(columnOf(f.name, fmt::format("filters[{}]", first - pl.filters.begin()))),
                         {-1, std::nullopt, std::move(f.ranges)}});
    }
    const bool needStart = std::any_of(tests.begin(), tests.end(), [](const Test& t) { return t.column < 0; });
    const size_t cLat = needStart ? columnOf(columns::pathline::kStartLat, "brushes") : 0;
    const size_t cLon = needStart ? columnOf(columns::pathline::kStartLon, "brushes") : 0;
    const size_t cR = needStart ? columnOf(columns::pathline::kStartRadius, "brushes") : 0;

    for (size_t line = 0; line < lineCount(); ++line) {
        const int injected = injectionStep(line);
        if (injected > state.step || injected < state.step - pl.window + 1)
            continue;
        bool inside = true;
        for (const Test& t : tests) {
            double v;
            if (t.column >= 0) {
                v = attribute(line, size_t(t.column));
            } else {
                const double lat = attribute(line, cLat), lon = wrapLonDeg(attribute(line, cLon)),
                             r = attribute(line, cR);
                v = grid::coordinateValue(*t.filter.coordinate, lat, lon, r);
            }
            if (!t.filter.contains(v)) {
                inside = false;
                break;
            }
        }
        mask[line] = inside;
    }
    return mask;
}

PathlineStyle PathlineLines::styleFor(const state::PathlineState& pl) const
{
    PathlineStyle style;
    style.colorMap = pl.effectiveColorMap();
    style.ambientOcclusion = pl.ambientOcclusion;
    if (pl.colorBy == "age") {
        style.colorColumn = -1;
        const double span = m_stepMyr > 0 ? double(pl.window) * m_stepMyr : std::max(1.0, double(m_maxAgeMyr));
        style.range = pl.range ? *pl.range : dataset::ValueRange{0.0f, float(span)};
        return style;
    }
    const auto it = std::find(m_columns.begin(), m_columns.end(), pl.colorBy);
    if (it == m_columns.end())
        fail("pathlines: colorBy '{}' is neither \"age\" nor a line attribute; the lines have: {}", pl.colorBy,
             columnList(m_columns));
    style.colorColumn = int(it - m_columns.begin());
    if (pl.range) {
        style.range = *pl.range;
        return style;
    }
    float lo = INFINITY, hi = -INFINITY;
    for (size_t line = 0; line < lineCount(); ++line) {
        const float v = attribute(line, size_t(style.colorColumn));
        if (std::isfinite(v))
            lo = std::min(lo, v), hi = std::max(hi, v);
    }
    if (!(lo <= hi))
        lo = 0, hi = 1;
    style.range = defaultColorRange(dataset::ValueRange{lo, hi}, state::isCentredOnZero(style.colorMap));
    return style;
}

size_t PathlineScene::applyState(const state::RenderState& state)
{
    // Everything is computed before anything changes, so a bad state leaves the scene as it was.
    PathlineStyle style = styleFor(state.pathlines);
    std::vector<uint8_t> mask = visibilityFor(state);
    if (!(state.pathlines.radiusKm > 0.0f))
        fail("pathlines: radiusKm {}: expected a positive number", state.pathlines.radiusKm);
    if (state.pathlines.radiusKm != m_impl->radiusKm)
        setRadiusKm(state.pathlines.radiusKm);
    setStyle(style);
    return setVisibility(std::move(mask));
}

size_t PathlineScene::setVisibility(std::vector<uint8_t> mask)
{
    if (mask.size() != lineCount())
        fail("pathlines: visibility mask of {} entries for {} lines", mask.size(), lineCount());
    m_impl->mask = std::move(mask);
    m_impl->visible = size_t(std::count_if(m_impl->mask.begin(), m_impl->mask.end(), [](uint8_t b) { return b != 0; }));
    return m_impl->visible;
}

const std::vector<uint8_t>& PathlineScene::visibility() const { return m_impl->mask; }
size_t PathlineScene::visibleCount() const { return m_impl->visible; }

void PathlineScene::setStyle(const PathlineStyle& style)
{
    if (!(style.range.min < style.range.max))
        fail("pathlines: colour range [{}, {}]: expected min < max", style.range.min, style.range.max);
    if (style.colorColumn >= int(m_impl->lines.columns().size()))
        fail("pathlines: colour column {} of {}", style.colorColumn, m_impl->lines.columns().size());
    m_impl->style = style;
    m_impl->bakeColors();
}

const PathlineStyle& PathlineScene::style() const { return m_impl->style; }

void PathlineScene::setRadiusKm(float radiusKm)
{
    Impl& im = *m_impl;
    if (!(radiusKm > 0.0f) || !std::isfinite(radiusKm))
        fail("pathlines: tube radius {} km, expected a positive number", radiusKm);
    im.boundRadiusKm += radiusKm - im.radiusKm;
    im.radiusKm = radiusKm;
    if (!im.geometry)
        return;
    for (size_t v = 0; v < im.vertexCount; ++v)
        im.vertices[4 * v + 3] = radiusKm;
    rtcUpdateGeometryBuffer(im.geometry, RTC_BUFFER_TYPE_VERTEX, 0);
    rtcCommitGeometry(im.geometry);
    rtcCommitScene(im.scene);
}

float PathlineScene::radiusKm() const { return m_impl->radiusKm; }

void PathlineScene::bind(kernel::KernelParams& k) const
{
    if (m_impl->visible == 0 || !m_impl->geometry) {
        k.traceTubes = nullptr;
        k.tubeContext = nullptr;
        return;
    }
    k.traceTubes = &traceTubes;
    k.tubeContext = m_impl.get();
}

}  // namespace raypc::render
