// The state document described once (document() below) and everything derived from it: strict
// parsing with messages that name the key, serialisation, the JSON Schema and the docs table.
#include "state/state_schema.h"

#include "core/error.h"
#include "core/json_input.h"
#include "analysis/pathline_storage.h"
#include "state/render_state.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <set>

namespace raypc::state {
namespace {

using nlohmann::json;

// ---- Reading ------------------------------------------------------------------------------------

// What a whole parse shares: the source's name for messages and the document's version (keys
// newer than it are refused).
struct ParseContext {
    std::string what;
    int version = kRenderStateVersion;
};

// Strict reading of one JSON object: every key must be consumed; `path` prefixes messages.
class Reader {
public:
    Reader(const json& object, ParseContext& context, std::string path)
        : m_object(object), m_context(context), m_path(std::move(path))
    {
        if (!m_object.is_object())
            failAt("", "expected an object, found " + std::string(m_object.type_name()));
    }

    [[noreturn]] void failAt(const std::string& key, const std::string& message) const
    {
        fail("{}: {}: {}", m_context.what,
             key.empty() ? (m_path.empty() ? std::string("top level") : m_path) : name(key), message);
    }
    std::string name(const std::string& key) const { return m_path.empty() ? key : m_path + "." + key; }
    int version() const { return m_context.version; }
    void setVersion(int version) { m_context.version = version; }

    const json* get(const std::string& key)
    {
        m_used.insert(key);
        const auto it = m_object.find(key);
        return it == m_object.end() ? nullptr : &*it;
    }
    Reader child(const std::string& key, const json& value) const { return Reader(value, m_context, name(key)); }

