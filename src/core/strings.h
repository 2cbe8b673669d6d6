// Small string helpers used at the edges (CLI, file names, JSON keys).
#pragma once

#include <optional>
#include <ranges>
#include <string>
#include <string_view>
#include <vector>

namespace raypc {

// "Natural" order: digit runs compare by value, so step2.nc < step10.nc.
bool naturalLess(std::string_view a, std::string_view b);

// A file-system-safe form of a variable name: "temperature anomaly" -> "temperature_anomaly".
std::string fileSafeName(std::string_view name);

// A CSV field: quoted (with doubled quotes) when it holds a comma, quote or newline.
std::string csvQuote(std::string_view field);

std::vector<std::string> split(std::string_view text, char separator);
std::string trim(std::string_view text);

// The value among `all` whose name (`nameOf(value)`) is `name`, or nullopt; `known` then lists
// every name, comma-separated, for the caller's message. The one lookup behind the parsers of
// named options (colour maps, stereo modes, projections).
template <std::ranges::range Range, class NameOf>
std::optional<std::ranges::range_value_t<Range>> findByName(std::string_view name, const Range& all, NameOf nameOf,
                                                            std::string& known)
{
    known.clear();
    for (const auto& value : all) {
        if (nameOf(value) == name)
            return value;
        known += (known.empty() ? "" : ", ") + std::string(nameOf(value));
    }
    return std::nullopt;
}

}  // namespace raypc
