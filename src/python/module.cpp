// The compiled half of Python's `raypc` package (raypc/_raypc): thin bindings of what the `raypc`
// executable calls, so that Python runs the same code — the dataset pipeline (app/series_inputs),
// the state's one description (state/render_state), the one path from a state to pixels
// (render/state_renderer), exact statistics (analysis/selection), probing (analysis/probe) and the server
// (server/server). The Pythonic layer (xarray, pandas, the notebook view) is the raypc package's modules.
//
// Errors: raypc::Error becomes raypc.Error (a ValueError) with the CLI's one-line message, its kinds
// (core/error_kinds.h) the subclasses that are also Python's builtin exceptions: NotFoundError
// (FileNotFoundError), UnknownNameError (KeyError), OutOfRangeError (IndexError). Messages name
// Python's arguments (step, level, lat, variable …), not the CLI's flags. Long work (preprocessing,
// rendering, statistics, reading a field) releases the GIL and runs on every core as the executable
// does; progress callbacks take the GIL only while they run, and a KeyboardInterrupt seen there
// cancels the work between steps.
#include "app/cli.h"
#include "app/compare_fields.h"
#include "app/feature_table.h"
#include "app/options.h"
#include "analysis/probe.h"
#include "app/series_inputs.h"
#include "app/slice_grid.h"
#include "core/error.h"
#include "core/error_kinds.h"
#include "core/install_paths.h"
#include "core/spherical.h"
#include "io/cf_grid.h"
#include "analysis/critical_points.h"
#include "dataset/dataset.h"
#include "preprocess/difference.h"
#include "analysis/feature_run.h"
#include "analysis/features.h"
#include "analysis/pathline_storage.h"
#include "analysis/selection.h"
#include "state/render_state.h"
#include "render/state_renderer.h"
#include "server/api_views.h"
#include "server/server.h"
#include "server/step_cache.h"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <cstring>
#include <optional>
#include <thread>

namespace py = pybind11;

