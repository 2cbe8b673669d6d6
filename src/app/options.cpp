#include "app/options.h"

#include "core/error.h"
#include "core/error_kinds.h"
#include "core/mpi.h"
#include "state/render_state.h"
#include "core/spherical.h"
#include "core/strings.h"
#include "dataset/value_encoding.h"
#include "grid/coordinates.h"
#include "grid/variable_names.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <charconv>
#include <cmath>

namespace raypc::app {

void requireFiniteNumbers(CLI::App& app)
{
    static const CLI::Validator finite(
        [](std::string& text) -> std::string {
            char* end = nullptr;
            const double v = std::strtod(text.c_str(), &end);
            if (end != text.c_str() && *end == '\0' && !std::isfinite(v))
                return text + " is not a finite number";
            return {};
        },
        "FINITE");
    for (CLI::Option* option : app.get_options())
        if (option->get_type_name() == "FLOAT")
            option->check(finite);
    for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; }))
        requireFiniteNumbers(*sub);
}

void ReaderFlags::add(CLI::App& app)
{
    app.add_option("--map", variableMap,
                   "Read the input's variable FILE_NAME as NAME (NAME=FILE_NAME, repeatable), e.g. --map "
                   "temperature=T or --map 'shear velocity=vs'");
    app.add_option("--lat-name", latName, "Name of the latitude coordinate variable (default: found)");
    app.add_option("--r-name", rName, "Name of the radius coordinate variable (default: found)");
    app.add_option("--lon-name", lonName, "Name of the longitude coordinate variable (default: found)");
    app.add_option("--radius-units", radiusUnits,
                   "What the radius (or depth) coordinate's numbers are, whatever its units attribute says: km, m, "
                   "or nondimensional (fractions of 6371 km). Default: its units attribute; without one, km if the "
                   "radii lie within 3000..7000 km")
        ->check(CLI::IsMember({"km", "m", "nondimensional"}));
    app.add_option("--velocity", velocity,
                   "The velocity's three variables in the input when they are not vx, vy, vz: x,y,z or, with "
                   "--velocity-frame spherical, radial,north,east, or with --velocity-frame colatitude (CitcomS' "
                   "order) colatitude,longitude,radial (m/s, cm/yr, mm/yr or m/yr)")
        ->delimiter(',')
        ->expected(3);
    app.add_option("--velocity-frame", velocityFrame,
                   "What --velocity's (or vx, vy, vz's) components are: cartesian (x, y, z), spherical (radial, "
                   "north, east) or colatitude (CitcomS' order: colatitude, i.e. southward; longitude, eastward; "
                   "radial)")
        ->check(CLI::IsMember({"cartesian", "spherical", "colatitude"}))
        ->capture_default_str();
    app.add_flag("--fill-missing", fillMissing,
                 "Replace missing values (_FillValue, missing_value, NaN) by their shell's mean instead of failing");
    app.add_option("--time-units", timeUnits,
                   "Unit of the times in a .pvd collection (ASPECT's output): years (ASPECT's default), seconds or Myr")
        ->capture_default_str();
    app.add_option("--grid", grid,
                   "Grid LATxRxLON that an ASPECT (VTK XML) mesh or CitcomS' caps are resampled onto, e.g. "
                   "180x201x360 (default: as fine as the mesh's finest cell, within memory)");
    app.add_option("--temperature-scale", temperatureScaleK,
                   "CitcomS output: the temperature difference, K, its nondimensional temperatures are multiplied "
                   "by (default: kept as written, 0..1)");
    app.add_option("--planet-radius", planetRadiusKm,
                   "CitcomS output: the radius, km, of its radius 1 (default: the run's radius_km, else 6371)");
    app.add_option("--diffusivity", diffusivityM2s,
                   "CitcomS output: the thermal diffusivity, m^2/s, that scales its velocities (kappa/R) and times "
                   "(R^2/kappa) (default: the run's thermdiff, else 1e-6)");
}

