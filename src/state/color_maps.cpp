#include "state/color_maps.h"

#include "core/error.h"
#include "core/strings.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>

namespace raypc::state {
namespace {

// The text of src/state/color_maps.json, compiled in (CMake writes color_maps_json.inc).
constexpr const char* kTableJson =
#include "color_maps_json.inc"
    ;

struct MapEntry {
    std::string name;
    bool diverging = false, centred = false;
    std::vector<ColorStop> stops;
};

constexpr int kMapCount = int(ColorMapId::Balance) + 1;

// The table, read once. Its order is the enum's; a mismatch is a build error in all but name, so
// it is checked here and fails loudly at the first use.
const std::vector<MapEntry>& table()
{
    static const std::vector<MapEntry> maps = [] {
        static const char* const kNames[kMapCount] = {"viridis", "inferno", "cool-to-warm", "blue-white-red", "grayscale",
                                                      "batlow",  "lajolla", "vik",          "roma",           "thermal",
                                                      "balance"};
        const auto j = nlohmann::json::parse(kTableJson);
        std::vector<MapEntry> out;
        for (const auto& m : j.at("maps")) {
            MapEntry e;
            e.name = m.at("name").get<std::string>();
            e.diverging = m.at("kind").get<std::string>() == "diverging";
            e.centred = m.at("centred").get<bool>();
            for (const auto& s : m.at("stops"))
                e.stops.push_back({s.at(0).get<float>(), {s.at(1).get<float>(), s.at(2).get<float>(), s.at(3).get<float>()}});
            out.push_back(std::move(e));
        }
        if (out.size() != size_t(kMapCount))
            fail("color_maps.json: {} maps, the program knows {}", out.size(), kMapCount);
        for (int i = 0; i < kMapCount; ++i)
            if (out[size_t(i)].name != kNames[i])
                fail("color_maps.json: map {} is '{}', expected '{}' (the order of ColorMapId)", i, out[size_t(i)].name,
                     kNames[i]);
        return out;
    }();
    return maps;
}

const MapEntry& entry(ColorMapId map) { return table().at(size_t(map)); }

}  // namespace

std::span<const ColorStop> colorMapStops(ColorMapId map) { return entry(map).stops; }

bool isCentredOnZero(ColorMapId map) { return entry(map).centred; }

bool isDiverging(ColorMapId map) { return entry(map).diverging; }

std::string_view colorMapName(ColorMapId map) { return entry(map).name; }

const std::vector<ColorMapId>& allColorMaps()
{
    static const std::vector<ColorMapId> maps = [] {
        std::vector<ColorMapId> out;
        for (int i = 0; i < kMapCount; ++i)
            out.push_back(ColorMapId(i));
        return out;
    }();
    return maps;
}

ColorMapId parseColorMap(std::string_view name)
{
    std::string known;
    if (const auto map = findByName(name, allColorMaps(), colorMapName, known))
        return *map;
    // Accepted aliases: the names ParaView and matplotlib users type.
    if (name == "coolwarm" || name == "Cool to Warm")
        return ColorMapId::CoolToWarm;
    if (name == "blackbody" || name == "black-body")
        return ColorMapId::Inferno;
    if (name == "RdBu" || name == "bwr")
        return ColorMapId::BlueWhiteRed;
    fail("colour map '{}' is unknown, expected one of: {}", name, known);
}

}  // namespace raypc::state