namespace raypc::python {
namespace {

using Json = nlohmann::json;

// src/grid/names.json, the table the C++ constants were generated from, compiled in: the package
// names what this build writes whether it runs from the build tree or installed.
constexpr const char* kNamesJson =
#include "grid/names_json.inc"
    ;

// A NumPy array that owns a copy of `values` in the given shape.
template <typename T>
py::array_t<T> arrayOf(const std::vector<T>& values, std::vector<py::ssize_t> shape)
{
    py::array_t<T> out(shape);
    std::memcpy(out.mutable_data(), values.data(), values.size() * sizeof(T));
    return out;
}

// Grid values read from step files by Dataset.field and Dataset.read_box since the module was loaded:
// what the tests of the lazy xarray arrays count (tests/python/test_xarray.py). A whole variable read
// at once counts every grid point of its level. Relaxed: a statistic, it orders nothing.
std::atomic<uint64_t> g_valuesRead{0};

// The values of variable `var` of `volume` in the box [begin[a], end[a]) of each axis (lat, r, lon)
// into `out` (the box's shape, C order): StepVolume::valuesInBox, which decodes only what the box
// needs (a shell anomaly: its base on the box's whole shells), unless that is most of the step (then
// the whole variable, in parallel). Counts what it read (g_valuesRead).
void readBox(const dataset::StepVolume& volume, size_t var, const std::array<size_t, 3>& begin,
             const std::array<size_t, 3>& end, float* out)
{
    const grid::SphericalGrid& g = volume.grid();
    const size_t nLat = end[0] - begin[0], nR = end[1] - begin[1], nLon = end[2] - begin[2];
    const bool shells = volume.computedFrom(var) && !volume.valuesReady(var);
    const size_t needed = shells ? g.nLat() * nR * g.nLon() : nLat * nR * nLon;
    if (needed * 4 >= g.cellCount()) {
        const float* all = volume.values(var);
        for (size_t iLat = begin[0]; iLat < end[0]; ++iLat)
            for (size_t iR = begin[1]; iR < end[1]; ++iR)
                std::memcpy(out + ((iLat - begin[0]) * nR + (iR - begin[1])) * nLon, all + g.index(iLat, iR, begin[2]),
                            nLon * sizeof(float));
        g_valuesRead.fetch_add(g.cellCount(), std::memory_order_relaxed);
        return;
    }
    g_valuesRead.fetch_add(needed, std::memory_order_relaxed);
    volume.valuesInBox(var, begin, end, out);
}

py::array_t<double> doubles(const std::vector<double>& values)
{
    return arrayOf(values, {py::ssize_t(values.size())});
}

// The state document (docs/state.md) as the one description parses it: a malformed one throws
// raypc::Error with the schema's message.
state::RenderState parseState(const std::string& text, const std::string& what)
{
    Json document = Json::parse(text, nullptr, false);
    if (document.is_discarded())
        fail("{}: not valid JSON", what);
    return state::parseRenderState(document, what);
}

// The CLI's flags in a message ("--time-units: ...") as the keywords Python passes them with
// (time_units): for calls whose keyword arguments become the CLI's flags (raypc.open's options,
// raypc.show's host) and whose messages therefore come from the CLI's option parsing.
std::string pythonArgumentNames(const std::string& message)
{
    auto isLower = [](char c) { return std::islower(static_cast<unsigned char>(c)) != 0; };
    auto isFlagChar = [&](char c) { return isLower(c) || std::isdigit(static_cast<unsigned char>(c)) != 0 || c == '-'; };
    std::string out;
    for (size_t i = 0; i < message.size();) {
        const bool startsFlag = message.compare(i, 2, "--") == 0 && i + 2 < message.size() && isLower(message[i + 2]) &&
                                (i == 0 || !(std::isalnum(static_cast<unsigned char>(message[i - 1])) ||
                                             message[i - 1] == '-' || message[i - 1] == '_'));
        if (!startsFlag) {
            out += message[i++];
            continue;
        }
        for (i += 2; i < message.size() && isFlagChar(message[i]); ++i)
            out += message[i] == '-' ? '_' : message[i];
    }
    return out;
}

// Runs `work`; an error it throws is thrown again, of the same kind, with its flags named as Python's
// keywords (pythonArgumentNames).
template <typename Work>
auto withPythonArgumentNames(Work&& work)
{
    try {
        return work();
    } catch (const Error& e) {
        failLike(e, pythonArgumentNames(e.what()));
    }
}

// Calls `callback(done, total)` with the GIL; a KeyboardInterrupt (or any Python exception) there
// sets `cancel` and is kept for the caller to raise once the C++ work has stopped.
class ProgressBridge {
public:
    explicit ProgressBridge(py::object callback) : m_callback(std::move(callback)) {}
    void operator()(const std::string& phase, int done, int total)
    {
        py::gil_scoped_acquire gil;
        if (m_error || m_callback.is_none())
            return;
        try {
            if (PyErr_CheckSignals() != 0)
                throw py::error_already_set();
            m_callback(phase, done, total);
        } catch (py::error_already_set& e) {
            m_error = std::make_unique<py::error_already_set>(std::move(e));
            cancel = true;
        }
    }
    // After the work: raises what the callback raised, if anything.
    void rethrow()
    {
        if (m_error) {
            py::gil_scoped_acquire gil;
            auto error = std::move(m_error);
            throw std::move(*error);
        }
    }
    ~ProgressBridge()
    {
        py::gil_scoped_acquire gil;
        m_error.reset();
        m_callback = py::none();
    }
    std::atomic<bool> cancel{false};

private:
    py::object m_callback;
    std::unique_ptr<py::error_already_set> m_error;
};

// `raypc.open` of files: the arguments of `raypc serve`/`render` (INPUT… --dataset and the
// preprocessing options, parsed by the same option group), preprocessed where not done yet.
// Returns the dataset directory.
std::string prepare(std::vector<std::string> args, py::object progress)
{
    CLI::App app("raypc.open", "raypc.open");
    app::SeriesFlags flags;
    flags.add(app, "preprocessed first, reused later");
    app::requireFiniteNumbers(app);
    std::reverse(args.begin(), args.end());  // CLI11 takes them last first
    try {
        app.parse(args);
    } catch (const CLI::ParseError& e) {
        fail("{}", pythonArgumentNames(e.what()));
    }
    auto [inputs, options] = withPythonArgumentNames([&] { return flags.resolve(); });
    if (!inputs.fromFiles())
        return inputs.dataset.string();
    ProgressBridge bridge(std::move(progress));
    options.quiet = true;
    options.onProgress = [&bridge](const preprocess::PreprocessProgress& p) { bridge(p.phase, p.done, p.total); };
    options.cancel = &bridge.cancel;
    {
        py::gil_scoped_release release;
        try {
            app::prepareSeries(inputs, options);
        } catch (const Error& e) {
            if (!bridge.cancel)
                failLike(e, pythonArgumentNames(e.what()));
        }
    }
    bridge.rethrow();
    return inputs.dataset.string();
}

// Python's raypc.correlate, raypc.spectrum and raypc.degree_correlation (raypc/compare.py): the code of
// `raypc correlate` and `raypc spectrum` (app/compare_fields.h), their numbers as arrays. `input`: a
// dataset directory or what `raypc serve` takes; `variable` '' for the default; `step` an index or a
// time like "24Myr".
app::ComparedField comparedField(const std::string& input, const std::string& variable, const std::string& step,
                                 const std::string& what, const std::string& stepArgument)
{
    return app::openComparedField(app::FieldSpec{input, variable}, step, what, stepArgument, true);
}

py::dict fieldDict(const app::ComparedField& f)
{
    return py::dict(py::arg("title") = f.title(), py::arg("variable") = f.info().name, py::arg("units") = f.info().units,
                    py::arg("dataset") = f.dataset->dir().string(), py::arg("step") = f.step,
                    py::arg("time_myr") = f.dataset->steps()[size_t(f.step)].timeMyr);
}

py::dict correlate(const std::string& a, const std::string& varA, const std::string& stepA, const std::string& b,
                   const std::string& varB, const std::string& stepB, int lmax)
{
    std::optional<app::ComparedField> fa, fb;
    std::vector<analysis::ShellCorrelation> rows;
    analysis::CorrelationOptions options;
    if (lmax >= 0)
        options.lmax = lmax;
    {
        py::gil_scoped_release release;
        fa = comparedField(a, varA, stepA, "a", "step");
        fb = comparedField(b, varB, stepB, "b", "step_b");
        rows = app::correlateFields(*fa, *fb, options);
    }
    // Depth increasing, as the CLI's CSV.
    std::reverse(rows.begin(), rows.end());
    std::vector<double> depth, radius, r, rmsA, rmsB, ratio, area;
    std::vector<int64_t> points;
    py::list notes;
    for (const analysis::ShellCorrelation& row : rows) {
        depth.push_back(row.depthKm), radius.push_back(row.radiusKm), r.push_back(row.correlation);
        rmsA.push_back(row.rmsA), rmsB.push_back(row.rmsB), ratio.push_back(row.rmsRatio);
        points.push_back(int64_t(row.points)), area.push_back(100.0 * row.areaFraction);
        notes.append(row.note);
    }
    return py::dict(py::arg("depth_km") = doubles(depth), py::arg("radius_km") = doubles(radius),
                    py::arg("correlation") = doubles(r), py::arg("rms_a") = doubles(rmsA), py::arg("rms_b") = doubles(rmsB),
                    py::arg("rms_ratio") = doubles(ratio), py::arg("points") = arrayOf(points, {py::ssize_t(points.size())}),
                    py::arg("area_covered_percent") = doubles(area), py::arg("note") = notes, py::arg("a") = fieldDict(*fa),
                    py::arg("b") = fieldDict(*fb), py::arg("regridded") = !fb->volume->grid().sameAs(fa->volume->grid()));
}

py::dict spectrum(const std::string& input, const std::string& variable, const std::string& step, int lmax)
{
    std::optional<app::ComparedField> f;
    analysis::ShellSpectra s;
    {
        py::gil_scoped_release release;
        f = comparedField(input, variable, step, "ds", "step");
        s = app::fieldSpectra(*f, lmax);
    }
    // Depth increasing (radii descending), as the CLI's CSV.
    const size_t nR = s.radiiKm.size(), nL = size_t(s.lmax) + 1;
    std::vector<double> depth, radius, power;
    for (size_t iR = nR; iR-- > 0;) {
        depth.push_back(kSurfaceRadiusKm - s.radiiKm[iR]);
        radius.push_back(s.radiiKm[iR]);
        power.insert(power.end(), s.power.begin() + ptrdiff_t(iR * nL), s.power.begin() + ptrdiff_t((iR + 1) * nL));
    }
    return py::dict(py::arg("depth_km") = doubles(depth), py::arg("radius_km") = doubles(radius), py::arg("lmax") = s.lmax,
                    py::arg("power") = arrayOf(power, {py::ssize_t(nR), py::ssize_t(nL)}),
                    py::arg("quadrature") = analysis::quadratureName(s.quadrature), py::arg("field") = fieldDict(*f));
}

py::dict degreeCorrelation(const std::string& a, const std::string& varA, const std::string& stepA, const std::string& b,
                           const std::string& varB, const std::string& stepB, double depthKm, int lmax)
{
    std::optional<app::ComparedField> fa, fb;
    analysis::DegreeCorrelation c;
    {
        py::gil_scoped_release release;
        fa = comparedField(a, varA, stepA, "a", "step");
        fb = comparedField(b, varB, stepB, "b", "step_b");
        c = app::fieldDegreeCorrelation(*fa, *fb, depthKm, lmax);
    }
    return py::dict(py::arg("depth_km") = c.depthKm, py::arg("radius_km") = c.radiusKm, py::arg("lmax") = c.lmax,
                    py::arg("power_a") = doubles(c.powerA), py::arg("power_b") = doubles(c.powerB),
                    py::arg("correlation") = doubles(c.correlation), py::arg("a") = fieldDict(*fa), py::arg("b") = fieldDict(*fb));
}

// `raypc.diff`: raypc diff's difference dataset written to `out` by the same code
// (preprocess/difference.h); `b` empty with `steps` k > 0 for step differences. Messages name
// Python's arguments (steps, match).
void difference(const std::string& a, const std::string& b, const std::string& out,
                const std::vector<std::string>& variables, int steps, const std::string& match, py::object progress)
{
    preprocess::DifferenceRequest request;
    request.a = a;
    request.b = b;
    request.variables = variables;
    request.stepLag = steps;
    request.match = preprocess::parseStepMatch(match, "match");
    if (steps < 0 || (b.empty() && steps == 0))
        fail("steps: {}, expected a step lag k >= 1 (or a dataset b to subtract)", steps);
    ProgressBridge bridge(std::move(progress));
    preprocess::PreprocessOptions options;
    options.quiet = true;
    options.onProgress = [&bridge](const preprocess::PreprocessProgress& p) { bridge(p.phase, p.done, p.total); };
    options.cancel = &bridge.cancel;
    {
        py::gil_scoped_release release;
        try {
            preprocess::preprocessDifference(request, out, options);
        } catch (const Error& e) {
            if (!bridge.cancel)
                failLike(e, pythonArgumentNames(e.what()));
        }
    }
    bridge.rethrow();
}

class PyDataset {
public:
    explicit PyDataset(const std::string& dir) : m_dataset(dataset::Dataset::open(dir)) {}

