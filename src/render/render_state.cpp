#include "render/render_state.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <cmath>
#include <set>

namespace raypc::render {
namespace {

using nlohmann::json;

// Strict reading of one JSON object: every key must be consumed; `path` prefixes messages.
class Reader {
public:
    Reader(const json& object, std::string what, std::string path)
        : m_object(object), m_what(std::move(what)), m_path(std::move(path))
    {
        if (!m_object.is_object())
            failAt("", "expected an object, found " + std::string(m_object.type_name()));
    }

    [[noreturn]] void failAt(const std::string& key, const std::string& message) const
    {
        fail("{}: {}: {}", m_what, key.empty() ? (m_path.empty() ? std::string("top level") : m_path) : name(key),
             message);
    }
    std::string name(const std::string& key) const { return m_path.empty() ? key : m_path + "." + key; }
    const std::string& what() const { return m_what; }

    const json* get(const std::string& key)
    {
        m_used.insert(key);
        const auto it = m_object.find(key);
        return it == m_object.end() ? nullptr : &*it;
    }

    double number(const std::string& key, double fallback, double lo = -INFINITY, double hi = INFINITY)
    {
        const json* v = get(key);
        if (!v)
            return fallback;
        if (!v->is_number())
            failAt(key, "expected a number, found " + v->dump());
        const double x = v->get<double>();
        if (!(x >= lo && x <= hi) || !std::isfinite(x))
            failAt(key, fmt::format("expected a number in [{}, {}], found {}", lo, hi, x));
        return x;
    }
    int integer(const std::string& key, int fallback, int lo, int hi)
    {
        const json* v = get(key);
        if (!v)
            return fallback;
        if (!v->is_number_integer())
            failAt(key, "expected an integer, found " + v->dump());
        const auto x = v->get<int64_t>();
        if (x < lo || x > hi)
            failAt(key, fmt::format("expected an integer in [{}, {}], found {}", lo, hi, x));
        return int(x);
    }
    bool boolean(const std::string& key, bool fallback)
    {
        const json* v = get(key);
        if (!v)
            return fallback;
        if (!v->is_boolean())
            failAt(key, "expected true or false, found " + v->dump());
        return v->get<bool>();
    }
    std::string string(const std::string& key, const std::string& fallback)
    {
        const json* v = get(key);
        if (!v || v->is_null())
            return fallback;
        if (!v->is_string())
            failAt(key, "expected a string, found " + v->dump());
        return v->get<std::string>();
    }
    std::vector<double> numbers(const std::string& key, const json& v, size_t count)
    {
        if (!v.is_array() || v.size() != count)
            failAt(key, fmt::format("expected an array of {} numbers, found {}", count, v.dump()));
        std::vector<double> out;
        for (const json& e : v) {
            if (!e.is_number())
                failAt(key, "expected numbers, found " + v.dump());
            out.push_back(e.get<double>());
        }
        return out;
    }
    Rgb colour(const std::string& key, Rgb fallback)
    {
        const json* v = get(key);
        if (!v)
            return fallback;
        const auto c = numbers(key, *v, 3);
        for (double x : c)
            if (!(x >= 0 && x <= 1))
                failAt(key, "expected colour components in [0, 1], found " + v->dump());
        return {float(c[0]), float(c[1]), float(c[2])};
    }
    std::optional<ValueRange> range(const std::string& key)
    {
        const json* v = get(key);
        if (!v || v->is_null())
            return std::nullopt;
        const auto r = numbers(key, *v, 2);
        if (!(r[0] < r[1]))
            failAt(key, fmt::format("expected [min, max] with min < max, found {}", v->dump()));
        return ValueRange{float(r[0]), float(r[1])};
    }
    ColorMapId colorMap(const std::string& key, ColorMapId fallback)
    {
        const json* v = get(key);
        if (!v)
            return fallback;
        if (!v->is_string())
            failAt(key, "expected a colour map name, found " + v->dump());
        try {
            return parseColorMap(v->get<std::string>());
        } catch (const Error& e) {
            failAt(key, e.what());
        }
    }
    Reader child(const std::string& key, const json& v) { return Reader(v, m_what, name(key)); }

