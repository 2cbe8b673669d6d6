// The protocol's messages described once (messages() below), and what is derived from it: the JSON
// Schema the UI's types come from and the key tables of docs/protocol.md.
#include "server/protocol_schema.h"

#include "core/error.h"
#include "analysis/features.h"
#include "render/map_projection.h"
#include "render/stereo.h"
#include "server/protocol.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <map>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

namespace raypc::server {
namespace {

// In the order written (the docs tables list keys as described); the schema is returned as nlohmann::json.
using Json = nlohmann::ordered_json;

// ---- The vocabulary --------------------------------------------------------------------------

struct Key {
    std::string name;
    Json schema;
    std::string meaning;
    bool required = true;
};

Json typed(const char* type, std::string_view meaning)
{
    return {{"type", type}, {"description", meaning}};
}
Json number(std::string_view meaning) { return typed("number", meaning); }
Json integer(std::string_view meaning) { return typed("integer", meaning); }
Json text(std::string_view meaning) { return typed("string", meaning); }
Json boolean(std::string_view meaning) { return typed("boolean", meaning); }
Json constant(const Json& value, std::string_view meaning)
{
    return {{"const", value}, {"description", meaning}};
}
Json oneOfTexts(std::vector<std::string> values, std::string_view meaning)
{
    return {{"type", "string"}, {"enum", std::move(values)}, {"description", meaning}};
}

std::vector<std::string> stallMeasureNames()
{
    std::vector<std::string> names;
    for (const analysis::StallMeasure m : analysis::kStallMeasures)
        names.emplace_back(analysis::stallMeasureName(m));
    return names;
}
Json arrayOf(Json items, std::string_view meaning)
{
    return {{"type", "array"}, {"items", std::move(items)}, {"description", meaning}};
}
Json pairOf(Json items, std::string_view meaning)
{
    Json s = arrayOf(std::move(items), meaning);
    s["minItems"] = 2;
    s["maxItems"] = 2;
    return s;
}
// A part described once and used in several messages: its own definition, and its own table.
Json ref(std::string_view part)
{
    return {{"$ref", fmt::format("#/definitions/{}", part)}};
}
Json nullable(Json schema)
{
    if (schema.contains("$ref"))
        return {{"anyOf", Json::array({std::move(schema), {{"type", "null"}}})}};
    schema["type"] = Json::array({schema["type"], "null"});
    if (schema.contains("enum"))
        schema["enum"].push_back(nullptr);
    return schema;
}
// A state document (docs/state.md): checked by its own schema, typed by the UI's RenderState.
Json stateDocument(std::string_view meaning)
{
    return {{"type", "object"}, {"tsType", "RenderState"}, {"description", meaning}};
}
Json closedObject(std::string_view meaning, const std::vector<Key>& keys)
{
    Json properties = Json::object(), required = Json::array();
    for (const Key& k : keys) {
        Json s = k.schema;
        if (!s.contains("$ref") && !k.meaning.empty())
            s["description"] = k.meaning;
        properties[k.name] = std::move(s);
        if (k.required)
            required.push_back(k.name);
    }
    return {{"type", "object"},
            {"description", meaning},
            {"properties", std::move(properties)},
            {"required", std::move(required)},
            {"additionalProperties", false}};
}
// An inline object with a type name of its own in the UI.
Json named(std::string_view title, std::string_view meaning, const std::vector<Key>& keys)
{
    Json s = closedObject(meaning, keys);
    s["title"] = title;
    return s;
}
// An object whose keys are names (variables, coordinates), each with a value of `value`'s shape.
Json mapOf(Json value, std::string_view meaning)
{
    return {{"type", "object"}, {"additionalProperties", std::move(value)}, {"description", meaning}};
}

// The names of an enumeration (render's), as the state writes them; `skip` is left out.
template <class E, class All>
Json namesOf(const All& all, std::string_view (*name)(E), std::string_view meaning, std::optional<E> skip = {})
{
    Json names = Json::array();
    for (const E e : all)
        if (e != skip)
            names.push_back(std::string(name(e)));
    return {{"type", "string"}, {"enum", std::move(names)}, {"description", meaning}};
}

struct Definition {
    std::string title;
    std::string carrier;  // empty for a part of messages
    Json schema;
};

Definition message(std::string title, std::string carrier, std::string_view meaning, const std::vector<Key>& keys)
{
    Json s = closedObject(meaning, keys);
    s["title"] = title;
    s["x-carrier"] = carrier;
    return {std::move(title), std::move(carrier), std::move(s)};
}
Definition part(std::string title, std::string_view meaning, const std::vector<Key>& keys)
{
    Json s = closedObject(meaning, keys);
    s["title"] = title;
    return {std::move(title), "", std::move(s)};
}

// ---- The messages ----------------------------------------------------------------------------

std::vector<Key> selectionKeys()
{
    return {{"fractionOfMantle", number(""), "selected volume over the mantle shell's volume, 0..1"},
            {"volumeKm3", number(""), "selected volume, km³ (exact from the grid's dual-cell volumes)"}};
}

// The keys of a map's or a section's picture header (`view`), then `more`.
std::vector<Key> sliceKeys(const char* view, std::vector<Key> more)
{
    std::vector<Key> keys{{"view", constant(view, ""), fmt::format("`{}`", view)},
                          {"width", integer(""), "the picture's width, pixels"},
                          {"height", integer(""), "its height, pixels"},
                          {"step", integer(""), "the step drawn"}};
    keys.insert(keys.end(), std::make_move_iterator(more.begin()), std::make_move_iterator(more.end()));
    return keys;
}

const std::vector<Definition>& messages()
{
    static const std::vector<Definition> all = [] {
        std::vector<Definition> d;
        const Json range = pairOf(number(""), "");

        // -- HTTP ----------------------------------------------------------------------------
        d.push_back(part("VariableInfo", "a variable of the dataset, over all steps",
                         {{"name", text(""), "the variable's name (e.g. `temperature anomaly`)"},
                          {"units", text(""), "its units as the file gives them"},
                          {"derived", boolean(""), "computed at preprocessing (e.g. `velocity magnitude`), not in the files"},
                          {"source", text(""),
                           "a stored variable's name in the input files, a derived one's inputs (e.g. `vx, vy, vz`); "
                           "empty for a computed one and in datasets written before it was recorded"},
                          {"computed",
                           named("ComputedFrom", "",
                                 {{"from", text(""), "the stored variable it is computed from"},
                                  {"kind", oneOfTexts({"anomaly", "anomaly %"}, ""),
                                   "`anomaly`: minus its shell mean at each radius; `anomaly %`: that difference in % of the mean"}}),
                           "only for a variable computed when read (a shell anomaly, dataset/shell_anomaly.h)", false},
                          {"min", number(""), "smallest value over every step"},
                          {"max", number(""), "largest value over every step"},
                          {"mean", number(""), "volume-weighted mean over every step"},
                          {"histogram", arrayOf(number(""), ""), "256 volume fractions over [min, max]"},
                          {"defaultColorRange",
                           named("DefaultColorRange", "",
                                 {{"centred", range, "[lo, hi] for colour maps centred on zero: ±the 99.5th percentile of \\|v\\| rounded up to a nice number"},
                                  {"other", range, "[lo, hi] for the others"}}),
                           "the colour range the renderer takes when the state gives none (`render::defaultColorRange`)"}}));
        d.push_back(part("CoordinateInfo", "a coordinate the sample and the brushes offer",
                         {{"name", text(""), "`x`, `y`, `z`, `lat`, `lon`, `radius` or `depth`"},
                          {"units", text(""), "`km` or `degrees_north`/`degrees_east`"},
                          {"min", number(""), "smallest value on the grid"},
                          {"max", number(""), "largest value on the grid"}}));
        d.push_back(message(
            "Info", "GET /api/info", "the dataset",
            {{"protocol", integer(""), fmt::format("the protocol's version ({})", kProtocolVersion)},
             {"name", text(""),
              "the dataset: its directory's last two path components (e.g. `demo-data/dataset`; no absolute "
              "path, the UI may be remote)"},
             {"variables", arrayOf(ref("VariableInfo"), ""), "the variables, in the dataset's order"},
             {"coordinates", arrayOf(ref("CoordinateInfo"), ""), "the coordinates (grid/coordinates.h)"},
             {"steps",
              arrayOf(named("StepInfo", "",
                            {{"index", integer(""), "the step's index"},
                             {"timeMyr", number(""), "model time, Myr"},
                             {"source", text(""), "the file it came from"}}),
                      ""),
              "the time steps"},
             {"levels",
              arrayOf(named("LevelInfo", "",
                            {{"level", integer(""), "0 = full resolution"},
                             {"nLat", integer(""), "grid points in latitude"},
                             {"nR", integer(""), "grid points in radius"},
                             {"nLon", integer(""), "grid points in longitude"}}),
                      ""),
              "the levels of detail"},
             {"sample",
              named("SampleInfo", "",
                    {{"rows", integer(""), "rows of `GET /api/sample`"},
                     {"columns", arrayOf(text(""), ""), "its columns: the coordinates, then the variables"},
                     {"units", arrayOf(text(""), ""), "the columns' units"}}),
              "the shape of the parallel coordinates' sample"},
             {"colorMaps", arrayOf(text(""), ""), "the colour maps' names"},
             {"featurePalette", arrayOf(arrayOf(number(""), ""), ""),
              "the colours (r, g, b in 0..1) the 3D view paints features in (render/feature_paint.h): slot 0 the "
              "rest of the selection, 1..10 a feature by its id ((id − 1) mod 10 + 1), 11 a highlighted one"},
             {"defaultState", stateDocument(""), "a full state document: the first view (`render::defaultState`)"},
             {"noPathlines", text(""),
              "why the dataset has no pathlines (the model has no velocity, its flow has missing values, "
              "preprocessed with --no-pathlines); absent when it has them",
              false},
             {"pair",
              named("PairInfo", "",
                    {{"index", integer(""), "which of the two this info is about: 0, or 1 (asked with `?dataset=1`)"},
                     {"datasets",
                      arrayOf(named("PairDataset", "",
                                    {{"name", text(""), "the dataset's name, as `name` above"},
                                     {"timesMyr", arrayOf(number(""), ""), "its steps' model times, Myr"}}),
                              ""),
                      "the two datasets, first then second"}}),
              "only when the server serves a pair (`raypc serve A B`, docs/compare.md): the endpoints and `/ws` "
              "take `dataset=1` for the second",
              false},
             {"limits",
              named("ServerLimits", "",
                    {{"screenshotPixels", integer(""), "largest width × height of a screenshot"},
                     {"screenshotPasses", integer(""), "most passes of a screenshot"},
                     {"screenshotPixelPasses", integer(""), "largest width × height × passes"}}),
              "what `POST /api/screenshot` takes"}}));
        d.push_back(message("Histogram", "GET /api/histogram", "one variable at one step",
                            {{"name", text(""), "the variable"},
                             {"units", text(""), "its units"},
                             {"min", number(""), "smallest value at the step"},
                             {"max", number(""), "largest value at the step"},
                             {"histogram", arrayOf(number(""), ""), "256 volume fractions over [min, max]"}}));
        {
            std::vector<Key> keys = selectionKeys();
            keys.push_back({"step", integer(""), "the step it is of"});
            keys.push_back({"empty",
                            arrayOf(named("EmptyBecause", "",
                                          {{"name", text(""), "a brushed variable or coordinate"},
                                           {"alone", number(""), "the fraction of the mantle its ranges select alone, 0..1"},
                                           {"withoutIt", number(""),
                                            "the fraction the other brushes select without it (1 when it is the only one)"}}),
                                    ""),
                            "only when the brushes select nothing: per brushed axis, in the brushes' order, what "
                            "excluded everything (an axis selecting nothing alone, or one whose removal selects something)",
                            false});
            d.push_back(message("Selection", "POST /api/selection",
                                "the volume inside every brush, at full resolution", keys));
        }
        d.push_back(message(
            "SeriesProgress", "GET /api/progress", "the background preprocessing of `raypc serve FILE.nc…`",
            {{"state", oneOfTexts({"complete", "preparing", "ready", "failed"}, ""),
              "`complete`: a whole dataset is shown (no other key); `preparing`; `ready`: the whole series is written, reload; `failed`"},
             {"dataset", text(""), "the dataset being written", false},
             {"steps", integer(""), "steps of the series", false},
             {"phase", oneOfTexts({"steps", "pathlines"}, ""), "what the line shows: the steps until every one is written, then the pathlines (a one-pass run writes them in turn)", false},
             {"done", integer(""), "items done, including what an earlier run finished", false},
             {"total", integer(""), "items of that phase", false},
             {"elapsedSeconds", number(""), "seconds since the run started", false},
             {"etaSeconds", nullable(number("")), "seconds left in the phase shown, at this run's rate in it (a one-pass run traces the pathlines as the steps are written: the last sets follow the last step); null until this run finished an item", false},
             {"message", text(""), "why it failed (`failed` only)", false}}));
        d.push_back(message(
            "JobProgress", "GET /api/job-progress?job=ID",
            "where the request `POST /api/features?job=ID` is (the id is the client's: 1-64 letters, digits, `-`, `_`)",
            {{"job", text(""), "the id asked about"},
             {"state", oneOfTexts({"unknown", "running", "done", "failed"}, ""),
              "`unknown`: not started (waiting behind another request) or forgotten (the last 32 are kept); "
              "`running`; `done`: answered; `failed`: refused or cancelled"},
             {"done", integer(""), "steps done"},
             {"total", integer(""), "steps of the series (0 until it runs)"},
             {"elapsedSeconds", number(""), "seconds since it started running"}}));
        d.push_back(part("Preset", "an example state of the examples directory",
                         {{"name", text(""), "the file's name without `.json`"},
                          {"title", text(""), "a short human title"},
                          {"state", typed("object", ""), "the file's document as it is (checked when applied)"},
                          {"unavailable", text(""), "why it cannot be applied to this dataset (only when so)", false}}));
        d.push_back(Definition{"Presets", "GET /api/presets",
                               {{"title", "Presets"},
                                {"x-carrier", "GET /api/presets"},
                                {"description", "every example state, sorted by name"},
                                {"type", "array"},
                                {"items", ref("Preset")}}});
        {
            std::vector<Key> stepKeys = selectionKeys();
            stepKeys.insert(stepKeys.begin(), {{"step", integer(""), "the step"}, {"timeMyr", number(""), "its time, Myr"}});
            d.push_back(message(
                "SelectionOverTime", "POST /api/stats", "the selection of the state's brushes over time",
                {{"level", integer(""), "the level the volumes are exact on"},
                 {"steps", arrayOf(named("StepSelection", "", stepKeys), ""), "every step"},
                 {"profile",
                  named("SelectionProfile", "",
                        {{"step", integer(""), "the state's step"},
                         {"radiusKm", arrayOf(number(""), ""), "the level's radii, ascending, km"},
                         {"depthKm", arrayOf(number(""), ""), "the same as depths below the surface, km"},
                         {"volumeKm3", arrayOf(number(""), ""), "selected volume of each radius' dual shell, km³"},
                         {"shellVolumeKm3", arrayOf(number(""), ""), "volume of each dual shell, km³"}}),
                  "the selection per radius at the state's step"},
                 {"profiles",
                  arrayOf(named("StepProfile", "",
                                {{"step", integer(""), "the step"},
                                 {"volumeKm3", arrayOf(number(""), ""), "selected volume of each radius' dual shell, km³"},
                                 {"shellVolumeKm3", arrayOf(number(""), ""), "volume of each dual shell, km³"}}),
                          ""),
                  "with `profiles=all` only: every step's selection per radius (the radii of `profile`), so that a "
                  "client follows the step without asking again",
                  false}}));
        }
        d.push_back(message(
            "FeatureSeries", "POST /api/features",
            "the features of the state's selection through the series, with the state's `features` settings "
            "(docs/features.md)",
            {{"level", integer(""), "the level of detail the features were found at (0: the full grid, exact)"},
             {"minVolumeKm3", number(""), "features smaller than this were dropped, km³"},
             {"depthsKm", arrayOf(number(""), ""), "the depths of the stalls, the band shares and the fluxes, km"},
             {"bandHalfWidthKm", number(""), "half-width of the band around each depth, km"},
             {"minOverlapShare", number(""), "share of a feature's volume carried onto another for a link"},
             {"stallBy", oneOfTexts(stallMeasureNames(), ""),
              "which depth of a feature times its stalls (the state's `features.stallBy`)"},
             {"steps",
              arrayOf(named("FeatureStep", "",
                            {{"step", integer(""), "the step"},
                             {"timeMyr", number(""), "its time, Myr"},
                             {"features", integer(""), "features found in it"}}),
                      ""),
              "every step"},
             {"tracks",
              arrayOf(named("FeatureTrack", "",
                            {{"track", integer(""), "the track's id, 1.."},
                             {"firstStep", integer(""), "its first step (birth, or the first step of the series)"},
                             {"lastStep", integer(""), "its last step"},
                             {"lifetimeMyr", number(""), "time from its first to its last step, Myr"},
                             {"maxVolumeKm3", number(""), "its largest volume, km³"},
                             {"meanDepthKm", number(""), "the mean over its steps of its mean depth, km"},
                             {"points",
                              arrayOf(named("TrackPoint", "",
                                            {{"step", integer(""), "the step"},
                                             {"timeMyr", number(""), "its time, Myr"},
                                             {"feature", integer(""), "the track's feature in that step (ids by decreasing volume)"},
                                             {"volumeKm3", number(""), "its volume, km³"},
                                             {"percentOfMantle", number(""), "its share of the mantle, %"},
                                             {"meanDepthKm", number(""), "volume-weighted mean depth, km"},
                                             {"topDepthKm", number(""), "its shallowest point's depth, km"},
                                             {"bottomDepthKm", number(""), "its deepest point's depth, km"},
                                             {"centroidLatDeg", number(""), "centroid latitude, degrees"},
                                             {"centroidLonDeg", number(""), "centroid longitude, 0–360 degrees"},
                                             {"centroidDepthKm", number(""), "the centroid's depth, km (below a curved feature)"},
                                             {"radialVelocityCmPerYr", nullable(number("")),
                                              "mean radial velocity, cm/yr (negative: sinking); null without one"},
                                             {"bandPercent", arrayOf(number(""), ""),
                                              "per depth of `depthsKm`, the share of its volume within the band, %"}}),
                                      ""),
                              "its feature in each of its steps, in step order"},
                             {"stalls",
                              arrayOf(named("TrackStall", "",
                                            {{"depthKm", number(""), "the depth it stalls at, km"},
                                             {"firstStep", integer(""), "first step with its `stallBy` depth in the band"},
                                             {"lastStep", integer(""), "last such step of the run"},
                                             {"durationMyr", number(""), "time from first to last step, Myr"},
                                             {"meanRadialVelocityCmPerYr", nullable(number("")),
                                              "mean over the run of the feature's mean radial velocity, cm/yr"},
                                             {"left", oneOfTexts({"down", "up", "ended", ""}, ""),
                                              "how the run ended: down, up, ended (the track stops), \"\" (still there)"}}),
                                      ""),
                              "its stalls at each depth"}}),
                      ""),
              "every track, by id"},
             {"events",
              arrayOf(named("TrackEventInfo", "",
                            {{"step", integer(""), "where it shows: birth and merge the later step, death and split the earlier"},
                             {"timeMyr", number(""), "that step's time, Myr"},
                             {"kind", oneOfTexts({"birth", "death", "merge", "split"}, ""), "what happened"},
                             {"track", integer(""), "the feature's track"},
                             {"feature", integer(""), "the feature of that step"},
                             {"others", arrayOf(integer(""), ""),
                              "merge: the earlier features; split: the later features"},
                             {"centroidLatDeg", number(""), "the feature's centroid latitude, degrees"},
                             {"centroidLonDeg", number(""), "its longitude, degrees"},
                             {"meanDepthKm", number(""), "its mean depth, km"}}),
                      ""),
              "births, deaths, merges and splits, in step order"},
             {"flux",
              nullable(named(
                  "FeatureFlux", "",
                  {{"depthsKm", arrayOf(number(""), ""), "the shells: the depths inside the grid, km"},
                   {"sigmas", number(""), "avalanche threshold: mean + sigmas × σ of the downward flux"},
                   {"steps",
                    arrayOf(named("FluxStep", "",
                                  {{"step", integer(""), "the step"},
                                   {"timeMyr", number(""), "its time, Myr"},
                                   {"downKm3PerYr", arrayOf(number(""), ""), "per shell, the downward volume flux (≤ 0), km³/yr"},
                                   {"upKm3PerYr", arrayOf(number(""), ""), "per shell, the upward volume flux (≥ 0), km³/yr"},
                                   {"selectedDownKm3PerYr", arrayOf(number(""), ""), "the same within the selection"},
                                   {"selectedUpKm3PerYr", arrayOf(number(""), ""), "the same within the selection"},
                                   {"selectedPercentOfShell", arrayOf(number(""), ""),
                                    "per shell, the share of its area in the selection, %"},
                                   {"massDownKgPerYr", arrayOf(number(""), ""),
                                    "per shell, the downward mass flux (≤ 0), kg/yr: only where the data have a "
                                    "`density` variable (kg/m³)", false},
                                   {"massUpKgPerYr", arrayOf(number(""), ""), "the same upward (≥ 0)", false}}),
                            ""),
                    "every step"},
                   {"avalanches",
                    arrayOf(named("Avalanche", "",
                                  {{"depthKm", number(""), "the shell"}, {"step", integer(""), "the step"}}),
                            ""),
                    "steps whose downward flux is an avalanche"}})),
              "the flux across the shells; null without a radial velocity"},
             {"csv",
              named("FeatureTables", "",
                    {{"tracks", text(""), "the CSV of `raypc features --tracks` (docs/features.md)"},
                     {"events", text(""), "the CSV of `raypc features --events`"},
                     {"stalls", text(""), "the CSV of `raypc features --stalls` with `stallBy`"},
                     {"flux", nullable(text("")),
                      "the CSV of `raypc flux` at the shells of `flux` (mass columns where the data have a "
                      "density); null without a radial velocity"}}),
              "the tables as the command line writes them, for the UI's CSV buttons"}}));
        d.push_back(message(
            "PathlinesHeader", "GET /api/pathlines (JSON header)", "the attributes of the pathlines shown at a step",
            {{"step", integer(""), "the step"},
             {"window", integer(""), "steps of injections shown"},
             {"lines", integer(""), "rows of the float32 values that follow"},
             {"columns", arrayOf(text(""), ""), "the attributes (docs/format.md, Pathlines)"},
             {"units", arrayOf(text(""), ""), "their units"},
             {"sets",
              arrayOf(named("PathlineSetInfo", "",
                            {{"injectionStep", integer(""), "the step the set was seeded at"},
                             {"injectionTimeMyr", number(""), "its time, Myr"},
                             {"lines", integer(""), "its lines"}}),
                      ""),
              "the sets of the window, oldest first"}}));
        d.push_back(message(
            "PersistenceDiagram", "GET /api/persistence", "the persistence diagram of a step (docs/persistence.md)",
            {{"step", integer(""), "the step"},
             {"variable", text(""), "the variable"},
             {"units", text(""), "its units"},
             {"range", number(""), "the global pair's persistence: max − min"},
             {"pairCount", integer(""), "pairs in all"},
             {"counts",
              named("PairCounts", "",
                    {{"minimum-saddle", integer(""), "pairs of a minimum and a saddle"},
                     {"saddle-maximum", integer(""), "pairs of a saddle and a maximum"},
                     {"global", integer(""), "the global pair"}}),
              "pairs of each kind"},
             {"pairs",
              arrayOf(named("PersistencePair", "",
                            {{"kind", oneOfTexts({"minimum-saddle", "saddle-maximum", "global"}, ""), "the pair's kind"},
                             {"birth", number(""), "value at the lower end"},
                             {"death", number(""), "value at the upper end"},
                             {"persistence", number(""), "death − birth"},
                             {"birthLat", number(""), "the lower end's latitude, °N"},
                             {"birthLon", number(""), "its longitude, °E"},
                             {"birthDepthKm", number(""), "its depth, km"},
                             {"lat", number(""), "the extremum's (the seed's) latitude, °N"},
                             {"lon", number(""), "its longitude, °E"},
                             {"depthKm", number(""), "its depth, km"}}),
                      ""),
              "the most persistent pairs, by decreasing persistence"},
             {"rest",
              named("PairRest", "",
                    {{"count", integer(""), "pairs not listed"},
                     {"maxPersistence", number(""), "the largest of their persistences"}}),
              "the pairs not listed"},
             {"stored",
              nullable(named("StoredSeeding", "",
                             {{"threshold", number(""), "persistence threshold, in the variable's units"},
                              {"rule", text(""), "the seeding rule"},
                              {"lines", integer(""), "lines seeded"},
                              {"seedPersistenceColumn", boolean(""), "whether the lines carry `seed persistence`"}})),
              "how the step's pathlines were seeded; null without pathlines or for another variable"}}));
        d.push_back(message(
            "Spectrum", "POST /api/spectrum",
            "the spherical-harmonic power per degree of a variable on one shell (docs/compare.md, \"Spectra\")",
            {{"variable", text(""), "the variable"},
             {"units", text(""), "its units (the power's are their square)"},
             {"step", integer(""), "the step"},
             {"depthKm", number(""), "the shell's depth, km (the grid's shell nearest the depth asked for)"},
             {"radiusKm", number(""), "its radius, km"},
             {"lmax", integer(""), "the largest degree"},
             {"quadrature", text(""), "the rows' quadrature: Fejér's first rule, Clenshaw–Curtis or area weights"},
             {"power", arrayOf(number(""), ""),
              "S_l for l = 0 … lmax: Σ_m c_lm² of the 4π-normalised real harmonics (Σ_l S_l is the mean square over "
              "the sphere)"}}));
        d.push_back(message(
            "PairCorrelation", "POST /api/correlate",
            "a pair's two datasets correlated shell by shell on the first's grid (docs/compare.md, \"Correlation\")",
            {{"variable", text(""), "the variable correlated (the state's colour variable, or `var`)"},
             {"units", text(""), "its units (the RMS amplitudes')"},
             {"steps", pairOf(integer(""), ""), "the first's step and the second's matched step"},
             {"lmax", nullable(integer("")), "both filtered to degrees ≤ lmax first; null: unfiltered"},
             {"shells",
              arrayOf(named("ShellCorrelationRow", "",
                            {{"depthKm", number(""), "the shell's depth, km"},
                             {"correlation", nullable(number("")), "area-weighted Pearson r; null where `note` says why"},
                             {"rmsA", nullable(number("")), "the first's RMS about the shell's mean"},
                             {"rmsB", nullable(number("")), "the second's"},
                             {"rmsRatio", nullable(number("")), "rmsA / rmsB"},
                             {"areaFraction", number(""), "the share of the sphere where both have data, 0..1"},
                             {"note", text(""), "why a value is missing; empty otherwise"}}),
                      ""),
              "one per radius of the first's grid, deepest first"}}));
        d.push_back(message(
            "MapHeader", "POST /api/slice?view=map (JSON header)", "where a map puts the sphere",
            sliceKeys("map",
                      {{"projection", namesOf<render::MapProjection>(state::allMapProjections(), state::mapProjectionName, ""),
                         "the map projection"},
                        {"centralMeridianDeg", number(""), "the projection's central meridian, °E"},
                        {"centralLatitudeDeg", number(""), "its central latitude, °N (0 but for `orthographic`)"},
                        {"scale", number(""), "d3-geo's `scale` of the projection"},
                        {"centre", pairOf(number(""), ""), "d3-geo's `translate` [x, y], pixels"},
                        {"depthKm", number(""), "the map's depth, km"}})));
        d.push_back(message(
            "SectionHeader", "POST /api/slice?view=section (JSON header)", "where a section puts the arc and the depths",
            sliceKeys("section",
                      {{"plot",
                         named("PlotBox", "",
                               {{"left", number(""), "pixels"},
                                {"right", number(""), "pixels"},
                                {"top", number(""), "pixels: depth 0"},
                                {"bottom", number(""), "pixels: depth `depthSpanKm`"}}),
                         "the plot's box"},
                        {"depthSpanKm", number(""), "depth at the plot's bottom, km"},
                        {"from", pairOf(number(""), ""), "the arc's start [lat, lon], degrees, at `left`"},
                        {"to", pairOf(number(""), ""), "its end [lat, lon], at `right`"},
                        {"azimuthDeg", number(""), "the arc's direction leaving `from`, clockwise from north, degrees"},
                        {"lengthDeg", number(""), "its length along the surface, degrees"},
                        {"lengthKm", number(""), "its length along the surface, km"}})));
        d.push_back(part("ProbeValue", "a value at the probed point",
                         {{"value", number(""), "the value"}, {"units", text(""), "its units"}}));
        d.push_back(message(
            "ProbeAnswer", "GET /api/probe", "the values at a point, as `raypc probe` prints them (analysis/probe.h)",
            {{"step", integer(""), "the step"},
             {"time_myr", number(""), "its time, Myr"},
             {"level", integer(""), "the level sampled"},
             {"point", mapOf(ref("ProbeValue"), ""), "the point's coordinates: lat, lon, radius, depth, x, y, z"},
             {"values",
              mapOf(named("ProbeVariable", "",
                          {{"value", number(""), "the trilinear value"},
                           {"units", text(""), "its units"},
                           {"quantisation_error_max", number(""), "the largest error of the stored encoding there"}}),
                    ""),
              "each variable asked for, by name"}}));
        d.push_back(message(
            "LinkedState", "GET /api/link", "the state the UI shows, for programs",
            {{"version", integer(""), "counts every change; 0 at start"},
             {"state", nullable(typed("object", "")), "the document as it was sent; null at start"},
             {"source", nullable(oneOfTexts({"ui", "api"}, "")), "who set it: a session's settled state or POST /api/link"},
             {"sessions", integer(""), "open WebSocket sessions"}}));
        d.push_back(message("LinkSet", "POST /api/link", "the linked state was set",
                            {{"version", integer(""), "the new version"},
                             {"sessions", integer(""), "the sessions it was sent to"}}));
        d.push_back(message("HttpError", "HTTP 4xx/5xx", "what went wrong",
                            {{"error", text(""), "a message naming the parameter or key"}}));

        // -- WebSocket, client → server ------------------------------------------------------
        const std::string toServer = "WebSocket client → server";
        d.push_back(message("ClientHello", toServer, "the first message",
                            {{"type", constant("hello", ""), "`hello`"},
                             {"protocol", integer(""), fmt::format("the client's protocol version ({})", kProtocolVersion)}}));
        d.push_back(message(
            "ClientState", toServer, "replace the session's whole state",
            {{"type", constant("state", ""), "`state`"},
             {"id", integer(""), "the client's counter, echoed in frames and errors (signed 64-bit)"},
             {"state", stateDocument(""), "the render state document"},
             {"interactive", boolean(""), "the user drags: one pass within `timeBudgetMs`", false},
             {"playback", boolean(""), "a step of playback (not with `interactive`)", false}}));
        d.push_back(message("ClientCancel", toServer, "stop the current work", {{"type", constant("cancel", ""), "`cancel`"}}));
        d.push_back(message("ClientPing", toServer, "answered by a pong",
                            {{"type", constant("ping", ""), "`ping`"}, {"id", integer(""), "echoed"}}));

        // -- WebSocket, server → client ------------------------------------------------------
        const std::string toClient = "WebSocket server → client";
        d.push_back(message("ServerHello", toClient, "the answer to hello",
                            {{"type", constant("hello", ""), "`hello`"},
                             {"protocol", integer(""), "the server's protocol version"},
                             {"session", text(""), "the session's name"}}));
        d.push_back(message("ServerError", toClient, "a message or state that was refused; the connection stays",
                            {{"type", constant("error", ""), "`error`"},
                             {"message", text(""), "what is wrong, naming the key"},
                             {"id", integer(""), "the state's or ping's id, when the error is about one", false}}));
        d.push_back(message("ServerPong", toClient, "the answer to a ping",
                            {{"type", constant("pong", ""), "`pong`"}, {"id", integer(""), "the ping's id"}}));
        d.push_back(message("ServerLink", toClient, "a program set the linked state (POST /api/link)",
                            {{"type", constant("link", ""), "`link`"},
                             {"version", integer(""), "the linked state's version"},
                             {"state", typed("object", ""), "the document, for the UI to check and apply"}}));
        d.push_back(part("ShellKeyEntry", "a reference shell drawn",
                         {{"label", text(""), "as the legend names it (e.g. `410 km`)"},
                          {"color", arrayOf(number(""), ""), "its colour, r, g, b in [0, 1]"}}));
        d.push_back(part("ShellLabel", "a reference shell's depth written on its ring",
                         {{"label", text(""), "the depth (e.g. `660 km`)"},
                          {"color", arrayOf(number(""), ""), "the shell's colour, r, g, b in [0, 1]"},
                          {"x", number(""), "where the label's centre goes, a fraction of the frame's width from its left"},
                          {"y", number(""), "the same, a fraction of its height from its top"}}));
        std::vector<Key> frameSelection = selectionKeys();
        d.push_back(message(
            "FrameHeader", "WebSocket server → client (binary frame's JSON header)", "one rendered pass",
            {{"type", constant("frame", ""), "`frame`"},
             {"id", integer(""), "the state's id"},
             {"step", integer(""), "the step rendered"},
             {"level", integer(""), "the level rendered"},
             {"pass", integer(""), "counts from 1; 0 for a preview"},
             {"passes", integer(""), "passes the state asks for"},
             {"converged", boolean(""), "the last pass of the state"},
             {"interactive", boolean(""), "an interactive state's one pass"},
             {"playback", boolean(""), "a step of playback"},
             {"preview", boolean(""), "a still state's quick pass before its first"},
             {"cached", boolean(""),
              "the frame was rendered ahead (or kept from an earlier still frame) of this state at this step and is "
              "sent from the session's frame cache: the state's level (else 0), full size, every pass"},
             {"ranks", integer(""), "MPI ranks that rendered the pass (1 alone)"},
             {"width", integer(""), "the JPEG's width, pixels"},
             {"height", integer(""), "its height, pixels"},
             {"camera", {{"type", "object"}, {"tsType", "CameraState"}}, "the state's camera, exactly as rendered"},
             {"jpegBytes", integer(""), "bytes of the JPEG after the header"},
             {"depthWidth", integer(""), "the depth map's width"},
             {"depthHeight", integer(""), "its height"},
             {"depthBytes", integer(""), "bytes of the float32 depth map after the JPEG"},
             {"stats",
              named("PassStats", "",
                    {{"passMs", number(""), "the pass's wall time, ms"},
                     {"samples", integer(""), "samples taken and skipped in empty bricks"},
                     {"samplesPerSecond", number(""), "samples / pass time"},
                     {"bricksSkipped", integer(""), "bricks skipped as empty"},
                     {"bricksTotal", integer(""), "bricks in all"}}),
              "what the pass cost"},
             {"selection", nullable(named("FrameSelection", "", frameSelection)),
              "the brushes' volume on the grid of one level; null on a new still state's first frame"},
             {"pathlines",
              named("FramePathlines", "",
                    {{"lines", integer(""), "lines of the window"},
                     {"visible", integer(""), "those the filters and brushes leave visible"}}),
              "with pathlines shown", false},
             {"shellKey", arrayOf(ref("ShellKeyEntry"), ""), "with reference shells drawn: each shell drawn", false},
             {"pair",
              named("FramePair", "",
                    {{"notes", arrayOf(text(""), ""),
                      "what this dataset's picture leaves out or changes of the state (a brush on a variable it "
                      "lacks, …; `render/pair_state.h`), one sentence each; empty when nothing"}}),
              "a session of a pair's second dataset (`/ws?dataset=1`): its `step` is the one matched to the "
              "state's (`pair.steps` of the state)",
              false},
             {"shellLabels", arrayOf(ref("ShellLabel"), ""),
              "a mono frame with reference shells whose rings are in view: each shell's depth label, for the UI to "
              "write over the frame (the frame itself carries none; stereo frames and pictures carry theirs)",
              false},
             {"surfaceOutline", arrayOf(pairOf(number(""), ""), ""),
              "a mono frame seen from outside the planet: the surface's silhouette as points [x, y], fractions of "
              "the frame's width and height from its top left, a closed line the UI draws over the frame",
              false},
             {"stereo",
              named("FrameStereo", "",
                    {{"mode", namesOf<render::StereoMode>(state::allStereoModes(), state::stereoModeName, "", render::StereoMode::Off), "the stereo mode"},
                     {"eyeSeparationKm", number(""), "km"},
                     {"convergenceKm", number(""), "the convergence in effect, km"},
                     {"eyeWidth", integer(""), "each eye's width as rendered"},
                     {"eyeHeight", integer(""), "each eye's height as rendered"},
                     {"pixelAspect", number(""), "the eyes' pixel aspect (2 for `side-by-side-half`)"}}),
              "a stereo frame", false}}));
        return d;
    }();
    return all;
}

// ---- The docs tables -------------------------------------------------------------------------

std::string typeText(const Json& s)
{
    if (s.contains("$ref")) {
        const std::string name = s["$ref"].get<std::string>().substr(std::string("#/definitions/").size());
        std::string anchor = name;
        std::transform(anchor.begin(), anchor.end(), anchor.begin(), [](unsigned char c) { return char(std::tolower(c)); });
        return fmt::format("[{}](#{})", name, anchor);
    }
    if (s.contains("anyOf"))
        return typeText(s["anyOf"][0]) + " or null";
    if (s.contains("const"))
        return fmt::format("`\"{}\"`", s["const"].get<std::string>());
    if (s.contains("enum")) {
        std::string out;
        for (const auto& v : s["enum"])
            out += (out.empty() ? "" : ", ") + (v.is_null() ? std::string("null") : fmt::format("`\"{}\"`", v.get<std::string>()));
        return out;
    }
    std::string type;
    const Json& t = s["type"];
    const bool orNull = t.is_array();
    type = orNull ? t[0].get<std::string>() : t.get<std::string>();
    if (type == "array") {
        type = "array of " + typeText(s["items"]);
        if (s.contains("minItems"))
            type = fmt::format("{} {}", s["minItems"].get<int>(), typeText(s["items"]) + "s");
    } else if (type == "object" && s.contains("tsType")) {
        type = s["tsType"].get<std::string>() == "RenderState" ? "state document" : "the state's `camera`";
    } else if (type == "object" && s.contains("additionalProperties") && s["additionalProperties"].is_object()) {
        type = "object of name → " + typeText(s["additionalProperties"]);
    }
    return orNull ? type + " or null" : type;
}

void tableRows(const Json& s, const std::string& path, std::string& out)
{
    const Json* object = &s;
    if (s.contains("anyOf"))
        object = &s["anyOf"][0];
    if (object->value("type", Json()) == "array" && (*object)["items"].value("type", Json()) == "object")
        object = &(*object)["items"];
    const Json type = object->value("type", Json());
    if (!(type == "object" || (type.is_array() && type[0] == "object")) || !object->contains("properties"))
        return;
    const Json& required = (*object)["required"];
    for (const auto& [name, property] : (*object)["properties"].items()) {
        const std::string key = path.empty() ? name : path + "." + name;
        const bool isRequired = std::find(required.begin(), required.end(), name) != required.end();
        std::string meaning = property.value("description", std::string());
        out += fmt::format("| `{}` | {}{} | {} |\n", key, typeText(property), isRequired ? "" : ", optional", meaning);
        const bool arrayOfObjects = property.value("type", Json()) == "array";
        tableRows(property, arrayOfObjects ? key + "[]" : key, out);
    }
}

}  // namespace

nlohmann::json protocolJsonSchema()
{
    nlohmann::json definitions = nlohmann::json::object();
    for (const Definition& d : messages())
        definitions[d.title] = nlohmann::json(d.schema);
    return {{"$schema", "http://json-schema.org/draft-07/schema#"},
            {"description",
             fmt::format("The RayPC server protocol's messages, version {} (docs/protocol.md). Generated by `raypc "
                         "protocol-schema` from src/server/protocol_schema.cpp; do not edit.",
                         kProtocolVersion)},
            {"definitions", std::move(definitions)}};
}

const std::vector<std::string>& messageKeys(std::string_view title)
{
    static const std::map<std::string, std::vector<std::string>, std::less<>> keys = [] {
        std::map<std::string, std::vector<std::string>, std::less<>> out;
        for (const Definition& d : messages())
            if (d.schema.contains("properties"))
                for (const auto& [key, value] : d.schema["properties"].items())
                    out[d.title].push_back(key);
        return out;
    }();
    const auto it = keys.find(title);
    if (it == keys.end())
        fail("protocol: no message '{}' in the description", title);
    return it->second;
}

std::string protocolMessageTables()
{
    std::string out;
    for (const Definition& d : messages()) {
        out += fmt::format("\n#### {}\n\n", d.title);
        out += fmt::format("{}{}.\n\n", d.carrier.empty() ? "A part of messages: " : "`" + d.carrier + "`: ",
                           d.schema["description"].get<std::string>());
        if (d.schema["type"] == "array") {
            out += fmt::format("An array of {}.\n", typeText(d.schema["items"]));
            continue;
        }
        out += "| key | type | meaning |\n|---|---|---|\n";
        tableRows(d.schema, "", out);
    }
    return out;
}

}  // namespace raypc::server