    const dataset::Dataset& dataset() const { return *m_dataset; }

    py::list variables() const
    {
        py::list out;
        for (const dataset::VariableInfo& v : m_dataset->variables())
            out.append(py::dict(py::arg("name") = v.name, py::arg("units") = v.units, py::arg("derived") = v.derived,
                                py::arg("min") = v.global.range.min, py::arg("max") = v.global.range.max));
        return out;
    }
    py::array_t<double> timesMyr() const
    {
        std::vector<double> t;
        for (const dataset::StepInfo& s : m_dataset->steps())
            t.push_back(s.timeMyr);
        return doubles(t);
    }
    py::list levels() const
    {
        py::list out;
        for (const dataset::LevelInfo& level : m_dataset->levels())
            out.append(py::dict(py::arg("lat") = doubles(level.grid.latDeg), py::arg("r") = doubles(level.grid.rKm),
                                py::arg("lon") = doubles(level.grid.lonDeg)));
        return out;
    }
    std::string encoding() const { return m_dataset->encoding() == dataset::ValueEncoding::Float32 ? "float32" : "u16"; }
    std::string dir() const { return m_dataset->dir().string(); }

    // Step "12" or "24Myr" as the CLI's --time takes it; messages name the argument `what`.
    int step(const std::string& text, const std::string& what) const { return app::parseStep(*m_dataset, text, what); }

    // One variable of one step at one level, (lat, r, lon), float32, a copy.
    py::array_t<float> field(const std::string& name, int step, int level) const
    {
        const int var = variableIndex(name);
        m_dataset->checkStep(step, "step");
        m_dataset->checkLevel(level, "level");
        const grid::SphericalGrid& grid = m_dataset->levels()[size_t(level)].grid;
        py::array_t<float> out({py::ssize_t(grid.nLat()), py::ssize_t(grid.nR()), py::ssize_t(grid.nLon())});
        float* dst = out.mutable_data();
        {
            py::gil_scoped_release release;
            const auto volume = m_dataset->load(step, level);
            std::memcpy(dst, volume->values(size_t(var)), grid.cellCount() * sizeof(float));
            g_valuesRead.fetch_add(grid.cellCount(), std::memory_order_relaxed);
        }
        return out;
    }

