// A file name with at most one number in it, as `raypc render -o frames/frame_%03d.png --time 0:9`
// takes: "%d" or "%0Nd" (N = 1…9, zero-padded to N characters) stands for the number, "%%" for a
// literal "%", and nothing else may follow a "%". Expanded without printf, so no user text is ever a
// format string (through printf, "%s%03d" crashed, "%x%d" and "%p%d" wrote stack values into names,
// "%999999999d" cut names so that frames overwrote each other).
#pragma once

#include <cstdint>
#include <string>

namespace raypc {

class NumberedName {
public:
    // Throws raypc::Error "<option> '<pattern>': …" naming the conversion it refuses (the pattern
    // quoted to at most 80 characters).
    NumberedName(const std::string& pattern, const std::string& option);

    // True when the pattern holds "%d" / "%0Nd": different numbers then give different names.
    bool numbered() const { return m_width >= 0; }
    // The name for `number` (the pattern with "%%" as "%" when it is not numbered).
    std::string operator()(int64_t number) const;

private:
    std::string m_prefix, m_suffix;
    int m_width = -1;  // -1: no number; 0: "%d"; N: "%0Nd"
};

}  // namespace raypc