io::ReaderOptions ReaderFlags::toOptions() const
{
    io::ReaderOptions o;
    for (const auto& m : variableMap) {
        const auto eq = m.find('=');
        if (eq == std::string::npos || eq == 0 || eq + 1 == m.size())
            fail("--map: '{}' is not NAME=FILE_NAME", m);
        const auto name = m.substr(0, eq), fileName = m.substr(eq + 1);
        // Any name but a coordinate's (brushes and axes name both) and the velocity's derived
        // quantities (computed, never read).
        if (grid::findCoordinate(name))
            fail("--map: '{}' is a coordinate's name; a variable needs another", name);
        if (name == varname::kRadialVelocity || name == varname::kVelocityMagnitude)
            fail("--map: '{}' is derived from the velocity; name the velocity with --velocity", name);
        if (o.variableNames.contains(name))
            fail("--map: '{}' is given twice", name);
        for (const auto& [other, inFile] : o.variableNames)
            if (inFile == fileName)
                fail("--map: '{}' is read as both '{}' and '{}'", fileName, other, name);
        o.variableNames[name] = fileName;
    }
    if (!velocity.empty()) {
        if (velocity.size() != 3 || std::any_of(velocity.begin(), velocity.end(), [](const auto& v) { return v.empty(); }))
            fail("--velocity: '{}', expected three variable names A,B,C", fmt::join(velocity, ","));
        for (int c = 0; c < 3; ++c)
            o.variableNames[std::string("v") + "xyz"[c]] = velocity[size_t(c)];
    }
    using VelocityFrame = io::ReaderOptions::VelocityFrame;
    o.velocityFrame = velocityFrame == "spherical"    ? VelocityFrame::Spherical
                      : velocityFrame == "colatitude" ? VelocityFrame::Colatitude
                                                      : VelocityFrame::Cartesian;
    o.latName = latName;
    o.rName = rName;
    o.lonName = lonName;
    using RadiusUnits = io::ReaderOptions::RadiusUnits;
    o.radiusUnits = radiusUnits == "km"               ? RadiusUnits::Km
                    : radiusUnits == "m"              ? RadiusUnits::M
                    : radiusUnits == "nondimensional" ? RadiusUnits::Nondimensional
                                                      : RadiusUnits::FromFile;
    o.fillMissing = fillMissing;
    for (const auto& [value, option] : {std::pair{temperatureScaleK, "--temperature-scale"},
                                        {planetRadiusKm, "--planet-radius"}, {diffusivityM2s, "--diffusivity"}})
        if (value < 0)
            fail("{}: {} is negative", option, value);
    o.temperatureScaleK = temperatureScaleK;
    if (planetRadiusKm > 0)
        o.planetRadiusKm = planetRadiusKm;
    if (diffusivityM2s > 0)
        o.diffusivityM2s = diffusivityM2s;
    if (timeUnits == "years")
        o.myrPerTimeUnit = 1e-6;
    else if (timeUnits == "seconds")
        o.myrPerTimeUnit = 1 / kSecondsPerMyr;
    else if (timeUnits == "Myr" || timeUnits == "myr")
        o.myrPerTimeUnit = 1;
    else
        fail("--time-units '{}': expected years, seconds or Myr", timeUnits);
    if (!grid.empty()) {
        const auto parts = split(grid, 'x');
        std::array<size_t, 3> n{};
        bool ok = parts.size() == 3;
        for (size_t i = 0; ok && i < 3; ++i) {
            const auto [end, ec] = std::from_chars(parts[i].data(), parts[i].data() + parts[i].size(), n[i]);
            ok = ec == std::errc() && end == parts[i].data() + parts[i].size() && n[i] >= (i == 2 ? 4u : 2u) &&
                 n[i] <= 100000;
        }
        if (!ok)
            fail("--grid '{}': expected LATxRxLON, at least 2x2x4, e.g. 180x201x360", grid);
        o.resampleSize = n;
    }
    return o;
}

int parseStep(const dataset::Dataset& dataset, const std::string& text, const std::string& option)
{
    const std::string t = trim(text);
    if (t.size() > 3 && (t.ends_with("Myr") || t.ends_with("myr"))) {
        const std::string number = trim(t.substr(0, t.size() - 3));
        double myr = 0;
        const auto [end, ec] = std::from_chars(number.data(), number.data() + number.size(), myr);
        if (ec != std::errc() || end != number.data() + number.size() || !std::isfinite(myr))
            fail("{}: '{}' is not a time like 24Myr", option, text);
        for (const auto& s : dataset.steps())
            if (std::abs(s.timeMyr - myr) <= 1e-6 * std::max(1.0, std::abs(myr)))
                return s.index;
        failOutOfRange("{}: no step at {} Myr; steps are {} Myr apart from {} to {} Myr", option, myr, dataset.dtMyr(),
             dataset.steps().front().timeMyr, dataset.steps().back().timeMyr);
    }
    int step = -1;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), step);
    if (ec != std::errc() || end != t.data() + t.size())
        fail("{}: '{}' is neither a step index nor a time like 24Myr", option, text);
    dataset.checkStep(step, option);
    return step;
}

