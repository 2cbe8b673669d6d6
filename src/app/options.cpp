#include "app/options.h"

#include "core/error.h"
#include "core/strings.h"

#include <algorithm>
#include <charconv>
#include <cmath>

namespace raypc::app {

void ReaderFlags::add(CLI::App& app)
{
    app.add_option("--map", variableMap,
                   "Read variable NAME from FILE_NAME in the input (NAME=FILE_NAME, repeatable), e.g. "
                   "--map temperature=T");
    app.add_option("--lat-name", latName, "Name of the latitude coordinate variable (default: found)");
    app.add_option("--r-name", rName, "Name of the radius coordinate variable (default: found)");
    app.add_option("--lon-name", lonName, "Name of the longitude coordinate variable (default: found)");
    app.add_flag("--fill-missing", fillMissing,
                 "Replace missing values (_FillValue, missing_value, NaN) by their shell's mean instead of failing");
}

ReaderOptions ReaderFlags::toOptions() const
{
    ReaderOptions o;
    for (const auto& m : variableMap) {
        const auto eq = m.find('=');
        if (eq == std::string::npos || eq == 0 || eq + 1 == m.size())
            fail("--map: '{}' is not NAME=FILE_NAME", m);
        const auto name = m.substr(0, eq);
        const auto& known = contestVariableNames();
        if (std::find(known.begin(), known.end(), name) == known.end())
            fail("--map: '{}' is not one of the variables RayPC reads ({})", name, fmt::join(known, ", "));
        o.variableNames[name] = m.substr(eq + 1);
    }
    o.latName = latName;
    o.rName = rName;
    o.lonName = lonName;
    o.fillMissing = fillMissing;
    return o;
}

int parseStep(const Dataset& dataset, const std::string& text, const std::string& option)
{
    const int count = static_cast<int>(dataset.steps().size());
    const std::string t = trim(text);
    if (t.size() > 3 && (t.ends_with("Myr") || t.ends_with("myr"))) {
        const std::string number = trim(t.substr(0, t.size() - 3));
        double myr = 0;
        const auto [end, ec] = std::from_chars(number.data(), number.data() + number.size(), myr);
        if (ec != std::errc() || end != number.data() + number.size())
            fail("{}: '{}' is not a time like 24Myr", option, text);
        for (const auto& s : dataset.steps())
            if (std::abs(s.timeMyr - myr) <= 1e-6 * std::max(1.0, std::abs(myr)))
                return s.index;
        fail("{}: no step at {} Myr; steps are {} Myr apart from {} to {} Myr", option, myr, dataset.dtMyr(),
             dataset.steps().front().timeMyr, dataset.steps().back().timeMyr);
    }
    int step = -1;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), step);
    if (ec != std::errc() || end != t.data() + t.size())
        fail("{}: '{}' is neither a step index nor a time like 24Myr", option, text);
    if (step < 0 || step >= count)
        fail("{}: step {} out of range, the dataset has steps 0..{}", option, step, count - 1);
    return step;
}

NamedRange parseRangeOption(const std::string& text, const std::string& option)
{
    const size_t eq = text.rfind('=');
    const size_t colon = eq == std::string::npos ? std::string::npos : text.find(':', eq + 1);
    if (eq == std::string::npos || eq == 0 || colon == std::string::npos)
        fail("{} '{}': expected NAME=MIN:MAX", option, text);
    NamedRange r;
    r.name = trim(text.substr(0, eq));
    const std::string lo = trim(text.substr(eq + 1, colon - eq - 1)), hi = trim(text.substr(colon + 1));
    auto number = [&](const std::string& s) {
        float v = 0;
        const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (s.empty() || ec != std::errc() || end != s.data() + s.size())
            fail("{} '{}': MIN and MAX must be numbers", option, text);
        return v;
    };
    r.min = number(lo);
    r.max = number(hi);
    if (!(r.min <= r.max))
        fail("{} '{}': min {} is greater than max {}", option, text, r.min, r.max);
    return r;
}

void applyRangeOptions(std::vector<NamedRange>& ranges, const std::vector<std::string>& options,
                       const std::string& option)
{
    std::vector<NamedRange> given;
    for (const std::string& text : options)
        given.push_back(parseRangeOption(text, option));
    std::erase_if(ranges, [&](const NamedRange& r) {
        return std::any_of(given.begin(), given.end(), [&](const NamedRange& g) { return g.name == r.name; });
    });
    ranges.insert(ranges.end(), given.begin(), given.end());
}

std::pair<int, int> parseStepRange(const Dataset& dataset, const std::string& text, const std::string& option)
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

}  // namespace raypc::app
