// Fields to compare: opened from "INPUT[:VARIABLE]", B put on A's grid (compare_fields.h).
#include "app/compare_fields.h"

#include "app/options.h"
#include "app/series_inputs.h"
#include "core/error.h"
#include "core/error_kinds.h"
#include "core/spherical.h"
#include "grid/regrid.h"
#include "grid/variable_names.h"
#include "render/depth_profile_view.h"
#include "render/legend.h"
#include "render/time_depth_view.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace raypc::app {
namespace fs = std::filesystem;

FieldSpec parseFieldSpec(const std::string& text)
{
    std::error_code ec;
    if (fs::exists(text, ec))
        return {text, ""};
    const size_t colon = text.rfind(':');
    if (colon == std::string::npos || colon == 0)
        return {text, ""};
    return {text.substr(0, colon), text.substr(colon + 1)};
}

std::string ComparedField::title() const
{
    const dataset::VariableInfo& v = info();
    return fmt::format("{}: {} [{}], step {} ({:g} Myr)", dataset->dir().filename().string(), v.name,
                       v.units.empty() ? std::string("1") : v.units, step, dataset->steps()[size_t(step)].timeMyr);
}

ComparedField openComparedField(const FieldSpec& spec, const std::string& stepText, const std::string& what,
                                const std::string& stepOption, bool quiet)
{
    SeriesInputs inputs;
    try {
        inputs = resolveSeriesInputs({spec.input}, "", io::ReaderOptions{});
    } catch (const Error& e) {
        failLike(e, fmt::format("{}: {}", what, e.what()));
    }
    if (inputs.fromFiles()) {
        preprocess::PreprocessOptions options;
        options.quiet = quiet;
        options.timesMyr = inputs.timesMyr;
        prepareSeries(inputs, options);
    }
    ComparedField f;
    f.dataset = dataset::Dataset::open(inputs.dataset);
    const std::vector<std::string> names = f.dataset->variableNames();
    const std::string name = spec.variable.empty() ? varname::anomalyToShow(names) : spec.variable;
    const int index = f.dataset->variableIndex(name);
    if (index < 0)
        failUnknownName("{}: no variable '{}' in {}; it has {}", what, name, inputs.dataset.string(), fmt::join(names, ", "));
    f.variable = size_t(index);
    f.step = parseStep(*f.dataset, stepText, stepOption);
    f.volume = f.dataset->load(f.step, 0);
    return f;
}

std::vector<float> valuesOnGridOf(const ComparedField& b, const ComparedField& a)
{
    const grid::SphericalGrid& target = a.volume->grid();
    const grid::SphericalGrid& source = b.volume->grid();
    if (source.sameAs(target))
        return {b.values(), b.values() + target.cellCount()};
    if (!(grid::coveredFraction(source, target) > 0))
        fail("B ({}) does not overlap A's grid ({}): radii {:.0f}..{:.0f} km against {:.0f}..{:.0f} km{}", b.title(), a.title(),
             source.rKm.front(), source.rKm.back(), target.rKm.front(), target.rKm.back(),
             source.regional() || target.regional() ? ", or regions apart" : "");
    return grid::regrid(source, b.values(), target);
}

std::vector<analysis::ShellCorrelation> correlateFields(const ComparedField& a, const ComparedField& b,
                                                        const analysis::CorrelationOptions& options)
{
    const std::vector<float> onA = valuesOnGridOf(b, a);
    return analysis::correlateShells(a.volume->grid(), a.values(), onA.data(), options, "A (" + a.title() + ")");
}

analysis::ShellSpectra fieldSpectra(const ComparedField& field, int lmax)
{
    const grid::SphericalGrid& g = field.volume->grid();
    return analysis::shellSpectra(g, field.values(), lmax < 0 ? analysis::defaultSpectrumDegree(g) : lmax, field.title());
}

analysis::DegreeCorrelation fieldDegreeCorrelation(const ComparedField& a, const ComparedField& b, double depthKm, int lmax)
{
    const grid::SphericalGrid& g = a.volume->grid();
    const size_t shell = analysis::nearestShell(g, depthKm);
    const std::vector<float> onA = valuesOnGridOf(b, a);
    return analysis::degreeCorrelationAt(g, a.values(), onA.data(), shell, lmax < 0 ? analysis::defaultSpectrumDegree(g) : lmax,
                                         "A (" + a.title() + ")", "B (" + b.title() + ") on A's grid");
}