    // The box [lat0, lat1) x [r0, r1) x [lon0, lon1) (grid indices of the level) of one variable of
    // one step, float32, a copy; reads only what the box needs (readBox): the lazy xarray arrays'
    // one read. Throws raypc::Error naming an axis whose range is empty or outside the grid.
    py::array_t<float> readBoxOf(const std::string& name, int step, int level, std::array<size_t, 3> begin,
                                 std::array<size_t, 3> end) const
    {
        const int var = variableIndex(name);
        m_dataset->checkStep(step);
        m_dataset->checkLevel(level);
        const grid::SphericalGrid& grid = m_dataset->levels()[size_t(level)].grid;
        const std::array<size_t, 3> n{grid.nLat(), grid.nR(), grid.nLon()};
        constexpr const char* axes[] = {"lat", "r", "lon"};
        for (size_t a = 0; a < 3; ++a)
            if (!(begin[a] < end[a] && end[a] <= n[a]))
                fail("read_box: {} index range {}..{} is empty or outside 0..{} of level {}", axes[a], begin[a], end[a],
                     n[a], level);
        py::array_t<float> out({py::ssize_t(end[0] - begin[0]), py::ssize_t(end[1] - begin[1]),
                                py::ssize_t(end[2] - begin[2])});
        float* dst = out.mutable_data();
        {
            py::gil_scoped_release release;
            readBox(*m_dataset->load(step, level), size_t(var), begin, end, dst);
        }
        return out;
    }

    std::string probe(double lat, double lon, double rKm, int step, int level, const std::string& var) const
    {
        py::gil_scoped_release release;
        static const analysis::ProbeArgumentNames kNames{"step", "level", "lat", "r_km", "variable"};
        return analysis::probeJson(*m_dataset, step, level, lat, lon, rKm, var, kNames).dump();
    }

    // The parallel-coordinates sample of a step: (columns, units, rows x columns float32).
    py::tuple sample(int step) const
    {
        m_dataset->checkStep(step, "step");  // loadSample checks it too, naming the dataset's directory
        dataset::SampleTable t;
        {
            py::gil_scoped_release release;
            t = m_dataset->loadSample(step);
        }
        return py::make_tuple(t.columns, t.units,
                              arrayOf(t.values, {py::ssize_t(t.rows), py::ssize_t(t.columns.size())}));
    }

    // The pathline sets injected in the `window` steps up to `step`: per set its injection step and
    // time, seed field, attribute columns and units, per-line attributes, points (x, y, z km, time
    // Myr) and the line offsets into them.
    py::list pathlines(int step, int window) const
    {
        m_dataset->checkStep(step);
        analysis::checkPathlineWindow(window);
        std::vector<analysis::PathlineSet> sets;
        {
            py::gil_scoped_release release;
            sets = analysis::loadPathlineWindow(m_dataset->dir(), step, window);
        }
        py::list out;
        for (const analysis::PathlineSet& s : sets) {
            std::vector<int64_t> offsets(s.offsets.begin(), s.offsets.end());
            out.append(py::dict(
                py::arg("injection_step") = s.injectionStep, py::arg("injection_time_myr") = s.injectionTimeMyr,
                py::arg("end_step") = s.endStep, py::arg("seed_field") = s.seedField,
                py::arg("threshold") = s.threshold, py::arg("columns") = s.columns, py::arg("units") = s.units,
                py::arg("attributes") =
                    arrayOf(s.attributes, {py::ssize_t(s.lineCount()), py::ssize_t(s.columns.size())}),
                py::arg("points") = arrayOf(s.points, {py::ssize_t(s.pointCount()), 4}),
                py::arg("offsets") = arrayOf(offsets, {py::ssize_t(offsets.size())})));
        }
        return out;
    }

    // The state `raypc render` draws without --state (the UI's first view), as JSON.
    std::string defaultState() const { return state::toJson(render::defaultState(*m_dataset)).dump(); }

    // The state checked against this dataset (names, step, level: resolveState), normalised.
    std::string checkState(const std::string& text) const
    {
        const render::ResolvedState resolved = render::resolveState(parseState(text, "state"), *m_dataset);
        return state::toJson(resolved.state).dump();
    }

    // The picture `raypc render --state` writes for this state (the same path: StateRenderer, its
    // passes, reference geometry and legends), (height, width, 4) uint8 RGBA. `passes` 0: the state's.
    py::array_t<uint8_t> render(const std::string& text, int passes, const std::string& view, py::object progress) const
    {
        const state::RenderState state = parseState(text, "state");
        if (passes < 0)
            fail("passes: {} is negative", passes);
        if (view != "3d" && view != "map" && view != "section")
            fail("view '{}': expected '3d', 'map' or 'section'", view);
        withPythonArgumentNames([&] { render::checkPictureFitsMemory(state, false, availableMemory()); });
        ProgressBridge bridge(std::move(progress));
        render::ImageRgba8 image;
        if (view != "3d") {
            // The state's map or section (raypc map / raypc section): one picture, no passes.
            {
                py::gil_scoped_release release;
                const render::ResolvedState resolved = render::resolveState(state, *m_dataset);
                image = render::StateRenderer(m_dataset).slicePicture(
                    resolved, view == "map" ? render::StateRenderer::Slice::Map : render::StateRenderer::Slice::Section);
            }
            return arrayOf(image.pixels, {py::ssize_t(image.height), py::ssize_t(image.width), 4});
        }
        {
            py::gil_scoped_release release;
            const render::ResolvedState resolved = render::resolveState(state, *m_dataset);
            render::StateRenderer renderer(m_dataset);
            // A KeyboardInterrupt seen by the progress callback stops the pass in flight.
            const render::StateRenderer::Still still = renderer.renderStill(
                resolved, passes, &bridge.cancel, {}, [&](int done, int total) { bridge("passes", done, total); });
            if (!bridge.cancel)
                image = renderer.picture(still.frames, resolved, true);
        }
        bridge.rethrow();
        return arrayOf(image.pixels, {py::ssize_t(image.height), py::ssize_t(image.width), 4});
    }