    // Throws on keys nobody asked for.
    void finish() const
    {
        for (auto it = m_object.begin(); it != m_object.end(); ++it)
            if (!m_used.count(it.key()))
                failAt(it.key(), "unknown key");
    }

private:
    const json& m_object;
    std::string m_what, m_path;
    std::set<std::string> m_used;
};

json colourJson(Rgb c) { return json::array({c.r, c.g, c.b}); }
json rangeJson(const std::optional<ValueRange>& r)
{
    return r ? json::array({r->min, r->max}) : json(nullptr);
}

}  // namespace

RenderState parseRenderState(const json& j, const std::string& what)
{
    RenderState s;
    Reader top(j, what, "");
    if (!top.get("version"))
        top.failAt("version", fmt::format("missing; expected {}", kRenderStateVersion));
    s.version = top.integer("version", kRenderStateVersion, 1, 1000000);
    if (s.version != 1 && s.version != kRenderStateVersion)
        top.failAt("version", fmt::format("{} is not supported, expected 1 or {}", s.version, kRenderStateVersion));
    s.step = top.integer("step", s.step, 0, 1000000);
    if (const json* c = top.get("camera")) {
        Reader r = top.child("camera", *c);
        s.camera.azimuthDeg = r.number("azimuthDeg", s.camera.azimuthDeg);
        s.camera.elevationDeg = r.number("elevationDeg", s.camera.elevationDeg, -90, 90);
        s.camera.distanceKm = r.number("distanceKm", s.camera.distanceKm, 1e-3, 1e9);
        s.camera.fovYDeg = r.number("fovYDeg", s.camera.fovYDeg, 1e-3, 179.9);
        if (const json* t = r.get("targetKm")) {
            const auto v = r.numbers("targetKm", *t, 3);
            s.camera.targetKm = {float(v[0]), float(v[1]), float(v[2])};
        }
        r.finish();
    }
    if (const json* c = top.get("image")) {
        Reader r = top.child("image", *c);
        s.width = r.integer("width", s.width, 1, 16384);
        s.height = r.integer("height", s.height, 1, 16384);
        r.finish();
    }
    if (const json* c = top.get("color")) {
        Reader r = top.child("color", *c);
        s.colorVariable = r.string("variable", s.colorVariable);
        s.colorMap = r.colorMap("colorMap", s.colorMap);
        s.colorRange = r.range("range");
        s.opacityUnitKm = float(r.number("opacityUnitKm", s.opacityUnitKm, 1e-6, 1e9));
        if (const json* o = r.get("opacity")) {
            if (!o->is_array() || o->empty())
                r.failAt("opacity", "expected an array of [position, opacity] pairs, found " + o->dump());
            s.opacity.clear();
            for (const json& p : *o) {
                const auto v = r.numbers("opacity", p, 2);
                if (!(v[0] >= 0 && v[0] <= 1 && v[1] >= 0 && v[1] <= 1))
                    r.failAt("opacity", "expected position and opacity in [0, 1], found " + p.dump());
                if (!s.opacity.empty() && v[0] < s.opacity.back().position)
                    r.failAt("opacity", "positions must ascend, found " + o->dump());
                s.opacity.push_back({float(v[0]), float(v[1])});
            }
        }
        r.finish();
    }
    if (const json* b = top.get("brushes")) {
        if (!b->is_array())
            top.failAt("brushes", "expected an array, found " + b->dump());
        for (size_t i = 0; i < b->size(); ++i) {
            Reader r = top.child(fmt::format("brushes[{}]", i), (*b)[i]);
            BrushSpec spec;
            spec.name = r.string("name", "");
            if (spec.name.empty())
                r.failAt("name", "missing; expected a variable or coordinate name");
            if (!r.get("min") || !r.get("max"))
                r.failAt(r.get("min") ? "max" : "min", "missing");
            spec.min = float(r.number("min", 0));
            spec.max = float(r.number("max", 0));
            if (!(spec.min <= spec.max))
                r.failAt("min", fmt::format("min {} is greater than max {}", spec.min, spec.max));
            r.finish();
            s.brushes.push_back(spec);
        }
    }
    if (const json* l = top.get("level")) {
        if (l->is_string() && l->get<std::string>() == "auto")
            s.level.reset();
        else
            s.level = top.integer("level", 0, 0, kLevelCount - 1);
    }
    s.timeBudgetMs = top.number("timeBudgetMs", s.timeBudgetMs, 1e-3, 1e7);
    s.passes = top.integer("passes", s.passes, 1, 100000);
    s.stepFactor = float(top.number("stepFactor", s.stepFactor, 0.05, 8));
    s.depthOpacity = float(top.number("depthOpacity", s.depthOpacity, 1e-3, 0.999));
    if (const json* c = top.get("core")) {
        Reader r = top.child("core", *c);
        s.core.visible = r.boolean("visible", s.core.visible);
        s.core.variable = r.string("variable", s.core.variable);
        s.core.colour = r.colour("color", s.core.colour);
        s.core.colorMap = r.colorMap("colorMap", s.core.colorMap);
        s.core.range = r.range("range");
        r.finish();
    }
    if (const json* c = top.get("shading")) {
        Reader r = top.child("shading", *c);
        s.shading.enabled = r.boolean("enabled", s.shading.enabled);
        if (const json* l = r.get("light")) {
            const auto v = r.numbers("light", *l, 3);
            if (v[0] == 0 && v[1] == 0 && v[2] == 0)
                r.failAt("light", "expected a non-zero direction");
            s.shading.lightFromCamera = {float(v[0]), float(v[1]), float(v[2])};
        }
        s.shading.ambient = float(r.number("ambient", s.shading.ambient, 0, 1));
        s.shading.diffuse = float(r.number("diffuse", s.shading.diffuse, 0, 1));
        r.finish();
    }
    s.background = top.colour("background", s.background);
    if (const json* c = top.get("pathlines")) {
        if (s.version < 2)
            top.failAt("pathlines", fmt::format("needs version 2, the document says version {}", s.version));
        Reader r = top.child("pathlines", *c);
        PathlineState& pl = s.pathlines;
        pl.visible = r.boolean("visible", pl.visible);
        if (const json* v = r.get("radiusKm"); v && !(v->is_number() && v->get<double>() > 0))
            r.failAt("radiusKm", "expected a positive number, found " + v->dump());
        pl.radiusKm = float(r.number("radiusKm", pl.radiusKm, 1e-6, 1e5));
        pl.window = r.integer("window", pl.window, 1, 1000);
        pl.colorBy = r.string("colorBy", pl.colorBy);
        if (pl.colorBy.empty())
            r.failAt("colorBy", "expected \"age\" or a line attribute name, found \"\"");
        if (const json* m = r.get("colorMap"); m && !m->is_null())
            pl.colorMap = r.colorMap("colorMap", ColorMapId::Viridis);
        pl.range = r.range("range");
        pl.filterByBrushes = r.boolean("filterByBrushes", pl.filterByBrushes);
        if (const json* f = r.get("filters")) {
            if (!f->is_array())
                r.failAt("filters", "expected an array, found " + f->dump());
            for (size_t i = 0; i < f->size(); ++i) {
                Reader fr = r.child(fmt::format("filters[{}]", i), (*f)[i]);
                PathlineFilter filter;
                filter.name = fr.string("name", "");
                if (filter.name.empty())
                    fr.failAt("name", "missing; expected a line attribute name");
                if (!fr.get("min") || !fr.get("max"))
                    fr.failAt(fr.get("min") ? "max" : "min", "missing");
                filter.min = float(fr.number("min", 0));
                filter.max = float(fr.number("max", 0));
                if (!(filter.min <= filter.max))
                    fr.failAt("min", fmt::format("min {} is greater than max {}", filter.min, filter.max));
                fr.finish();
                pl.filters.push_back(filter);
            }
        }
        pl.ambientOcclusion = r.boolean("ambientOcclusion", pl.ambientOcclusion);
        r.finish();
    }
    top.finish();
    return s;
}

RenderState loadRenderState(const std::filesystem::path& path)
{
    const std::string text = readFile(path);
    json j;
    try {
        j = json::parse(text);
    } catch (const json::parse_error& e) {
        fail("{}: not valid JSON: {}", path.string(), e.what());
    }
    return parseRenderState(j, path.filename().string());
}

json toJson(const RenderState& s)
{
    json opacity = json::array();
    for (const auto& p : s.opacity.empty() ? defaultOpacity(s.colorMap) : s.opacity)
        opacity.push_back({p.position, p.opacity});
    json brushes = json::array();
    for (const auto& b : s.brushes)
        brushes.push_back({{"name", b.name}, {"min", b.min}, {"max", b.max}});
    const Vec3 t = s.camera.targetKm;
    const Vec3 l = s.shading.lightFromCamera;
    json filters = json::array();
    for (const auto& f : s.pathlines.filters)
        filters.push_back({{"name", f.name}, {"min", f.min}, {"max", f.max}});
    // Always written in the current version (a version-1 document gains the default pathlines).
    return {
        {"version", kRenderStateVersion},
        {"step", s.step},
        {"camera",
         {{"azimuthDeg", s.camera.azimuthDeg},
          {"elevationDeg", s.camera.elevationDeg},
          {"distanceKm", s.camera.distanceKm},
          {"fovYDeg", s.camera.fovYDeg},
          {"targetKm", {t.x, t.y, t.z}}}},
        {"image", {{"width", s.width}, {"height", s.height}}},
        {"color",
         {{"variable", s.colorVariable},
          {"colorMap", std::string(colorMapName(s.colorMap))},
          {"range", rangeJson(s.colorRange)},
          {"opacity", opacity},
          {"opacityUnitKm", s.opacityUnitKm}}},
        {"brushes", brushes},
        {"level", s.level ? json(*s.level) : json("auto")},
        {"timeBudgetMs", s.timeBudgetMs},
        {"passes", s.passes},
        {"stepFactor", s.stepFactor},
        {"depthOpacity", s.depthOpacity},
        {"core",
         {{"visible", s.core.visible},
          {"variable", s.core.variable},
          {"color", colourJson(s.core.colour)},
          {"colorMap", std::string(colorMapName(s.core.colorMap))},
          {"range", rangeJson(s.core.range)}}},
        {"shading",
         {{"enabled", s.shading.enabled},
          {"light", {l.x, l.y, l.z}},
          {"ambient", s.shading.ambient},
          {"diffuse", s.shading.diffuse}}},
        {"background", colourJson(s.background)},
        {"pathlines",
         {{"visible", s.pathlines.visible},
          {"radiusKm", s.pathlines.radiusKm},
          {"window", s.pathlines.window},
          {"colorBy", s.pathlines.colorBy},
          {"colorMap", std::string(colorMapName(s.pathlines.effectiveColorMap()))},
          {"range", rangeJson(s.pathlines.range)},
          {"filterByBrushes", s.pathlines.filterByBrushes},
          {"filters", filters},
          {"ambientOcclusion", s.pathlines.ambientOcclusion}}},
    };
}

std::vector<OpacityPoint> defaultOpacity(ColorMapId map)
{
    if (isCentredOnZero(map))
        return {{0.0f, 0.5f}, {0.5f, 0.0f}, {1.0f, 0.5f}};
    return {{0.0f, 0.0f}, {1.0f, 0.5f}};
}

RenderParams resolveParams(const RenderState& s, const VariableCatalog& catalog)
{
    auto known = [&] {
        std::string list;
        for (const auto& n : catalog.names)
            list += (list.empty() ? "" : ", ") + n;
        return list;
    };
    auto variableIndex = [&](const std::string& name, const char* role) {
        for (size_t i = 0; i < catalog.names.size(); ++i)
            if (catalog.names[i] == name)
                return int(i);
        fail("{} variable '{}' is unknown; the dataset has: {}", role, name, known());
    };
    if (catalog.names.empty())
        fail("the volume has no variables to render");
    RenderParams p;
    p.camera = s.camera;
    p.width = s.width;
    p.height = s.height;
    p.colorVariable = s.colorVariable.empty() ? 0 : variableIndex(s.colorVariable, "colouring");
    auto defaultRange = [&](int var, ColorMapId map) {
        ValueRange r = var < int(catalog.ranges.size()) ? catalog.ranges[size_t(var)] : ValueRange{0, 1};
        if (isCentredOnZero(map)) {
            const float m = std::max(std::abs(r.min), std::abs(r.max));
            r = {-m, m};
        }
        if (!(r.min < r.max))
            r = {r.min - 0.5f, r.max + 0.5f};  // a constant variable still gets a usable range
        return r;
    };
    p.transfer.colorMap = s.colorMap;
    p.transfer.range = s.colorRange ? *s.colorRange : defaultRange(p.colorVariable, s.colorMap);
    p.transfer.opacity = s.opacity.empty() ? defaultOpacity(s.colorMap) : s.opacity;
    p.transfer.opacityUnitKm = s.opacityUnitKm;
    p.transfer.validate();
    std::vector<NamedRange> brushes;
    for (const BrushSpec& b : s.brushes)
        brushes.push_back({b.name, b.min, b.max});
    p.brushes = resolveRangeFilters(std::span<const std::string>(catalog.names), brushes, "brushes");
    p.core.visible = s.core.visible;
    p.core.colour = s.core.colour;
    p.core.colorMap = s.core.colorMap;
    if (!s.core.variable.empty()) {
        p.core.variable = variableIndex(s.core.variable, "core");
        p.core.range = s.core.range ? *s.core.range : defaultRange(p.core.variable, s.core.colorMap);
    }
    p.shading = s.shading;
    p.stepFactor = s.stepFactor;
    p.depthOpacity = s.depthOpacity;
    return p;
}

VariableCatalog catalogOf(const Dataset& dataset)
{
    VariableCatalog catalog;
    catalog.names = dataset.variableNames();
    for (const auto& v : dataset.variables())
        catalog.ranges.push_back(v.global.range);
    return catalog;
}

}  // namespace raypc::render