    // Throws on keys nobody asked for.
    void finish() const
    {
        for (auto it = m_object.begin(); it != m_object.end(); ++it)
            if (!m_used.count(it.key()))
                failAt(it.key(), "unknown key");
    }

private:
    const json& m_object;
    ParseContext& m_context;
    std::string m_path;
    std::set<std::string> m_used;
};

// ---- Kinds of values --------------------------------------------------------------------------

// One kind of JSON value and the C++ type it fills: how to read it (strictly, failing through the
// reader with the key), write it, describe it as JSON Schema and name it in the docs table.
template <class T>
struct Kind {
    // Reads a present value (possibly null) into `target`, which holds the default.
    std::function<void(const json& value, T& target, Reader& at, const std::string& key)> read;
    std::function<json(const T&)> write;
    json schema;
    std::string type;  // the docs table's "type" column
    // Arrays of objects: rows for their elements' keys, and the schema refusing element keys newer
    // than a version (null: none).
    std::function<void(const std::string& path, std::vector<std::vector<std::string>>& rows)> elementRows{};
    std::function<json(int version)> forbiddenBefore{};
    std::string elementPath = "[].";  // how the element rows' keys continue the key (an optional object: ".")
};

std::string boundText(double x) { return fmt::format("{}", x); }

// Whole bounds as JSON integers, so that the schema reads as written.
json boundJson(double x) { return x == std::trunc(x) && std::abs(x) < 1e15 ? json(int64_t(x)) : json(x); }

json numberSchema(const char* type, double lo, double hi)
{
    json s{{"type", type}};
    if (std::isfinite(lo))
        s["minimum"] = boundJson(lo);
    if (std::isfinite(hi))
        s["maximum"] = boundJson(hi);
    return s;
}

std::string rangeText(const char* type, double lo, double hi)
{
    if (std::isfinite(lo) && std::isfinite(hi))
        return fmt::format("{} in [{}, {}]", type, boundText(lo), boundText(hi));
    if (std::isfinite(lo))
        return fmt::format("{} ≥ {}", type, boundText(lo));
    return type;
}

// Every number of a state is kept as a float (or narrower): a finite JSON number beyond float32's
// range would become inf and be written back as null, which no reader accepts.
bool fitsFloat32(double x) { return std::abs(x) <= double(std::numeric_limits<float>::max()); }

template <class T>
Kind<T> number(double lo = -INFINITY, double hi = INFINITY)
{
    return {[lo, hi](const json& v, T& target, Reader& r, const std::string& key) {
                if (!v.is_number())
                    r.failAt(key, "expected a number, found " + jsonExcerpt(v));
                const double x = v.get<double>();
                // The bounds first: a NaN (a program's value; JSON text holds none) is out of them.
                if (!(x >= lo && x <= hi))
                    r.failAt(key, fmt::format("expected a number in [{}, {}], found {}", lo, hi, x));
                if (!fitsFloat32(x))
                    r.failAt(key, fmt::format("{} is beyond the float32 range", x));
                target = T(x);
            },
            [](const T& x) { return json(x); }, numberSchema("number", lo, hi), rangeText("number", lo, hi)};
}

Kind<int> integer(int lo, int hi)
{
    return {[lo, hi](const json& v, int& target, Reader& r, const std::string& key) {
                if (!v.is_number_integer())
                    r.failAt(key, "expected an integer, found " + jsonExcerpt(v));
                const auto x = v.get<int64_t>();
                if (x < lo || x > hi)
                    r.failAt(key, fmt::format("expected an integer in [{}, {}], found {}", lo, hi, x));
                target = int(x);
            },
            [](const int& x) { return json(x); }, numberSchema("integer", lo, hi), rangeText("integer", lo, hi)};
}

Kind<bool> boolean()
{
    return {[](const json& v, bool& target, Reader& r, const std::string& key) {
                if (!v.is_boolean())
                    r.failAt(key, "expected true or false, found " + jsonExcerpt(v));
                target = v.get<bool>();
            },
            [](const bool& x) { return json(x); }, {{"type", "boolean"}}, "bool"};
}

// A string. `nullable`: null keeps the default; `nonEmpty` (what is expected) refuses "".
Kind<std::string> text(bool nullable, const std::string& nonEmpty = "")
{
    json schema{{"type", nullable ? json::array({"string", "null"}) : json("string")}};
    if (!nonEmpty.empty())
        schema["minLength"] = 1;
    std::string type = nonEmpty.empty() ? "string" : "non-empty string";
    return {[nullable, nonEmpty](const json& v, std::string& target, Reader& r, const std::string& key) {
                if (nullable && v.is_null())
                    return;
                if (!v.is_string())
                    r.failAt(key, "expected a string, found " + jsonExcerpt(v));
                if (!nonEmpty.empty() && v.get_ref<const std::string&>().empty())
                    r.failAt(key, fmt::format("expected {}, found \"\"", nonEmpty));
                target = v.get<std::string>();
            },
            [](const std::string& x) { return json(x); }, schema, nullable ? type + " or null" : type};
}

json numbersSchema(size_t count, double lo = -INFINITY, double hi = INFINITY)
{
    return {{"type", "array"}, {"items", numberSchema("number", lo, hi)}, {"minItems", count}, {"maxItems", count}};
}

std::vector<double> numbers(const json& v, size_t count, Reader& r, const std::string& key)
{
    if (!v.is_array() || v.size() != count)
        r.failAt(key, fmt::format("expected an array of {} numbers, found {}", count, jsonExcerpt(v)));
    std::vector<double> out;
    for (const json& e : v) {
        if (!e.is_number())
            r.failAt(key, "expected numbers, found " + jsonExcerpt(v));
        if (!fitsFloat32(e.get<double>()))
            r.failAt(key, fmt::format("{} is beyond the float32 range", e.get<double>()));
        out.push_back(e.get<double>());
    }
    return out;
}

// A list of numbers in [lo, hi], at most `maxItems` (e.g. reference shell depths).
Kind<std::vector<float>> numberList(double lo, double hi, size_t maxItems)
{
    json schema{{"type", "array"}, {"items", numberSchema("number", lo, hi)}, {"maxItems", maxItems}};
    return {[lo, hi, maxItems](const json& v, std::vector<float>& target, Reader& r, const std::string& key) {
                if (!v.is_array() || v.size() > maxItems)
                    r.failAt(key, fmt::format("expected an array of at most {} numbers, found {}", maxItems, jsonExcerpt(v)));
                target.clear();
                for (const json& e : v) {
                    if (!e.is_number() || !fitsFloat32(e.get<double>()) || !(e.get<double>() >= lo && e.get<double>() <= hi))
                        r.failAt(key, fmt::format("expected numbers in [{}, {}], found {}", lo, hi, jsonExcerpt(e)));
                    target.push_back(e.get<float>());
                }
            },
            [](const std::vector<float>& x) {
                json out = json::array();
                for (float f : x)
                    out.push_back(f);
                return out;
            },
            schema, fmt::format("array of at most {} numbers in [{}, {}]", maxItems, boundText(lo), boundText(hi))};
}

// Whole numbers in [lo, hi], at most maxItems.
Kind<std::vector<int>> integerList(int lo, int hi, size_t maxItems)
{
    json schema{{"type", "array"}, {"items", numberSchema("integer", lo, hi)}, {"maxItems", maxItems}};
    return {[lo, hi, maxItems](const json& v, std::vector<int>& target, Reader& r, const std::string& key) {
                if (!v.is_array() || v.size() > maxItems)
                    r.failAt(key, fmt::format("expected an array of at most {} integers, found {}", maxItems, jsonExcerpt(v)));
                target.clear();
                for (const json& e : v) {
                    if (!e.is_number_integer() || e.get<int64_t>() < lo || e.get<int64_t>() > hi)
                        r.failAt(key, fmt::format("expected integers in [{}, {}], found {}", lo, hi, jsonExcerpt(e)));
                    target.push_back(int(e.get<int64_t>()));
                }
            },
            [](const std::vector<int>& x) { return json(x); }, schema,
            fmt::format("array of at most {} integers in [{}, {}]", maxItems, lo, hi)};
}

// Non-empty names, each at most once, or null (nullopt: a default that depends on the dataset).
Kind<std::optional<std::vector<std::string>>> nameList(size_t maxItems)
{
    json schema{{"type", json::array({"array", "null"})},
                {"items", {{"type", "string"}, {"minLength", 1}}},
                {"maxItems", maxItems},
                {"uniqueItems", true}};
    return {[maxItems](const json& v, std::optional<std::vector<std::string>>& target, Reader& r, const std::string& key) {
                if (v.is_null()) {
                    target.reset();
                    return;
                }
                if (!v.is_array() || v.size() > maxItems)
                    r.failAt(key, fmt::format("expected null or an array of at most {} names, found {}", maxItems,
                                              jsonExcerpt(v)));
                std::vector<std::string> names;
                for (const json& e : v) {
                    if (!e.is_string() || e.get_ref<const std::string&>().empty())
                        r.failAt(key, "expected non-empty names, found " + jsonExcerpt(e));
                    if (std::find(names.begin(), names.end(), e.get<std::string>()) != names.end())
                        r.failAt(key, "expected each name once, found " + jsonExcerpt(e) + " twice");
                    names.push_back(e.get<std::string>());
                }
                target = std::move(names);
            },
            [](const std::optional<std::vector<std::string>>& x) { return x ? json(*x) : json(nullptr); }, schema,
            fmt::format("array of at most {} distinct non-empty strings, or null", maxItems)};
}

Kind<Rgb> color()
{
    return {[](const json& v, Rgb& target, Reader& r, const std::string& key) {
                const auto c = numbers(v, 3, r, key);
                for (double x : c)
                    if (!(x >= 0 && x <= 1))
                        r.failAt(key, "expected colour components in [0, 1], found " + jsonExcerpt(v));
                target = {float(c[0]), float(c[1]), float(c[2])};
            },
            [](const Rgb& c) { return json::array({c.r, c.g, c.b}); }, numbersSchema(3, 0, 1),
            "[r, g, b], each in [0, 1]"};
}

// A vector; `direction`: [0, 0, 0] is refused.
Kind<Vec3> vec3(bool direction)
{
    json schema = numbersSchema(3);
    if (direction)
        schema["not"] = {{"const", json::array({0, 0, 0})}};
    return {[direction](const json& v, Vec3& target, Reader& r, const std::string& key) {
                const auto c = numbers(v, 3, r, key);
                if (direction && c[0] == 0 && c[1] == 0 && c[2] == 0)
                    r.failAt(key, "expected a non-zero direction");
                target = {float(c[0]), float(c[1]), float(c[2])};
            },
            [](const Vec3& x) { return json::array({x.x, x.y, x.z}); }, schema,
            direction ? "[x, y, z], not [0, 0, 0]" : "[x, y, z]"};
}

// [min, max] with min < max, or null (nullopt: a default that depends on the data).
Kind<std::optional<dataset::ValueRange>> range()
{
    json schema = numbersSchema(2);
    schema["type"] = json::array({"array", "null"});
    return {[](const json& v, std::optional<dataset::ValueRange>& target, Reader& r, const std::string& key) {
                if (v.is_null()) {
                    target.reset();
                    return;
                }
                const auto x = numbers(v, 2, r, key);
                if (!(x[0] < x[1]))
                    r.failAt(key, fmt::format("expected [min, max] with min < max, found {}", jsonExcerpt(v)));
                target = dataset::ValueRange{float(x[0]), float(x[1])};
            },
            [](const std::optional<dataset::ValueRange>& x) {
                return x ? json::array({x->min, x->max}) : json(nullptr);
            },
            schema, "[min, max] with min < max, or null"};
}

json colorMapNames()
{
    json names = json::array();
    for (ColorMapId m : allColorMaps())
        names.push_back(std::string(colorMapName(m)));
    return names;
}

ColorMapId readColorMap(const json& v, Reader& r, const std::string& key)
{
    if (!v.is_string())
        r.failAt(key, "expected a colour map name, found " + jsonExcerpt(v));
    try {
        return parseColorMap(v.get<std::string>());
    } catch (const Error& e) {
        r.failAt(key, e.what());
    }
}

std::string colorMapType()
{
    std::string list;
    for (const auto& n : colorMapNames())
        list += (list.empty() ? "" : ", ") + ("`" + n.get<std::string>() + "`");
    return "one of " + list;
}

Kind<ColorMapId> colorMap()
{
    return {[](const json& v, ColorMapId& target, Reader& r, const std::string& key) {
                target = readColorMap(v, r, key);
            },
            [](const ColorMapId& m) { return json(std::string(colorMapName(m))); },
            {{"type", "string"}, {"enum", colorMapNames()}}, colorMapType()};
}

// A colour map or null (nullopt: the default depends on other keys).
Kind<std::optional<ColorMapId>> optionalColorMap()
{
    json names = colorMapNames();
    names.push_back(nullptr);
    return {[](const json& v, std::optional<ColorMapId>& target, Reader& r, const std::string& key) {
                if (v.is_null())
                    target.reset();
                else
                    target = readColorMap(v, r, key);
            },
            [](const std::optional<ColorMapId>& m) {
                return m ? json(std::string(colorMapName(*m))) : json(nullptr);
            },
            {{"type", json::array({"string", "null"})}, {"enum", names}}, colorMapType() + ", or null"};
}

Kind<std::vector<OpacityPoint>> opacityPoints()
{
    return {[](const json& o, std::vector<OpacityPoint>& target, Reader& r, const std::string& key) {
                if (!o.is_array() || o.empty())
                    r.failAt(key, "expected an array of [position, opacity] pairs, found " + jsonExcerpt(o));
                target.clear();
                for (const json& p : o) {
                    const auto v = numbers(p, 2, r, key);
                    if (!(v[0] >= 0 && v[0] <= 1 && v[1] >= 0 && v[1] <= 1))
                        r.failAt(key, "expected position and opacity in [0, 1], found " + jsonExcerpt(p));
                    if (!target.empty() && v[0] < target.back().position)
                        r.failAt(key, "positions must ascend, found " + jsonExcerpt(o));
                    target.push_back({float(v[0]), float(v[1])});
                }
            },
            [](const std::vector<OpacityPoint>& points) {
                json out = json::array();
                for (const auto& p : points)
                    out.push_back({p.position, p.opacity});
                return out;
            },
            {{"type", "array"}, {"items", numbersSchema(2, 0, 1)}, {"minItems", 1}},
            "[[position, opacity], …], each in [0, 1], positions ascending"};
}

// Colour control points [[u, r, g, b], ...], each in [0, 1], u ascending; [] = none.
Kind<std::vector<ColorStop>> colorPoints()
{
    return {[](const json& o, std::vector<ColorStop>& target, Reader& r, const std::string& key) {
                if (!o.is_array() || o.size() == 1)
                    r.failAt(key, "expected [] or an array of at least 2 [u, r, g, b] points, found " + jsonExcerpt(o));
                target.clear();
                for (const json& p : o) {
                    const auto v = numbers(p, 4, r, key);
                    for (double x : v)
                        if (!(x >= 0 && x <= 1))
                            r.failAt(key, "expected u, r, g, b in [0, 1], found " + jsonExcerpt(p));
                    if (!target.empty() && v[0] < target.back().u)
                        r.failAt(key, "positions must ascend, found " + jsonExcerpt(o));
                    target.push_back({float(v[0]), {float(v[1]), float(v[2]), float(v[3])}});
                }
            },
            [](const std::vector<ColorStop>& points) {
                json out = json::array();
                for (const auto& p : points)
                    out.push_back({p.u, p.c.r, p.c.g, p.c.b});
                return out;
            },
            {{"type", "array"}, {"items", numbersSchema(4, 0, 1)}},
            "[[u, r, g, b], …], each in [0, 1], u ascending; [] or at least 2 points"};
}

// One of an enumeration's names (`what`: "a stereo mode"), read with its parser (whose message says
// what the names are) and written with its name.
template <class E>
Kind<E> enumeration(std::span<const E> all, std::string_view (*name)(E), E (*parse)(std::string_view), std::string what)
{
    json names = json::array();
    std::string list;
    for (E m : all) {
        names.push_back(std::string(name(m)));
        list += (list.empty() ? "" : ", ") + ("`" + std::string(name(m)) + "`");
    }
    return {[parse, what](const json& v, E& target, Reader& r, const std::string& key) {
                if (!v.is_string())
                    r.failAt(key, "expected " + what + " name, found " + jsonExcerpt(v));
                try {
                    target = parse(v.get<std::string>());
                } catch (const Error& e) {
                    r.failAt(key, e.what());
                }
            },
            [name](const E& m) { return json(std::string(name(m))); },
            {{"type", "string"}, {"enum", names}}, "one of " + list};
}

Kind<StereoMode> stereoMode()
{
    return enumeration<StereoMode>(allStereoModes(), stereoModeName, parseStereoMode, "a stereo mode");
}

Kind<analysis::StallMeasure> stallMeasure()
{
    return enumeration<analysis::StallMeasure>(analysis::kStallMeasures, analysis::stallMeasureName, analysis::parseStallMeasure, "a stall measure");
}

Kind<PairSteps> pairSteps()
{
    return enumeration<PairSteps>(allPairSteps(), pairStepsName, parsePairSteps, "a step matching");
}

Kind<MapProjection> mapProjection()
{
    return enumeration<MapProjection>(allMapProjections(), mapProjectionName, parseMapProjection, "a map projection");
}

// A number in [lo, hi] or null (nullopt: a default that depends on other keys).
Kind<std::optional<float>> optionalNumber(double lo, double hi)
{
    json schema = numberSchema("number", lo, hi);
    schema["type"] = json::array({"number", "null"});
    const Kind<float> plain = number<float>(lo, hi);
    return {[plain](const json& v, std::optional<float>& target, Reader& r, const std::string& key) {
                if (v.is_null()) {
                    target.reset();
                    return;
                }
                float x = 0;
                plain.read(v, x, r, key);
                target = x;
            },
            [](const std::optional<float>& x) { return x ? json(*x) : json(nullptr); }, schema,
            plain.type + ", or null"};
}

// Four numbers, each in [lo, hi] (a quaternion, frustum tangents).
Kind<std::array<float, 4>> four(const std::string& type, double lo = -INFINITY, double hi = INFINITY)
{
    return {[lo, hi](const json& v, std::array<float, 4>& target, Reader& r, const std::string& key) {
                const auto x = numbers(v, 4, r, key);
                for (size_t i = 0; i < 4; ++i) {
                    if (!(x[i] >= lo && x[i] <= hi))
                        r.failAt(key, fmt::format("expected numbers in [{}, {}], found {}", lo, hi, jsonExcerpt(v)));
                    target[i] = float(x[i]);
                }
            },
            [](const std::array<float, 4>& x) { return json::array({x[0], x[1], x[2], x[3]}); },
            numbersSchema(4, lo, hi), type};
}

// An explicit level or "auto" (nullopt).
Kind<std::optional<int>> level()
{
    const int top = dataset::kLevelCount - 1;
    return {[top](const json& v, std::optional<int>& target, Reader& r, const std::string& key) {
                if (v.is_string() && v.get_ref<const std::string&>() == "auto") {
                    target.reset();
                    return;
                }
                if (!v.is_number_integer() || v.get<int64_t>() < 0 || v.get<int64_t>() > top)
                    r.failAt(key, fmt::format("expected \"auto\" or an integer in [0, {}], found {}", top, jsonExcerpt(v)));
                target = v.get<int>();
            },
            [](const std::optional<int>& l) { return l ? json(*l) : json("auto"); },
            {{"anyOf", json::array({numberSchema("integer", 0, top), json{{"const", "auto"}}})}},
            fmt::format("integer in [0, {}] or `\"auto\"`", top)};
}

// The document's version: read first, it decides which keys the document may have.
Kind<int> version()
{
    json supported = json::array();
    std::string list;
    for (int v = 1; v <= kRenderStateVersion; ++v) {
        supported.push_back(v);
        list += v == 1 ? fmt::format("{}", v) : fmt::format("{} {}", v == kRenderStateVersion ? " or" : ",", v);
    }
    return {[list](const json& v, int& target, Reader& r, const std::string& key) {
                if (!v.is_number_integer())
                    r.failAt(key, "expected an integer, found " + jsonExcerpt(v));
                const auto x = v.get<int64_t>();
                if (x < 1 || x > kRenderStateVersion)
                    r.failAt(key, fmt::format("{} is not supported, expected {}", x, list));
                target = int(x);
                r.setVersion(target);
            },
            [](const int&) { return json(kRenderStateVersion); },  // always written in the current version
            {{"type", "integer"}, {"enum", supported}}, "integer: " + list};
}

// ---- Fields and objects ---------------------------------------------------------------------------

// What restarts or reloads when a key changes (house style: name the cost class of a change).
enum class Cost { None, Restart, Reload };

struct FieldDoc {
    std::string meaning{};
    Cost cost = Cost::Restart;
    std::string defaultText{};  // when the default is not a plain value (it depends on other keys or the data)
    int since = 1;            // the document version that added the key
    bool required = false;
    std::string expect{};  // what a missing required key should have been, for its message
};

std::string costText(Cost c)
{
    switch (c) {
    case Cost::Restart: return "restart";
    case Cost::Reload: return "reload";
    case Cost::None: break;
    }
    return "—";
}

// A docs-table rendering of a default value: numbers as the floats they are stored as.
std::string valueText(const json& v)
{
    if (v.is_number_float()) {
        const float f = float(v.get<double>());
        return f == std::trunc(f) && std::abs(f) < 1e9f ? fmt::format("{}", int64_t(f)) : fmt::format("{}", f);
    }
    if (v.is_array()) {
        std::string out;
        for (const auto& e : v)
            out += (out.empty() ? "" : ", ") + valueText(e);
        return "[" + out + "]";
    }
    return v.dump();
}

using Rows = std::vector<std::vector<std::string>>;

// One key of a JSON object whose values live in an `Owner` (RenderState, or an array element).
template <class Owner>
class Field {
public:
    Field(std::string key, FieldDoc doc) : key(std::move(key)), doc(std::move(doc)) {}
    virtual ~Field() = default;
    virtual void read(Reader& r, Owner& owner) const = 0;
    virtual json write(const Owner& owner) const = 0;
    // `defaults`: this key's value in toJson(RenderState{}), null where there is none.
    virtual json schema(const json& defaults) const = 0;
    virtual void rows(const std::string& prefix, const json& defaults, Rows& out) const = 0;
    // The schema of this key for a document of `version` refusing what is newer, or null.
    virtual json forbiddenBefore(int version) const = 0;