    // The exact selected volume of the state's brushes over steps first..last (raypc stats): per step
    // (step, time_myr, volume_km3, fraction_of_mantle, volume_by_radius_km3, shell_volume_km3,
    // selected_mean_by_radius, shell_mean_by_radius); the means of `meanOf` (raypc stats
    // --profile-var; NaN where nothing is selected), empty without it.
    py::list stats(const std::string& text, int first, int last, int level, const std::string& meanOf,
                   py::object progress) const
    {
        const state::RenderState state = parseState(text, "state");
        const std::vector<analysis::RangeFilter> filters = analysis::resolveRangeFilters(*m_dataset, state.brushes, "brushes");
        std::optional<size_t> meanVariable;
        if (!meanOf.empty()) {
            const int index = m_dataset->variableIndex(meanOf);
            if (index < 0)
                failUnknownName("mean_of: unknown variable '{}'; the dataset has: {}", meanOf,
                                fmt::join(m_dataset->variableNames(), ", "));
            meanVariable = size_t(index);
        }
        if (first > last)  // selectionOverTime checks the steps and the level
            fail("steps: {}..{} is empty", first, last);
        ProgressBridge bridge(std::move(progress));
        std::vector<analysis::StepSelection> selections;
        {
            py::gil_scoped_release release;
            int done = 0;  // onStep runs on this thread, after each step
            const int total = last - first + 1;
            try {
                selections = analysis::selectionOverTime(*m_dataset, filters, level, first, last, {}, [&] {
                    bridge("steps", ++done, total);
                    if (bridge.cancel)
                        fail("cancelled");
                }, meanVariable);
            } catch (const Error&) {
                if (!bridge.cancel)
                    throw;
            }
        }
        bridge.rethrow();
        py::list out;
        for (const analysis::StepSelection& s : selections)
            out.append(py::make_tuple(s.step, s.timeMyr, s.stats.volumeKm3, s.stats.fractionOfMantle,
                                      doubles(s.stats.volumeByRadiusKm3), doubles(s.stats.shellVolumeByRadiusKm3),
                                      doubles(s.stats.selectedMeanByRadius), doubles(s.stats.shellMeanByRadius)));
        return out;
    }

    // The features of the state's brushes in steps first..last (raypc features): the table's CSV text
    // (app/feature_table.h), for pandas to read.
    std::string features(const std::string& text, int first, int last, int level, double minVolumeKm3,
                         std::vector<double> depthsKm, double bandHalfWidthKm, py::object progress) const
    {
        const state::RenderState state = parseState(text, "state");
        const std::vector<analysis::RangeFilter> filters = analysis::resolveRangeFilters(*m_dataset, state.brushes, "brushes");
        if (filters.empty())
            fail("features: the state has no brushes (the whole mantle would be one feature)");
        if (first > last)
            fail("steps: {}..{} is empty", first, last);
        m_dataset->checkLevel(level, "level");
        state::FeatureSettings settings;
        settings.minVolumeKm3 = float(minVolumeKm3);
        settings.depthsKm.assign(depthsKm.begin(), depthsKm.end());
        settings.bandHalfWidthKm = float(bandHalfWidthKm);
        state::checkFeatureSettings(settings, {{"minVolumeKm3", "min_volume_km3"},
                                                {"depthsKm", "depths_km"},
                                                {"bandHalfWidthKm", "band_half_width_km"}});
        const analysis::FeatureOptions options = analysis::featureOptions(minVolumeKm3, std::move(depthsKm), bandHalfWidthKm);
        ProgressBridge bridge(std::move(progress));
        std::string csv = app::featureTableHeader(*m_dataset, options);
        {
            py::gil_scoped_release release;
            const analysis::StepVolumeLoader load = [&](int step) {
                m_dataset->checkStep(step, "steps");
                return m_dataset->load(step, level);
            };
            analysis::FeatureRunControl control{&bridge.cancel, [&](int done, int total) {
                                          if (done > 0)  // after each step
                                              bridge("steps", done, total);
                                      }};
            analysis::forEachStepFeatures(first, last, load, filters, options, [&](analysis::FeatureStep& s) {
                csv += app::featureTableRows(s.step, m_dataset->steps()[size_t(s.step)].timeMyr, s.features);
            }, control);
        }
        bridge.rethrow();
        return csv;
    }

