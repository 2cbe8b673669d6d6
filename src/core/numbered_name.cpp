#include "core/numbered_name.h"

#include "core/error.h"

#include <string_view>

namespace raypc {

namespace {

std::string quoted(const std::string& pattern)
{
    return pattern.size() <= 80 ? pattern : pattern.substr(0, 80) + "…";
}

}  // namespace

NumberedName::NumberedName(const std::string& pattern, const std::string& option)
{
    const auto refuse = [&](const std::string& why) {
        fail("{} '{}': {}; write the step number as %d or %03d (zero-padded, width 1 to 9) and a literal % as %%",
             option, quoted(pattern), why);
    };
    std::string* out = &m_prefix;
    for (size_t i = 0; i < pattern.size(); ++i) {
        if (pattern[i] != '%') {
            *out += pattern[i];
            continue;
        }
        if (i + 1 < pattern.size() && pattern[i + 1] == '%') {
            *out += '%';
            ++i;
            continue;
        }
        // "%d" or "%0Nd": the only conversions.
        size_t j = i + 1;
        int width = 0;
        if (j < pattern.size() && pattern[j] == '0') {
            ++j;
            if (j >= pattern.size() || pattern[j] < '1' || pattern[j] > '9')
                refuse(fmt::format("'{}' at character {} is not a step number", pattern.substr(i, j + 1 - i), i + 1));
            width = pattern[j] - '0';
            ++j;
        }
        if (j >= pattern.size() || pattern[j] != 'd') {
            const size_t end = std::min(pattern.size(), j + 1);
            refuse(fmt::format("'{}' at character {} is not a step number", quoted(pattern.substr(i, end - i)), i + 1));
        }
        if (m_width >= 0)
            refuse("it holds more than one step number");
        m_width = width;
        out = &m_suffix;
        i = j;
    }
}

std::string NumberedName::operator()(int64_t number) const
{
    if (m_width < 0)
        return m_prefix;
    const bool negative = number < 0;
    std::string digits = std::to_string(negative ? -(number + 1) + uint64_t(1) : uint64_t(number));
    const size_t width = size_t(m_width) - (negative && m_width > 0 ? 1 : 0);
    if (digits.size() < width)
        digits.insert(0, width - digits.size(), '0');
    return m_prefix + (negative ? "-" : "") + digits + m_suffix;
}

}  // namespace raypc