    const std::string key;
    const FieldDoc doc;

protected:
    // The value, or nullptr when absent; fails for a missing required key or one newer than the document.
    const json* present(Reader& r) const
    {
        const json* v = r.get(key);
        if (!v) {
            if (doc.required)
                r.failAt(key, doc.expect.empty() ? "missing" : "missing; expected " + doc.expect);
            return nullptr;
        }
        if (doc.since > r.version())
            r.failAt(key, fmt::format("needs version {}, the document says version {}", doc.since, r.version()));
        return v;
    }
    json annotate(json schema, const json& defaults) const
    {
        std::string description = doc.meaning;
        if (!doc.defaultText.empty())
            description += ". Default: " + doc.defaultText;
        if (!description.empty())
            schema["description"] = description;
        if (!defaults.is_null() && !doc.required)
            schema["default"] = defaults;
        return schema;
    }
    std::string sinceText() const { return doc.since > 1 ? fmt::format(", version ≥ {}", doc.since) : ""; }
    std::string defaultCell(const json& defaults) const
    {
        if (!doc.defaultText.empty())
            return doc.defaultText;
        if (doc.required || defaults.is_null())
            return "—";
        return "`" + valueText(defaults) + "`";
    }
};

template <class Owner>
using FieldPtr = std::shared_ptr<const Field<Owner>>;

// The keys of one JSON object, in document order; `check` tests what spans several keys.
template <class Owner>
struct Object {
    std::string title;  // names the generated TypeScript type; empty: written inline
    std::vector<FieldPtr<Owner>> fields;
    std::function<void(const Owner&, Reader&)> check;