    // The state's map or section of its colour variable as a CF grid (what `raypc map --netcdf` and
    // `raypc section --netcdf` write, app/slice_grid.h): a dict of the grid's parts for xarray.
    py::dict sliceGrid(const std::string& text, const std::string& view, double gridStepDeg, double depthStepKm) const
    {
        if (view != "map" && view != "section")
            fail("view '{}': expected 'map' or 'section'", view);
        const auto slice = view == "map" ? render::StateRenderer::Slice::Map : render::StateRenderer::Slice::Section;
        const app::SliceGridNames names{"grid_step_deg", "depth_step_km", "state.map.depthKm"};
        app::checkSliceGridSpacing(slice, gridStepDeg, depthStepKm, names);
        const state::RenderState state = parseState(text, "state");
        io::CfGridFile file;
        {
            py::gil_scoped_release release;
            const render::ResolvedState resolved = render::resolveState(state, *m_dataset);
            const auto volume = m_dataset->load(resolved.state.step, resolved.state.level.value_or(0));
            file = app::sliceGridFile(*m_dataset, *volume, resolved, slice, gridStepDeg, depthStepKm,
                                      "raypc.Dataset." + view + "_grid", names);
        }
        auto variable = [](const io::CfVariable1D& v) {
            return py::dict(py::arg("name") = v.name, py::arg("units") = v.units, py::arg("standard_name") = v.standardName,
                            py::arg("long_name") = v.longName, py::arg("axis") = v.axis, py::arg("positive") = v.positive,
                            py::arg("values") = doubles(v.values), py::arg("dimension") = v.dimension);
        };
        py::list auxiliary, scalars;
        for (const io::CfVariable1D& v : file.auxiliary)
            auxiliary.append(variable(v));
        for (const io::CfVariable1D& v : file.scalars)
            scalars.append(variable(v));
        return py::dict(py::arg("name") = file.name, py::arg("units") = file.units, py::arg("long_name") = file.longName,
                        py::arg("rows") = variable(file.rows), py::arg("columns") = variable(file.columns),
                        py::arg("auxiliary") = auxiliary, py::arg("scalars") = scalars,
                        py::arg("values") = arrayOf(file.values, {py::ssize_t(file.rows.values.size()),
                                                                  py::ssize_t(file.columns.values.size())}),
                        py::arg("attributes") = file.globalAttributes);
    }

    // The features of the state's brushes in every step followed through the series (what the UI's
    // Features panel shows and `raypc features --tracks/--events/--stalls` and `raypc flux` write:
    // server/api_views.h featureSeriesJson), as its JSON text with the CSV tables under "csv".
    std::string featureSeries(const std::string& text, int level, double minVolumeKm3, std::vector<double> depthsKm,
                              double bandHalfWidthKm, double minOverlapShare, const std::string& stallBy, double sigmas,
                              py::object progress) const
    {
        const state::RenderState state = parseState(text, "state");
        const std::vector<analysis::RangeFilter> filters = analysis::resolveRangeFilters(*m_dataset, state.brushes, "brushes");
        m_dataset->checkLevel(level, "level");
        state::FeatureSettings settings;
        settings.minVolumeKm3 = float(minVolumeKm3);
        settings.depthsKm.assign(depthsKm.begin(), depthsKm.end());
        settings.bandHalfWidthKm = float(bandHalfWidthKm);
        settings.minOverlapShare = float(minOverlapShare);
        state::checkFeatureSettings(settings, {{"minVolumeKm3", "min_volume_km3"},
                                                {"depthsKm", "depths_km"},
                                                {"bandHalfWidthKm", "band_half_width_km"},
                                                {"minOverlapShare", "min_overlap"}});
        const analysis::StallMeasure measure = analysis::parseStallMeasure(stallBy);
        const analysis::FeatureOptions options = analysis::featureOptions(minVolumeKm3, std::move(depthsKm), bandHalfWidthKm);
        ProgressBridge bridge(std::move(progress));
        std::string out;
        {
            py::gil_scoped_release release;
            // Each step is read once, in order: a small cache that keeps nothing for long.
            server::StepCache cache([this](int step, int lod) { return m_dataset->load(step, lod); }, size_t(1) << 30, 2);
            try {
                out = server::featureSeriesJson(*m_dataset, cache, filters, options, minOverlapShare, measure, level, sigmas,
                                                &bridge.cancel, [&](int done, int total) {
                                                    if (done > 0)
                                                        bridge("steps", done, total);
                                                })
                          .dump();
            } catch (const Error&) {
                if (!bridge.cancel)
                    throw;
            }
        }
        bridge.rethrow();
        return out;
    }

private:
    int variableIndex(const std::string& name) const
    {
        const int var = m_dataset->variableIndex(name);
        if (var < 0)
            failUnknownName("variable: unknown variable '{}'; the dataset has: {}", name,
                            fmt::join(m_dataset->variableNames(), ", "));
        return var;
    }

    std::shared_ptr<const dataset::Dataset> m_dataset;
};

// `raypc serve` of one dataset inside this process, on its own thread (the notebook view).
class PyServer {
public:
    // assets/examples: the UI's files and the example states inside the installed package
    // (raypc/web, raypc/examples, passed by raypc.show); nullopt: the executable's lookup
    // (core/install_paths.h), which finds them in the build and source trees.
    PyServer(const std::string& dataset, const std::string& host, int port,
             const std::optional<std::string>& assets, const std::optional<std::string>& examples)
    {
        if (port < 0 || port > 65535)
            fail("port: {} out of range 0..65535", port);
        server::ServerOptions options;
        options.dataset = dataset;
        options.host = host;
        options.port = uint16_t(port);
        options.handleSignals = false;  // the Python process's signals stay Python's
        const auto path = [](const std::optional<std::string>& p) {
            return p ? std::optional<std::filesystem::path>(*p) : std::nullopt;
        };
        options.assets = findAssetDir(path(assets));
        options.examples = findExamplesDir(path(examples));
        m_server = withPythonArgumentNames([&] { return std::make_unique<server::Server>(std::move(options)); });
        m_url = m_server->url();
        m_port = m_server->port();
        m_token = m_server->token();
        m_thread = std::thread([this] { m_server->run(); });
    }
    ~PyServer() { stop(); }
    // Stops serving and frees the port: Server::stop() ends the run loop, but the listening socket
    // is closed only with the Server, and a socket left listening would take connections that no
    // one answers (a client waits for its timeout instead of being refused). Stopping again: nothing.
    void stop()
    {
        if (!m_server)
            return;
        py::gil_scoped_release release;
        m_server->stop();
        m_thread.join();
        m_server.reset();
    }
    std::string url() const { return m_url; }
    int port() const { return m_port; }
    std::string token() const { return m_token; }

private:
    std::unique_ptr<server::Server> m_server;
    std::thread m_thread;
    std::string m_url, m_token;  // kept for after stop()
    int m_port = 0;
};

// `python3 -m raypc ARGS`: the command line (app/cli.h) as the executable runs it, minus the
// executable's restart with transparent huge pages, which would exec /proc/self/exe (Python).
int runCommandLine(std::vector<std::string> args)
{
    if (args.empty())
        fail("main: argv is empty, expected the program's name first (as sys.argv)");
    std::vector<char*> argv;
    for (auto& arg : args)
        argv.push_back(arg.data());
    argv.push_back(nullptr);
    // `serve` stops on SIGINT/SIGTERM through its own handlers, which it leaves at the default when
    // it stops: put back the handlers this process had (Python's KeyboardInterrupt) afterwards.
    struct sigaction savedInt{}, savedTerm{};
    sigaction(SIGINT, nullptr, &savedInt);
    sigaction(SIGTERM, nullptr, &savedTerm);
    // Python's own output first, then the command's (both to the same file descriptors).
    py::module_::import("sys").attr("stdout").attr("flush")();
    py::module_::import("sys").attr("stderr").attr("flush")();
    int status = 0;
    {
        py::gil_scoped_release release;
        status = app::run(int(args.size()), argv.data());
        std::cout.flush();
        std::fflush(stdout);
        std::fflush(stderr);
    }
    sigaction(SIGINT, &savedInt, nullptr);
    sigaction(SIGTERM, &savedTerm, nullptr);
    return status;
}

}  // namespace
}  // namespace raypc::python