analysis::NamedRange parseRangeOption(const std::string& text, const std::string& option)
{
    const size_t eq = text.rfind('=');
    const size_t colon = eq == std::string::npos ? std::string::npos : text.find(':', eq + 1);
    if (eq == std::string::npos || eq == 0 || colon == std::string::npos)
        fail("{} '{}': expected NAME=MIN:MAX", option, text);
    analysis::NamedRange r;
    r.name = trim(text.substr(0, eq));
    const std::string lo = trim(text.substr(eq + 1, colon - eq - 1)), hi = trim(text.substr(colon + 1));
    auto number = [&](const std::string& s) {
        float v = 0;
        const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (s.empty() || ec != std::errc() || end != s.data() + s.size())
            fail("{} '{}': MIN and MAX must be numbers", option, text);
        if (!std::isfinite(v))
            fail("{} '{}': MIN and MAX must be finite numbers (for an open end, give the range's end)", option, text);
        return v;
    };
    r.min = number(lo);
    r.max = number(hi);
    if (!(r.min <= r.max))
        fail("{} '{}': min {} is greater than max {}", option, text, r.min, r.max);
    return r;
}

void applyRangeOptions(std::vector<analysis::NamedRange>& ranges, const std::vector<std::string>& options,
                       const std::string& option)
{
    std::vector<analysis::NamedRange> given;
    for (const std::string& text : options)
        given.push_back(parseRangeOption(text, option));
    std::erase_if(ranges, [&](const analysis::NamedRange& r) {
        return std::any_of(given.begin(), given.end(), [&](const analysis::NamedRange& g) { return g.name == r.name; });
    });
    ranges.insert(ranges.end(), given.begin(), given.end());
}

std::pair<int, int> parseStepRange(const dataset::Dataset& dataset, const std::string& text, const std::string& option)
{
    const size_t colon = text.find(':');
    if (colon == std::string::npos) {
        const int step = parseStep(dataset, text, option);
        return {step, step};
    }
    const int first = parseStep(dataset, text.substr(0, colon), option);
    const int last = parseStep(dataset, text.substr(colon + 1), option);
    if (first > last)
        fail("{} '{}': the first step {} is after the last {}", option, text, first, last);
    return {first, last};
}

void PreprocessFlags::add(CLI::App& cmd, bool withQuiet)
{
    cmd.add_option("--dt-myr", options.dtMyr, "Time between steps in Myr")->capture_default_str();
    // As text: CLI11 reads "-1" into an unsigned count as 2^64 - 1.
    cmd.add_option_function<std::string>(
           "--sample-rows",
           [this](const std::string& text) {
               unsigned long long rows = 0;
               const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), rows);
               if (text.empty() || ec != std::errc() || end != text.data() + text.size() || rows == 0 ||
                   rows > preprocess::kMaxSampleRows)
                   fail("--sample-rows: '{}', expected a whole number of rows from 1 to {}", text, preprocess::kMaxSampleRows);
               options.sampleRows = size_t(rows);
           },
           fmt::format("Cells in the parallel-coordinates sample (1 to {})", preprocess::kMaxSampleRows))
        ->default_str(std::to_string(options.sampleRows));
    cmd.add_option("--seed", options.seed, "Seed of the sample")->capture_default_str();
    if (withQuiet)
        cmd.add_flag("-q,--quiet", options.quiet, "No progress output");
    cmd.add_option_function<std::string>(
           "--encoding", [this](const std::string& text) { options.encoding = dataset::parseEncoding(text, "--encoding"); },
           "Level arrays: 'u16' (quantised per brick, error <= brick range / 131070; half the size) or 'float32' "
           "(exact)")
        ->default_str(std::string(dataset::encodingName(options.encoding)));
    cmd.add_flag("!--no-read-ahead", options.readAhead,
                 "Read one step at a time: a step less in memory (about 0.5 GB at the contest's full resolution), "
                 "the next step no longer read while this one is worked on (slower)");
    auto& pl = options.pathlines;
    cmd.add_flag("--no-pathlines", noPathlines,
                 "Skip the critical points of --pathline-field and the pathlines seeded there");
    cmd.add_option("--pathline-field", pl.field, "Variable whose critical points seed pathlines")
        ->capture_default_str();
    cmd.add_option("--pathline-steps", pl.steps, "Steps each pathline is traced forward")->capture_default_str();
    cmd.add_option_function<std::string>(
           "--cp-select", [this](const std::string& text) { options.pathlines.filter.rule = analysis::parseSeedRule(text); },
           "Seeds: 'persistence' (extrema of persistent pairs) or 'value' (the largest |value|)")
        ->default_str(analysis::seedRuleName(pl.filter.rule));
    cmd.add_option_function<std::string>(
           "--cp-persistence",
           [this](const std::string& text) { analysis::parsePersistenceThreshold(text, options.pathlines.filter); },
           "Seeds by persistence: extrema whose persistence exceeds K (field units) or P% of the step's range")
        ->default_str("5%");
    cmd.add_option("--cp-min-abs", pl.filter.minAbsValue,
                   "Seeds by value: keep maxima >= V, minima <= -V, saddles |value| >= V (field units)")
        ->capture_default_str();
    cmd.add_option("--cp-min-fraction", pl.filter.minFractionOfMaxAbs,
                   "Seeds by value: the threshold is at least this fraction of the step's largest |value|")
        ->capture_default_str();
    cmd.add_option("--cp-max-count", pl.filter.maxCount,
                   "Seeds: at most this many per step (the most persistent, or the largest |value|, first)")
        ->capture_default_str();
    cmd.add_flag("--cp-saddles,!--cp-no-saddles", pl.filter.saddles,
                 "Seeds: also at saddles (by persistence: those paired with the kept extrema); "
                 "default: extrema only");
    reader.add(cmd);
}