    void read(Reader& r, Owner& owner) const
    {
        for (const auto& f : fields)
            f->read(r, owner);
        if (check)
            check(owner, r);
        r.finish();
    }
    json write(const Owner& owner) const
    {
        json out = json::object();
        for (const auto& f : fields)
            out[f->key] = f->write(owner);
        return out;
    }
    json schema(const json& defaults) const
    {
        json properties = json::object(), required = json::array();
        for (const auto& f : fields) {
            properties[f->key] = f->schema(defaults.is_object() && defaults.contains(f->key) ? defaults[f->key] : json());
            if (f->doc.required)
                required.push_back(f->key);
        }
        json s{{"type", "object"}, {"properties", properties}, {"additionalProperties", false}};
        if (!required.empty())
            s["required"] = required;
        if (!title.empty())
            s["title"] = title;
        return s;
    }
    void rows(const std::string& prefix, const json& defaults, Rows& out) const
    {
        for (const auto& f : fields)
            f->rows(prefix, defaults.is_object() && defaults.contains(f->key) ? defaults[f->key] : json(), out);
    }
    json forbiddenBefore(int version) const
    {
        json properties = json::object();
        for (const auto& f : fields) {
            if (f->doc.since > version)
                properties[f->key] = {{"not", json::object()}, {"description", fmt::format("needs version {}", f->doc.since)}};
            else if (json sub = f->forbiddenBefore(version); !sub.is_null())
                properties[f->key] = sub;
        }
        // "type" too: strict validators (ajv) want it beside "properties", e.g. for the keys of
        // "color" that a newer version added.
        return properties.empty() ? json() : json{{"type", "object"}, {"properties", properties}};
    }
};

// A key holding one value of a Kind, reached in the owner through `access`.
template <class Owner, class T, class Access>
class Leaf final : public Field<Owner> {
public:
    Leaf(std::string key, Access access, Kind<T> kind, FieldDoc doc, std::function<json(const Owner&)> writeAs)
        : Field<Owner>(std::move(key), std::move(doc)), m_access(access), m_kind(std::move(kind)),
          m_writeAs(std::move(writeAs))
    {
    }
    void read(Reader& r, Owner& owner) const override
    {
        if (const json* v = this->present(r))
            m_kind.read(*v, m_access(owner), r, this->key);
    }
    json write(const Owner& owner) const override { return m_writeAs ? m_writeAs(owner) : m_kind.write(m_access(owner)); }
    json schema(const json& defaults) const override { return this->annotate(m_kind.schema, defaults); }
    void rows(const std::string& prefix, const json& defaults, Rows& out) const override
    {
        const std::string type = m_kind.type + (this->doc.required ? ", required" : "") + this->sinceText();
        out.push_back({prefix + this->key, type, this->defaultCell(defaults), this->doc.meaning, costText(this->doc.cost)});
        if (m_kind.elementRows)
            m_kind.elementRows(prefix + this->key + m_kind.elementPath, out);
    }
    json forbiddenBefore(int version) const override
    {
        return m_kind.forbiddenBefore ? m_kind.forbiddenBefore(version) : json();
    }

private:
    Access m_access;
    Kind<T> m_kind;
    std::function<json(const Owner&)> m_writeAs;  // what toJson writes when it is not the member itself
};

// A key holding a JSON object whose keys fill the same owner (e.g. "camera" within RenderState).
template <class Owner>
class Group final : public Field<Owner> {
public:
    Group(std::string key, Object<Owner> object, FieldDoc doc)
        : Field<Owner>(std::move(key), std::move(doc)), m_object(std::move(object))
    {
    }
    void read(Reader& r, Owner& owner) const override
    {
        if (const json* v = this->present(r)) {
            Reader child = r.child(this->key, *v);
            m_object.read(child, owner);
        }
    }
    json write(const Owner& owner) const override { return m_object.write(owner); }
    json schema(const json& defaults) const override { return this->annotate(m_object.schema(defaults), json()); }
    void rows(const std::string& prefix, const json& defaults, Rows& out) const override
    {
        out.push_back({prefix + this->key, "object" + this->sinceText(), "—", this->doc.meaning, "—"});
        m_object.rows(prefix + this->key + ".", defaults, out);
    }
    json forbiddenBefore(int version) const override { return m_object.forbiddenBefore(version); }

private:
    Object<Owner> m_object;
};

// The member reached from an owner through a chain of member pointers, e.g.
// at(&RenderState::camera, &OrbitCamera::fovYDeg); const for a const owner.
template <class... Members>
auto at(Members... members)
{
    return [=](auto& owner) -> auto& { return (owner .* ... .* members); };
}

template <class Owner, class T, class Access>
FieldPtr<Owner> leaf(std::string key, Access access, Kind<T> kind, FieldDoc doc,
                     std::function<json(const Owner&)> writeAs = {})
{
    return std::make_shared<Leaf<Owner, T, Access>>(std::move(key), access, std::move(kind), std::move(doc),
                                                    std::move(writeAs));
}

template <class Owner>
FieldPtr<Owner> group(std::string key, std::string title, std::vector<FieldPtr<Owner>> fields, FieldDoc doc)
{
    return std::make_shared<Group<Owner>>(std::move(key), Object<Owner>{std::move(title), std::move(fields), {}},
                                          std::move(doc));
}

// An array of JSON objects, each read into one element.
template <class E>
Kind<std::vector<E>> arrayOf(Object<E> element, std::string type)
{
    auto e = std::make_shared<const Object<E>>(std::move(element));
    Kind<std::vector<E>> kind{
        [e](const json& v, std::vector<E>& target, Reader& r, const std::string& key) {
            if (!v.is_array())
                r.failAt(key, "expected an array, found " + jsonExcerpt(v));
            target.clear();
            for (size_t i = 0; i < v.size(); ++i) {
                Reader child = r.child(fmt::format("{}[{}]", key, i), v[i]);
                E item;
                e->read(child, item);
                target.push_back(std::move(item));
            }
        },
        [e](const std::vector<E>& items) {
            json out = json::array();
            for (const E& item : items)
                out.push_back(e->write(item));
            return out;
        },
        {{"type", "array"}, {"items", e->schema(json())}},
        std::move(type)};
    kind.elementRows = [e](const std::string& prefix, Rows& out) { e->rows(prefix, json(), out); };
    kind.forbiddenBefore = [e](int version) {
        json sub = e->forbiddenBefore(version);
        return sub.is_null() ? sub : json{{"items", sub}};
    };
    return kind;
}

// A JSON object read into an optional element, or null (nullopt, written as null).
template <class E>
Kind<std::optional<E>> optionalObject(Object<E> element, std::string type)
{
    auto e = std::make_shared<const Object<E>>(std::move(element));
    json schema = e->schema(json());
    schema["type"] = json::array({"object", "null"});
    Kind<std::optional<E>> kind{
        [e](const json& v, std::optional<E>& target, Reader& r, const std::string& key) {
            if (v.is_null()) {
                target.reset();
                return;
            }
            if (!v.is_object())
                r.failAt(key, "expected an object or null, found " + jsonExcerpt(v));
            Reader child = r.child(key, v);
            E item;
            e->read(child, item);
            target = std::move(item);
        },
        [e](const std::optional<E>& item) { return item ? e->write(*item) : json(); },
        schema,
        std::move(type)};
    kind.elementRows = [e](const std::string& prefix, Rows& out) { e->rows(prefix, json(), out); };
    kind.elementPath = ".";
    return kind;
}

// {name, min, max} ranges: brushes over variables or coordinates, filters over line attributes.
template <class Range>
Object<Range> namedRange(std::string title, const std::string& nameMeaning, const std::string& nameExpect)
{
    auto bound = [](const char* which) {
        return FieldDoc{.meaning = std::string(which) + " of the range, inclusive", .required = true};
    };
    return {std::move(title),
            {leaf<Range>("name", at(&Range::name), text(false, nameExpect),
                         {.meaning = nameMeaning, .required = true, .expect = nameExpect}),
             leaf<Range>("min", at(&Range::min), number<float>(), bound("lower end")),
             leaf<Range>("max", at(&Range::max), number<float>(), bound("upper end"))},
            [](const Range& range, Reader& r) {
                if (!(range.min <= range.max))
                    r.failAt("min", fmt::format("min {} is greater than max {}", range.min, range.max));
            }};
}

// One explicit camera view (render/camera.h CameraView); what JSON Schema cannot say (a unit
// quaternion, left < right and down < up) is CameraView::validate's, reported at the view's path.
Object<CameraView> cameraView()
{
    using V = CameraView;
    return {"CameraView",
            {leaf<V>("positionKm", at(&V::positionKm), vec3(false),
                     {.meaning = "the eye, km (contest Cartesian frame)", .required = true, .expect = "[x, y, z]"}),
             leaf<V>("orientation", at(&V::orientation), four("[x, y, z, w], a unit quaternion", -1.01, 1.01),
                     {.meaning = "rotation from camera axes (looking along −z, +y up, +x right: WebXR's) to the "
                                 "contest frame; its length must be 1 within 0.001",
                      .required = true,
                      .expect = "[x, y, z, w]"}),
             leaf<V>("frustum", at(&V::frustum), four("[left, right, down, up], left < right, down < up", -1e4, 1e4),
                     {.meaning = "signed tangents of the angles of the image's edges from the view axis (a 90° "
                                 "square view: [-1, 1, -1, 1]); the image's width and height span them",
                      .required = true,
                      .expect = "[left, right, down, up]"})},
            [](const V& view, Reader& r) {
                try {
                    view.validate();
                } catch (const Error& e) {
                    r.failAt("", e.what());
                }
            }};
}

// ---- The document ------------------------------------------------------------------------------

const Object<RenderState>& document()
{
    using S = RenderState;
    using C = OrbitCamera;
    using P = PathlineState;
    using R = ReferenceState;
    static const Object<S> doc{
        "RenderState",
        {
            leaf<S>("version", at(&S::version), version(),
                    {.meaning = fmt::format("schema version: {} or an older one (read, written back as {}); "
                                            "a key newer than the document's version is refused",
                                            kRenderStateVersion, kRenderStateVersion),
                     .cost = Cost::None,
                     .defaultText = fmt::format("`{}`", kRenderStateVersion),
                     .required = true,
                     .expect = fmt::format("{}", kRenderStateVersion)}),
            leaf<S>("step", at(&S::step), integer(0, 1000000), {.meaning = "time step index", .cost = Cost::Reload}),
            group<S>("camera", "CameraState",
                     {leaf<S>("azimuthDeg", at(&S::camera, &C::azimuthDeg), number<double>(),
                              {.meaning = "orbit angle in the x–y plane from +x towards +y, degrees"}),
                      leaf<S>("elevationDeg", at(&S::camera, &C::elevationDeg), number<double>(-90, 90),
                              {.meaning = "angle above the equatorial plane, degrees"}),
                      leaf<S>("distanceKm", at(&S::camera, &C::distanceKm), number<double>(1e-3, 1e9),
                              {.meaning = "eye–target distance, km"}),
                      leaf<S>("fovYDeg", at(&S::camera, &C::fovYDeg), number<double>(1e-3, 179.9),
                              {.meaning = "vertical field of view, degrees"}),
                      leaf<S>("targetKm", at(&S::camera, &C::targetKm), vec3(false),
                              {.meaning = "point looked at, km (contest Cartesian frame)"}),
                      leaf<S>("views", at(&S::camera, &C::views), arrayOf(cameraView(), "array of {positionKm, orientation, frustum}"),
                              {.meaning = "explicit views replacing the orbit's pose and frustum (e.g. a WebXR "
                                          "headset's eyes, docs/rendering.md): [] the orbit camera; one view; or, "
                                          "with `stereo.mode` not `off`, the left and right eye (the orbit keys stay, "
                                          "for the UI's navigation)",
                               .since = 7})},
                     {.meaning = "the orbit camera"}),
            group<S>("image", "",
                     {leaf<S>("width", at(&S::width), integer(1, 16384), {.meaning = "image width, pixels"}),
                      leaf<S>("height", at(&S::height), integer(1, 16384), {.meaning = "image height, pixels"})},
                     {.meaning = "the size of the rendered image"}),
            leaf<S>("axes", at(&S::axes), nameList(256),
                    {.meaning = "the axes of the UI's volume parallel coordinates, in display order (sample "
                                "columns: coordinates and variables; names the dataset lacks are passed over); an "
                                "axis with a brush is shown whether listed or not. Pictures do not depend on it",
                     .cost = Cost::None,
                     .defaultText = "null: every axis but `x`, `y`, `z` and `radius`, in the dataset's order",
                     .since = 4}),
            group<S>(
                "color", "",
                {leaf<S>("variable", at(&S::colorVariable), text(true),
                         {.meaning = "colouring variable (dataset name, e.g. `\"temperature anomaly\"`)",
                          .defaultText = "`\"\"`: the first variable"}),
                 leaf<S>("colorMap", at(&S::colorMap), colorMap(),
                         {.meaning = "colour map (src/state/color_maps.json names each table's source): "
                                     "`inferno` is black body, `cool-to-warm` ParaView's; Crameri's `batlow`, "
                                     "`lajolla` and cmocean's `thermal` sequential, `vik`, `roma`, `balance` and "
                                     "`blue-white-red` diverging, centred on 0"}),
                 leaf<S>("range", at(&S::colorRange), range(),
                         {.meaning = "value range of the transfer function; values outside clamp to the ends",
                          .defaultText = "null: the variable's default range (`render::defaultColorRange`): for centred "
                                         "maps ±the 99.5th percentile of \\|v\\| over all steps rounded up to a nice "
                                         "number (at most ±max\\|v\\|), else the global range over all steps"}),
                 leaf<S>("opacity", at(&S::opacity), opacityPoints(),
                         {.meaning = "piecewise-linear opacity; position normalised over `color.range` (0 = min, 1 = "
                                     "max)",
                          .defaultText = "`[[0, 0], [1, 0.5]]`; for `blue-white-red` a V: `[[0, 0.5], [0.5, 0], [1, "
                                         "0.5]]` (transparent at zero)"},
                         [](const S& s) {
                             return opacityPoints().write(s.opacity.empty() ? defaultOpacity(s.colorMap) : s.opacity);
                         }),
                 leaf<S>("opacityUnitKm", at(&S::opacityUnitKm), number<float>(1e-6, 1e9),
                         {.meaning = "path length over which `opacity` applies (docs/rendering.md, opacity "
                                     "correction)"}),
                 leaf<S>("logScale", at(&S::logScale), boolean(),
                         {.meaning = "colour and opacity positions over log10 of the value, for positive quantities "
                                     "(the range must be positive)",
                          .since = 3}),
                 leaf<S>("points", at(&S::colorPoints), colorPoints(),
                         {.meaning = "colour control points (the UI's editor, an imported ParaView colour map), "
                                     "position normalised over `color.range` as `opacity`; when not empty they "
                                     "replace `colorMap` (and are not centred on 0)",
                          .since = 3}),
                 leaf<S>("reversed", at(&S::colorReversed), boolean(),
                         {.meaning = "run the colours from the map's (or the points') end to its start", .since = 3})},
                {.meaning = "the volume's transfer function"}),
            leaf<S>("brushes", at(&S::brushes),
                    arrayOf(namedRange<BrushSpec>("Brush", "a variable or a coordinate",
                                                  "a variable or coordinate name"),
                            "array of {name, min, max}"),
                    {.meaning = "ranges of any number of variables or coordinates (`x`, `y`, `z` km, `lat` °N, `lon` "
                                "°E, `radius` km, `depth` km); min ≤ max. A name that repeats adds a range to its "
                                "axis (version ≥ 4): a sample is selected when on every brushed axis it lies in at "
                                "least one of the axis' ranges (OR within an axis, AND over axes); a sample not "
                                "selected contributes nothing"}),
            leaf<S>("level", at(&S::level), level(),
                    {.meaning = "level of detail; auto = finest level whose estimated pass time fits the pass's share of `timeBudgetMs`",
                     .cost = Cost::Reload}),
            leaf<S>("timeBudgetMs", at(&S::timeBudgetMs), number<double>(1e-3, 1e7),
                    {.meaning = "time budget of one interactive frame on the server, ms: its pass gets three quarters of it less the measured time of preparing and encoding a frame (docs/rendering.md, level of detail); a step of playback is shown for about this long", .cost = Cost::Reload}),
            leaf<S>("passes", at(&S::passes), integer(1, 100000),
                    {.meaning = "progressive passes accumulated for a still image", .cost = Cost::None}),
            leaf<S>("convergenceGreyLevels", at(&S::convergenceGreyLevels), number<float>(0, 255),
                    {.meaning = "adaptive refinement of a still image: a block of 8² pixels stops taking passes "
                                "(of at most `passes`) once its estimated error is below this many 8-bit levels "
                                "(docs/rendering.md, adaptive refinement); 0: every pass renders every pixel",
                     .cost = Cost::None,
                     .since = 6}),
            leaf<S>("stepFactor", at(&S::stepFactor), number<float>(0.05, 8),
                    {.meaning = "step length as a fraction of the local cell extent along the ray"}),
            leaf<S>("depthOpacity", at(&S::depthOpacity), number<float>(1e-3, 0.999),
                    {.meaning = "accumulated opacity that defines a pixel's depth"}),
            group<S>("core", "",
                     {leaf<S>("visible", at(&S::core, &S::Core::visible), boolean(),
                              {.meaning = "draw the opaque core sphere at the core–mantle boundary"}),
                      leaf<S>("variable", at(&S::core, &S::Core::variable), text(true),
                              {.meaning = "colour the core by this variable at the core radius",
                               .defaultText = "`\"\"` or null: plain colour"}),
                      leaf<S>("color", at(&S::core, &S::Core::color), color(), {.meaning = "plain core colour"}),
                      leaf<S>("colorMap", at(&S::core, &S::Core::colorMap), colorMap(),
                              {.meaning = "colour map of the core variable"}),
                      leaf<S>("range", at(&S::core, &S::Core::range), range(),
                              {.meaning = "value range for the core colour map",
                               .defaultText = "null: the global range"})},
                     {.meaning = "the core sphere at the core–mantle boundary"}),
            group<S>("shading", "",
                     {leaf<S>("enabled", at(&S::shading, &ShadingStyle::enabled), boolean(),
                              {.meaning = "shading of the volume from the gradient of the colouring variable on the native grid (two-sided Blinn–Phong)"}),
                      leaf<S>("light", at(&S::shading, &ShadingStyle::lightFromCamera), vec3(true),
                              {.meaning = "direction towards the light in the camera frame (x right, y up, z "
                                          "towards the viewer)"}),
                      leaf<S>("ambient", at(&S::shading, &ShadingStyle::ambient), number<float>(0, 1),
                              {.meaning = "ambient lighting weight (also used for the core)"}),
                      leaf<S>("diffuse", at(&S::shading, &ShadingStyle::diffuse), number<float>(0, 1),
                              {.meaning = "diffuse lighting weight (also used for the core)"}),
                      leaf<S>("specular", at(&S::shading, &ShadingStyle::specular), number<float>(0, 1),
                              {.meaning = "weight of the Blinn–Phong highlight of the volume", .since = 3}),
                      leaf<S>("shininess", at(&S::shading, &ShadingStyle::shininess), number<float>(1, 256),
                              {.meaning = "exponent of the highlight (larger: smaller, sharper)", .since = 3}),
                      leaf<S>("shadows", at(&S::shading, &ShadingStyle::shadows), boolean(),
                              {.meaning = "soft shadows from the light and ambient occlusion, cast by the volume, the "
                                          "core and the tubes on the volume, the core and the tubes (a coarse "
                                          "occlusion grid, docs/rendering.md; applies with or without `enabled`)",
                               .since = 6}),
                      leaf<S>("shadowStrength", at(&S::shading, &ShadingStyle::shadowStrength), number<float>(0, 1),
                              {.meaning = "how much of the occluded light `shadows` takes away (0: none, 1: all)",
                               .since = 6})},
                     {.meaning = "lighting of the volume and the core"}),
            leaf<S>("background", at(&S::background), color(), {.meaning = "background colour of PNG output"}),
            leaf<S>("legend", at(&S::legend), boolean(),
                    {.meaning = "colour legends (variable, units, range; the pathlines' colouring when shown) in "
                                "still pictures: `raypc render` and screenshots (the UI draws its own on the view)",
                     .since = 3}),
            group<S>("selection", "",
                     {leaf<S>("show", at(&S::selection, &S::Selection::show), boolean(),
                              {.meaning = "show the selection: while `brushes` are set, every selected sample is "
                                          "drawn with at least `minOpacity`, whatever `color.opacity` gives its "
                                          "value (its colour stays the transfer function's); no effect without "
                                          "brushes. The UI turns it on when brushing starts from the default "
                                          "view"}),
                      leaf<S>("minOpacity", at(&S::selection, &S::Selection::minOpacity), number<float>(0, 1),
                              {.meaning = "the least opacity of a selected sample over `color.opacityUnitKm` when "
                                          "`show` is on"})},
                     {.meaning = "selected samples made visible whatever the transfer function says", .since = 8}),
            group<S>(
                "pathlines", "PathlineState",
                {leaf<S>("visible", at(&S::pathlines, &P::visible), boolean(),
                         {.meaning = "draw the pathlines as tubes (ray traced with Embree in the volume's frame)"}),
                 leaf<S>("radiusKm", at(&S::pathlines, &P::radiusKm), number<float>(1e-6, 1e5),
                         {.meaning = "tube radius, km (a change refits the tube BVH)"}),
                 leaf<S>("minWidthPx", at(&S::pathlines, &P::minWidthPx), number<float>(0, 100),
                         {.meaning = "tubes at least this many pixels wide at the camera target's distance (the "
                                     "radius grows when zoomed out); 0: `radiusKm` alone",
                          .since = 3}),
                 leaf<S>("window", at(&S::pathlines, &P::window), integer(1, analysis::kMaxPathlineWindow),
                         {.meaning = "show lines injected in steps [`step` − window + 1, `step`] (a change reloads "
                                     "the line window and its BVH)",
                          .cost = Cost::Reload}),
                 leaf<S>("colorBy", at(&S::pathlines, &P::colorBy), text(true, "\"age\" or a line attribute name"),
                         {.meaning = "`\"age\"` (point time − the line's injection time, Myr) or a line attribute "
                                     "column (docs/format.md, e.g. `\"length\"`, `\"start temperature anomaly\"`)"}),
                 leaf<S>("colorMap", at(&S::pathlines, &P::colorMap), optionalColorMap(),
                         {.meaning = "colour map of `colorBy` (written as the map in effect)",
                          .defaultText = "null: `\"blue-white-red\"` for age, else `\"viridis\"`"},
                         [](const S& s) { return json(std::string(colorMapName(s.pathlines.effectiveColorMap()))); }),
                 leaf<S>("range", at(&S::pathlines, &P::range), range(),
                         {.meaning = "value range of the colour map",
                          .defaultText = "null: age [0, window × step length in Myr] (blue at the seed, white half "
                                         "way, red at the end of the window); an attribute: its range over the loaded "
                                         "lines (symmetric for centred maps)"}),
                 leaf<S>("filterByBrushes", at(&S::pathlines, &P::filterByBrushes), boolean(),
                         {.meaning = "show a line only if its start satisfies every `brushes` range (coordinates from "
                                     "`start lat`/`start lon`/`start radius`, variables from `start <variable>`)"}),
                 leaf<S>("filters", at(&S::pathlines, &P::filters),
                         arrayOf(namedRange<PathlineFilter>("PathlineFilter", "a line attribute column",
                                                            "a line attribute name"),
                                 "array of {name, min, max}"),
                         {.meaning = "ranges over line attribute columns (the pathline parallel-coordinates plot); "
                                     "min ≤ max; a column that repeats ORs its ranges, as in `brushes` (version ≥ 4)"}),
                 leaf<S>("ambientOcclusion", at(&S::pathlines, &P::ambientOcclusion), boolean(),
                         {.meaning = "ambient occlusion on the tubes (a few rays per pass against the tubes and the "
                                     "core)"})},
                {.meaning = "tubes along the pathlines injected in the last `window` steps", .since = 2}),
            group<S>(
                "reference", "ReferenceState",
                {group<S>("shells", "",
                          {leaf<S>("visible", at(&S::reference, &R::shells, &R::Shells::visible), boolean(),
                                   {.meaning = "draw thin translucent spheres at the given depths"}),
                           leaf<S>("depthsKm", at(&S::reference, &R::shells, &R::Shells::depthsKm),
                                   numberList(0, 6371, 32),
                                   {.meaning = "depths below the surface, km (e.g. the 410 and 660 km "
                                               "discontinuities); depths outside the grid's shell draw nothing"}),
                           leaf<S>("opacity", at(&S::reference, &R::shells, &R::Shells::opacity), number<float>(0, 1),
                                   {.meaning = "opacity of a shell seen face-on; it grows towards the silhouette, "
                                               "where the line of sight runs along the shell"}),
                           leaf<S>("color", at(&S::reference, &R::shells, &R::Shells::color), color(),
                                   {.meaning = "tint of the shells: each shell has its own colour from a fixed "
                                               "palette in the list's order (yellow, green, magenta, orange, violet), "
                                               "multiplied by this; white shows the palette"})},
                          {.meaning = "reference shells at fixed depths"}),
                 group<S>("graticule", "",
                          {leaf<S>("visible", at(&S::reference, &R::graticule, &R::Graticule::visible), boolean(),
                                   {.meaning = "draw parallels and meridians on the surface"}),
                           leaf<S>("spacingDeg", at(&S::reference, &R::graticule, &R::Graticule::spacingDeg),
                                   number<float>(1, 90), {.meaning = "spacing of the lines, degrees"}),
                           leaf<S>("opacity", at(&S::reference, &R::graticule, &R::Graticule::opacity),
                                   number<float>(0, 1), {.meaning = "line opacity"}),
                           leaf<S>("color", at(&S::reference, &R::graticule, &R::Graticule::color), color(),
                                   {.meaning = "line colour"})},
                          {.meaning = "latitude/longitude graticule on the surface"}),
                 group<S>("coastlines", "",
                          {leaf<S>("visible", at(&S::reference, &R::coastlines, &R::Coastlines::visible), boolean(),
                                   {.meaning = "draw the coastlines on the surface (Natural Earth 1:110m, from the "
                                               "npm package world-atlas; the UI build writes coastlines.json)"}),
                           leaf<S>("opacity", at(&S::reference, &R::coastlines, &R::Coastlines::opacity),
                                   number<float>(0, 1), {.meaning = "line opacity"}),
                           leaf<S>("color", at(&S::reference, &R::coastlines, &R::Coastlines::color), color(),
                                   {.meaning = "line colour"})},
                          {.meaning = "coastlines of the Earth's surface"}),
                 leaf<S>("lineWidthPx", at(&S::reference, &R::lineWidthPx), number<float>(0.25, 32),
                         {.meaning = "width of graticule and coastline lines, pixels of the image"})},
                {.meaning = "reference geometry drawn with the volume and composited by depth", .since = 3}),
            group<S>(
                "map", "MapState",
                {leaf<S>("depthKm", at(&S::map, &MapState::depthKm), number<float>(0, 6371),
                         {.meaning = "depth of the slice below the surface, km; a map needs it within the grid's "
                                     "radii (from the outermost to the innermost)"}),
                 leaf<S>("projection", at(&S::map, &MapState::projection), mapProjection(),
                         {.meaning = "map projection (d3-geo's and d3-geo-projection's formulas, in the UI and in "
                                     "figures alike)"}),
                 leaf<S>("centralMeridianDeg", at(&S::map, &MapState::centralMeridianDeg), number<float>(-180, 180),
                         {.meaning = "longitude at the map's centre, degrees east"}),
                 leaf<S>("centralLatitudeDeg", at(&S::map, &MapState::centralLatitudeDeg), number<float>(-90, 90),
                         {.meaning = "latitude at the centre of the `orthographic` projection, degrees north (the "
                                     "other projections are centred on the equator)"}),
                 leaf<S>("greyUnselected", at(&S::map, &MapState::greyUnselected), boolean(),
                         {.meaning = "while `brushes` are set, what lies outside the selection is drawn in grey "
                                     "(its value's lightness kept), so the selection stands out in colour (on maps "
                                     "and sections)"}),
                 leaf<S>("contours", at(&S::map, &MapState::contours), numberList(-INFINITY, INFINITY, 16),
                         {.meaning = "contour lines at these values of the colour variable (on maps and sections)"}),
                 leaf<S>("flow", at(&S::map, &MapState::flow), boolean(),
                         {.meaning = "arrows of the horizontal flow at the depth (east and north components of the "
                                     "velocity; needs `vx`, `vy`, `vz`)"}),
                 leaf<S>("showInView", at(&S::map, &MapState::showInView), boolean(),
                         {.meaning = "the 3D view marks where the map and the section lie: the map's depth as a cyan "
                                     "shell, the section's curtain as cyan lines (its arc at the surface and at the "
                                     "innermost radius, radial lines at its ends); the UI turns it on while its Map "
                                     "& section tab is shown"})},
                {.meaning = "a map of the colour variable on the sphere at one depth (`raypc map`, the UI's map "
                            "panel); the colours are the transfer function's, its opacity does not apply",
                 .since = 9}),
            group<S>(
                "section", "SectionState",
                {group<S>("from", "",
                          {leaf<S>("latDeg", at(&S::section, &SectionState::from, &SectionState::Point::latDeg),
                                   number<float>(-90, 90), {.meaning = "latitude, degrees north"}),
                           leaf<S>("lonDeg", at(&S::section, &SectionState::from, &SectionState::Point::lonDeg),
                                   number<float>(-360, 360), {.meaning = "longitude, degrees east"})},
                          {.meaning = "the section's start on the surface"}),
                 group<S>("to", "",
                          {leaf<S>("latDeg", at(&S::section, &SectionState::to, &SectionState::Point::latDeg),
                                   number<float>(-90, 90), {.meaning = "latitude, degrees north"}),
                           leaf<S>("lonDeg", at(&S::section, &SectionState::to, &SectionState::Point::lonDeg),
                                   number<float>(-360, 360), {.meaning = "longitude, degrees east"})},
                          {.meaning = "the section's end on the surface (not the start nor its antipode)"}),
                 leaf<S>("flow", at(&S::section, &SectionState::flow), boolean(),
                         {.meaning = "arrows of the flow in the section's plane (the velocity's components along "
                                     "the profile and radial; needs `vx`, `vy`, `vz`)"})},
                {.meaning = "a vertical section along the great circle from `from` to `to` (the shorter arc), from "
                            "the surface to the core-mantle boundary (`raypc section`); colours, contours and "
                            "brushes as on the map",
                 .since = 9}),
            group<S>(
                "features", "FeatureSettings",
                {leaf<S>("minVolumeKm3", at(&S::features, &FeatureSettings::minVolumeKm3), number<float>(0, 1e12),
                         {.meaning = "regions of the selection smaller than this, km³, are dropped (specks)"}),
                 leaf<S>("depthsKm", at(&S::features, &FeatureSettings::depthsKm), numberList(0, 6371, 32),
                         {.meaning = "depths, km, at which each feature reports the share of its volume within "
                                     "`bandHalfWidthKm`, and at which tracks' stalls are timed"}),
                 leaf<S>("bandHalfWidthKm", at(&S::features, &FeatureSettings::bandHalfWidthKm), number<float>(0, 3000),
                         {.meaning = "half-width of the band around each of `depthsKm`, km"}),
                 leaf<S>("level", at(&S::features, &FeatureSettings::level), integer(0, 2),
                         {.meaning = "level of detail the regions are found at (0: full resolution; the dataset "
                                     "must have it)"}),
                 leaf<S>("minOverlapShare", at(&S::features, &FeatureSettings::minOverlapShare), number<float>(0, 1),
                         {.meaning = "share of a feature's volume that, moved with the flow over a step, must fall "
                                     "on a feature of the next step to link them into one track"}),
                 leaf<S>("stallBy", at(&S::features, &FeatureSettings::stallBy), stallMeasure(),
                         {.meaning = "which depth of a feature times its stalls at `depthsKm`: `mean-depth` (its "
                                     "volume-weighted mean depth), `deepest` (its deepest point: a sinking slab's "
                                     "tip) or `shallowest` (its shallowest point: a rising plume's head)",
                          .since = 12}),
                 leaf<S>("colorById", at(&S::features, &FeatureSettings::colorById), boolean(),
                         {.meaning = "the 3D view colours the selection by feature: each feature of the step in its "
                                     "own colour (its id modulo 10, the UI's table's colours), other selected material "
                                     "dark grey and faint",
                          .since = 11}),
                 leaf<S>("highlight", at(&S::features, &FeatureSettings::highlight), integerList(1, 1000000, 64),
                         {.meaning = "ids of features of the state's step drawn highlighted (amber, or their own "
                                     "colour with `colorById`); the rest of the selection dark grey and faint; empty: none",
                          .since = 11})},
                {.meaning = "how the connected regions of the selection (features) are found and followed through "
                            "the steps (`raypc features --state`, docs/features.md); a saved state reproduces their "
                            "table",
                 .since = 10}),
            group<S>(
                "stereo", "StereoState",
                {leaf<S>("mode", at(&S::stereo, &StereoState::mode), stereoMode(),
                         {.meaning = "stereo pairs: `side-by-side` puts the left eye's picture beside the right "
                                     "eye's, each `image.width` wide (2 × width); `side-by-side-half` squeezes each eye into half the width "
                                     "(width × height, for 3D displays); `anaglyph` is red–cyan (red: the left "
                                     "eye's luma, green and blue: the right eye's)"}),
                 leaf<S>("eyeSeparationKm", at(&S::stereo, &StereoState::eyeSeparationKm), number<float>(0, 1e6),
                         {.meaning = "distance between the eyes, km (side by side along the image's horizontal "
                                     "axis, centred on the camera's position)"}),
                 leaf<S>("convergenceKm", at(&S::stereo, &StereoState::convergenceKm), optionalNumber(1e-3, 1e9),
                         {.meaning = "distance in front of the eyes of the zero-parallax plane (the screen), km; "
                                     "nearer points stand out of the screen, farther ones lie behind it (parallel "
                                     "view axes, asymmetric frusta)",
                          .defaultText = "null: `camera.distanceKm` (the camera's target on the screen)"})},
                {.meaning = "stereoscopic output of the camera (docs/rendering.md, Stereo)", .since = 5}),
            leaf<S>("pair", at(&S::pair),
                    optionalObject<PairState>(
                        {"PairState",
                         {leaf<PairState>("dataset", at(&PairState::dataset), text(false, "a dataset directory"),
                                          {.meaning = "the second dataset's directory (relative: to the working "
                                                      "directory of `raypc render`; the UI writes the name the "
                                                      "server gives, `GET /api/info` `pair`)",
                                           .cost = Cost::Reload,
                                           .required = true,
                                           .expect = "a dataset directory"}),
                          leaf<PairState>("steps", at(&PairState::steps), pairSteps(),
                                          {.meaning = "which step of the second dataset is drawn: `time` its step "
                                                      "nearest in model time to the state's `step` (the earlier of "
                                                      "two as near), `index` the same index (the last if it has "
                                                      "fewer)",
                                           .cost = Cost::Reload,
                                           .defaultText = "`time`"})},
                         {}},
                        "object or null"),
                    {.meaning = "two datasets side by side (docs/compare.md, \"Side by side\"): the state is drawn "
                                "for this second dataset too, each in half the image's width, the first on the "
                                "left, with the same camera, transfer function and brushes (by name: a brush on a "
                                "variable the second lacks is left out for it)",
                     .cost = Cost::Reload,
                     .defaultText = "null: one dataset",
                     .since = 13}),
        },
        // Explicit views: one, or a stereo pair's two eyes. Before version 4 a repeated name meant
        // the intersection of its ranges (nothing wrote that); since then the union. An older
        // document repeating a name is refused rather than re-read.
        [](const S& s, Reader& r) {
            if (const std::string problem = cameraViewsMismatch(s); !problem.empty())
                r.failAt("camera.views", problem);
            if (r.version() >= 4)
                return;
            auto refuseRepeats = [&](const std::vector<analysis::NamedRange>& ranges, const std::string& key) {
                for (size_t i = 0; i < ranges.size(); ++i)
                    for (size_t j = 0; j < i; ++j)
                        if (ranges[j].name == ranges[i].name)
                            r.failAt(fmt::format("{}[{}]", key, i),
                                     fmt::format("a second range on '{}' needs version 4 (ranges on one axis are "
                                                 "OR-ed), the document says version {}",
                                                 ranges[i].name, r.version()));
            };
            refuseRepeats(s.brushes, "brushes");
            refuseRepeats(s.pathlines.filters, "pathlines.filters");
        }};
    return doc;
}

}  // namespace

RenderState parseRenderState(const json& j, const std::string& what)
{
    ParseContext context{what};
    RenderState s;
    Reader top(j, context, "");
    document().read(top, s);
    return s;
}

json toJson(const RenderState& s) { return document().write(s); }

json stateJsonSchema()
{
    json schema = document().schema(toJson(RenderState{}));
    schema["$schema"] = "http://json-schema.org/draft-07/schema#";
    schema["description"] =
        fmt::format("The RayPC render state document, version {} (docs/state.md). Generated by `raypc state-schema` "
                    "from src/state/state_schema.cpp; do not edit.",
                    kRenderStateVersion);
    // Keys newer than the document's version are refused, as parseRenderState does.
    json gates = json::array();
    for (int v = 1; v < kRenderStateVersion; ++v)
        if (json forbidden = document().forbiddenBefore(v); !forbidden.is_null())
            gates.push_back({{"if", {{"properties", {{"version", {{"const", v}}}}}}}, {"then", forbidden}});
    if (!gates.empty())
        schema["allOf"] = gates;
    return schema;
}

std::string stateFieldTable()
{
    Rows rows;
    document().rows("", toJson(RenderState{}), rows);
    std::string out = "| key | type | default | meaning | cost |\n|---|---|---|---|---|\n";
    for (const auto& row : rows) {
        out += "|";
        for (size_t i = 0; i < row.size(); ++i)
            out += " " + (i == 0 ? "`" + row[i] + "`" : row[i]) + " |";
        out += "\n";
    }
    return out;
}

}  // namespace raypc::state