PYBIND11_MODULE(_raypc, m)
{
    using namespace raypc::python;
    m.doc() = "RayPC's compiled core (use the raypc package)";
    // raypc.Error is a ValueError (a bad value given, as most of its messages say); each kind is also
    // the builtin exception a Python user catches for it. Shown as raypc.X, where the package
    // exports them (raypc/__init__.py).
    static py::exception<raypc::Error> error(m, "Error", PyExc_ValueError);
    static py::exception<raypc::NotFoundError> notFound(m, "NotFoundError",
                                                        py::make_tuple(error, py::handle(PyExc_FileNotFoundError)));
    static py::exception<raypc::UnknownNameError> unknownName(m, "UnknownNameError",
                                                              py::make_tuple(error, py::handle(PyExc_KeyError)));
    static py::exception<raypc::OutOfRangeError> outOfRange(m, "OutOfRangeError",
                                                            py::make_tuple(error, py::handle(PyExc_IndexError)));
    error.doc() = "An expected failure of RayPC (bad input), with the command line's one-line message; a ValueError.";
    notFound.doc() = "A file, directory or dataset that is not there; also a FileNotFoundError.";
    unknownName.doc() = "A name (a variable, a brushed variable or coordinate) the dataset does not have; also a KeyError.";
    outOfRange.doc() = "A step or level of detail that does not exist; also an IndexError.";
    // KeyError's str() shows its argument's repr (quotes, escapes): a message prints as it reads.
    unknownName.attr("__str__") = py::cpp_function(
        [](py::handle self) -> py::str {
            const py::tuple args = self.attr("args");
            return args.size() == 1 ? py::str(args[0]) : py::str(py::object(args));
        },
        py::is_method(unknownName));
    for (py::handle type : {py::handle(error), py::handle(notFound), py::handle(unknownName), py::handle(outOfRange)})
        type.attr("__module__") = "raypc";
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p)
                std::rethrow_exception(p);
        } catch (const raypc::NotFoundError& e) {
            notFound(e.what());
        } catch (const raypc::UnknownNameError& e) {
            unknownName(e.what());
        } catch (const raypc::OutOfRangeError& e) {
            outOfRange(e.what());
        } catch (const raypc::Error& e) {
            error(e.what());
        }
    });

    m.attr("__version__") = RAYPC_VERSION;  // project(VERSION), as `raypc --version` and the wheel's metadata
    m.def("main", &runCommandLine, py::arg("argv"),
          "Runs the raypc command line on argv (argv[0] the program's name, as sys.argv); returns the exit status. "
          "Ctrl-C: `serve` stops; other commands stop only if SIGINT's handler is the default (python3 -m raypc sets it)");
    m.def("prepare", &prepare, py::arg("args"), py::arg("progress") = py::none(),
          "Preprocess inputs as `raypc serve INPUT…` does; returns the dataset directory");
    m.def("diff", &difference, py::arg("a"), py::arg("b"), py::arg("out"), py::arg("variables"), py::arg("steps"),
          py::arg("match"), py::arg("progress") = py::none(),
          "raypc diff: the difference dataset a − b (or a's step differences, b empty and steps k) written to out");
    m.def(
        "check_state",
        [](const std::string& text) { return raypc::state::toJson(parseState(text, "state")).dump(); },
        py::arg("json"), "The state document parsed by the one state schema, normalised (JSON)");
    m.def("values_read", [] { return g_valuesRead.load(std::memory_order_relaxed); },
          "Grid values read from step files by Dataset.field and read_box so far (for tests of laziness)");
    m.def("correlate", &correlate, py::arg("a"), py::arg("var_a"), py::arg("step"), py::arg("b"), py::arg("var_b"),
          py::arg("step_b"), py::arg("lmax"),
          "raypc correlate's numbers: per depth the area-weighted correlation, RMS of each and ratio (lmax < 0: unfiltered)");
    m.def("spectrum", &spectrum, py::arg("ds"), py::arg("var"), py::arg("step"), py::arg("lmax"),
          "raypc spectrum's numbers: the power per degree at every depth (lmax < 0: the grid's largest, at most 60)");
    m.def("degree_correlation", &degreeCorrelation, py::arg("a"), py::arg("var_a"), py::arg("step"), py::arg("b"),
          py::arg("var_b"), py::arg("step_b"), py::arg("depth_km"), py::arg("lmax"),
          "raypc spectrum --with's numbers: the per-degree powers and correlation at the shell nearest depth_km");
    m.def("surface_radius_km", [] { return raypc::kSurfaceRadiusKm; }, "The Earth's radius that depths count from, km");
    m.def("state_version", [] { return raypc::state::kRenderStateVersion; }, "The version of the state document this build writes");
    m.def("names_json", [] { return std::string(kNamesJson); },
          "src/grid/names.json: the names of derived variables and of the columns of the tables raypc writes");
    m.def("cf_name", &raypc::io::cfName, py::arg("display_name"),
          "The CF/netCDF-safe name of a variable's display name (io/cf_grid.h: what raypc writes in every file)");
    m.def(
        "critical_kind_name",
        [](int kind) {
            if (kind < 0 || kind > int(raypc::analysis::CriticalKind::MultiSaddle))
                raypc::fail("critical point kind {} out of range 0..{}", kind, int(raypc::analysis::CriticalKind::MultiSaddle));
            return std::string(raypc::analysis::criticalKindName(raypc::analysis::CriticalKind(kind)));
        },
        py::arg("kind"));

    py::class_<PyDataset>(m, "Dataset")
        .def(py::init<const std::string&>(), py::arg("dir"), "Opens a dataset directory (raypc preprocess)")
        .def_property_readonly("dir", &PyDataset::dir, "The dataset directory")
        .def_property_readonly("variables", &PyDataset::variables,
                               "Every variable: {name, units, derived, min, max (global range, in its units)}")
        .def_property_readonly("times_myr", &PyDataset::timesMyr, "The time of every step, Myr")
        .def_property_readonly("levels", &PyDataset::levels,
                               "Every level of detail's grid: {lat (degrees north), r (km), lon (degrees east)}")
        .def_property_readonly("encoding", &PyDataset::encoding, "How the levels are stored: 'u16' or 'float32'")
        .def("step", &PyDataset::step, py::arg("text"), py::arg("what") = "step",
             "The step of an index ('12') or a time ('24Myr'); `what` names the argument in errors")
        .def("field", &PyDataset::field, py::arg("variable"), py::arg("step"), py::arg("level"),
             "One variable of one step at a level, (lat, r, lon) float32 in its units, NaN where there are no data")
        .def("read_box", &PyDataset::readBoxOf, py::arg("variable"), py::arg("step"), py::arg("level"),
             py::arg("begin"), py::arg("end"),
             "One variable of one step in the grid-index box [begin, end) of (lat, r, lon), reading only what it needs")
        .def("probe", &PyDataset::probe, py::arg("lat"), py::arg("lon"), py::arg("r_km"), py::arg("step"),
             py::arg("level"), py::arg("variable"),
             "The values at a point (lat, lon degrees; r_km radius, km) as raypc probe's JSON text; `variable` '' for all")
        .def("sample", &PyDataset::sample, py::arg("step"),
             "The parallel-coordinates sample of a step: (columns, units, rows x columns float32)")
        .def("pathlines", &PyDataset::pathlines, py::arg("step"), py::arg("window"),
             "The pathline sets injected in the `window` steps up to `step` (points x, y, z km, time Myr)")
        .def("default_state", &PyDataset::defaultState, "The UI's first view of this dataset, as state JSON text")
        .def("check_state", &PyDataset::checkState, py::arg("json"),
             "The state checked against this dataset (variables, step, level), normalised JSON text")
        .def("render", &PyDataset::render, py::arg("json"), py::arg("passes"), py::arg("view") = "3d",
             py::arg("progress") = py::none(),
             "The state's picture (raypc render --state; view 'map'/'section': raypc map/section), (h, w, 4) uint8")
        .def("features", &PyDataset::features, py::arg("json"), py::arg("first"), py::arg("last"), py::arg("level"),
             py::arg("min_volume_km3"), py::arg("depths_km"), py::arg("band_half_width_km"), py::arg("progress") = py::none(),
             "The features of the state's brushes in steps first..last: raypc features' CSV text (volumes km³, depths km)")
        .def("slice_grid", &PyDataset::sliceGrid, py::arg("json"), py::arg("view"), py::arg("grid_step_deg"),
             py::arg("depth_step_km"),
             "The state's map or section as the CF grid of raypc map/section --netcdf (degrees, km), as a dict")
        .def("feature_series", &PyDataset::featureSeries, py::arg("json"), py::arg("level"), py::arg("min_volume_km3"),
             py::arg("depths_km"), py::arg("band_half_width_km"), py::arg("min_overlap"), py::arg("stall_by"),
             py::arg("sigmas"), py::arg("progress") = py::none(),
             "The features followed through every step (the UI's Features panel) as JSON text, the CLI's CSVs under 'csv'")
        .def("stats", &PyDataset::stats, py::arg("json"), py::arg("first"), py::arg("last"), py::arg("level"),
             py::arg("mean_of") = "", py::arg("progress") = py::none(),
             "The exact selected volume (km³, share of the mantle) per step, with its profile per radius");

    py::class_<PyServer>(m, "Server")
        .def(py::init<const std::string&, const std::string&, int, const std::optional<std::string>&,
                      const std::optional<std::string>&>(),
             py::arg("dataset"), py::arg("host"), py::arg("port"), py::arg("assets") = py::none(),
             py::arg("examples") = py::none(),
             "Serves the dataset's UI (raypc serve) on its own thread; `assets`/`examples`: the UI's and the states' directories")
        .def_property_readonly("url", &PyServer::url, "The UI's address (with the token off loopback)")
        .def_property_readonly("port", &PyServer::port, "The port it listens on")
        .def_property_readonly("token", &PyServer::token, "The access token ('' on loopback)")
        .def("stop", &PyServer::stop, "Stops the server and frees its port");
}