namespace {
// The reference shells the comparisons' pictures mark: the transition zone's boundaries.
state::ReferenceState::Shells transitionZone()
{
    state::ReferenceState::Shells marks;
    marks.visible = true;
    marks.depthsKm = {410.0f, 660.0f};
    return marks;
}
}  // namespace

render::ImageRgba8 correlationPicture(const std::vector<analysis::ShellCorrelation>& rows, const ComparedField& a,
                                      const ComparedField& b, const analysis::CorrelationOptions& options, int width,
                                      int height)
{
    render::DepthProfileInputs in;
    for (const analysis::ShellCorrelation& row : rows) {
        in.depthsKm.push_back(row.depthKm);
        in.values.push_back(row.correlation);
    }
    const grid::SphericalGrid& g = a.volume->grid();
    in.depthSpanKm = kSurfaceRadiusKm - g.rKm.front();
    in.xTicks = {-1, -0.5, 0, 0.5, 1};
    in.xTitle = options.lmax ? fmt::format("correlation (both filtered to degree ≤ {})", *options.lmax)
                             : std::string("correlation (area-weighted Pearson)");
    in.titleLines = {fmt::format("A: {}", a.title()), fmt::format("B: {}", b.title())};
    in.width = width;
    in.height = height;
    in.marks = transitionZone();
    return render::depthProfilePicture(in);
}

render::ImageRgba8 spectrumPicture(const analysis::ShellSpectra& s, const ComparedField& field, int width, int height)
{
    if (s.lmax < 1)
        fail("--png: a spectrum to degree {} has no degree to draw (degree 0, the shell's mean, is left out); give --lmax 1 "
             "or more",
             s.lmax);
    render::TimeDepthInputs in;
    in.columnsAre = render::TimeDepthInputs::Columns::Degree;
    for (int l = 1; l <= s.lmax; ++l)
        in.columns.push_back(double(l));
    in.radiiKm = s.radiiKm;
    in.values.resize(in.columns.size() * s.radiiKm.size());
    double most = -INFINITY;
    for (size_t iR = 0; iR < s.radiiKm.size(); ++iR)
        for (int l = 1; l <= s.lmax; ++l)
            if (s.at(iR, l) > 0)
                most = std::max(most, std::log10(s.at(iR, l)));
    if (!std::isfinite(most))
        fail("--png: {} has no power at degrees 1..{} (constant on every shell): nothing to draw", field.title(), s.lmax);
    // Six decades: below them is rounding (a shell where the field is constant, e.g. an anomaly at the
    // surface or the core-mantle boundary, is drawn as the background).
    const double floor = most - 6;
    double least = most;
    for (size_t iR = 0; iR < s.radiiKm.size(); ++iR) {
        double shell = 0;
        for (int l = 1; l <= s.lmax; ++l)
            shell = std::max(shell, s.at(iR, l));
        const bool flat = !(shell > 0) || std::log10(shell) < floor;
        for (size_t l = 1; l <= size_t(s.lmax); ++l) {
            const double p = s.at(iR, int(l));
            const float v = flat ? NAN : float(p > 0 ? std::max(std::log10(p), floor) : floor);
            in.values[(l - 1) * s.radiiKm.size() + iR] = v;
            if (!flat)
                least = std::min(least, double(v));
        }
    }
    in.blankNote = "background: the field has no lateral variation on that shell";
    in.colors.colorMap = render::ColorMapId::Viridis;
    in.colors.range = {float(least), float(most > least ? most : least + 1)};
    const dataset::VariableInfo& v = field.info();
    const std::string units = render::displayUnits(v.units.empty() ? "1" : v.units);
    in.colorTitle = fmt::format("log₁₀ power per degree of {} [{}²]", v.name,
                                units.find_first_of("/ ") == std::string::npos ? units : "(" + units + ")");
    in.title = fmt::format("{} · degree 1–{} · {}", field.title(), s.lmax, analysis::quadratureName(s.quadrature));
    in.width = width;
    in.height = height;
    in.marks = transitionZone();
    return render::timeDepthPicture(in);
}

}  // namespace raypc::app