preprocess::PreprocessOptions PreprocessFlags::toOptions(const CLI::App& cmd) const
{
    // An option of the other seed rule would be silently ignored.
    const bool byValue = options.pathlines.filter.rule == analysis::SeedRule::Value;
    for (const char* option : {"--cp-persistence", "--cp-min-abs", "--cp-min-fraction"})
        if (cmd.count(option) && byValue == (option == std::string("--cp-persistence")))
            fail("{}: applies to seeds chosen by {}, but --cp-select is {}", option, byValue ? "persistence" : "value",
                 analysis::seedRuleName(options.pathlines.filter.rule));
    preprocess::PreprocessOptions o = options;
    o.reader = reader.toOptions();
    o.pathlines.enabled = !noPathlines;
    return o;
}

void SeriesSelectionFlags::add(CLI::App& cmd)
{
    cmd.add_option("dataset", dataset, "Dataset directory")->required();
    cmd.add_option("--state", statePath, "STATE.json whose brushes define the selection");
    cmd.add_option("--range", ranges, "Brush NAME=MIN:MAX on a variable or coordinate; repeatable, overrides the state");
    cmd.add_option("-t,--time", time, "Steps A or A:B (index or time like 24Myr); default all");
    cmd.add_option("--lod", level, "Level of detail (0 = full resolution, exact)")->capture_default_str();
}

std::pair<int, int> parseSize(const std::string& text)
{
    const auto parts = split(text, 'x');
    try {
        if (parts.size() == 2) {
            size_t a = 0, b = 0;
            const int w = std::stoi(parts[0], &a), h = std::stoi(parts[1], &b);
            if (a == parts[0].size() && b == parts[1].size() && w >= 1 && h >= 1 && w <= 16384 && h <= 16384)
                return {w, h};
        }
    } catch (const std::exception&) {
    }
    fail("--size '{}': expected WIDTHxHEIGHT with 1..16384 pixels per side, e.g. 1024x768", text);
}

SeriesSelection resolveSeriesSelection(const SeriesSelectionFlags& flags)
{
    SeriesSelection s;
    s.dataset = dataset::Dataset::open(flags.dataset);
    // A regional model's statistics are of its region (its points outside have no volume): said once.
    if (const grid::SphericalGrid& g = s.dataset->levels().front().grid; g.regional() && mpi::isRoot())
        spdlog::info("{}: a regional model: volumes and percentages are of its region ({} to {} deg north, {} to {} "
                     "deg east), not the whole mantle",
                     flags.dataset, g.dataLatDeg ? (*g.dataLatDeg)[0] : -90.0, g.dataLatDeg ? (*g.dataLatDeg)[1] : 90.0,
                     g.dataLonDeg ? (*g.dataLonDeg)[0] : 0.0, g.dataLonDeg ? (*g.dataLonDeg)[1] : 360.0);
    std::vector<analysis::NamedRange> ranges;
    if (!flags.statePath.empty())
        ranges = state::loadRenderState(flags.statePath).brushes;
    applyRangeOptions(ranges, flags.ranges);
    s.filters = analysis::resolveRangeFilters(*s.dataset, ranges, flags.statePath.empty() ? "--range" : "brushes");
    s.dataset->checkLevel(flags.level, flags.levelFrom);
    std::tie(s.first, s.last) = flags.time.empty()
                                    ? std::pair<int, int>(0, static_cast<int>(s.dataset->steps().size()) - 1)
                                    : parseStepRange(*s.dataset, flags.time);
    return s;
}

}  // namespace raypc::app
