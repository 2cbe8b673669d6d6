// libFuzzer target: `raypc render -o` patterns (core/numbered_name.h). Any pattern is accepted or
// refused with one raypc::Error; an accepted numbered pattern gives different names for different
// steps (no two frames share a file) and never a name longer than the pattern plus 20 characters.
#include "core/error.h"
#include "core/numbered_name.h"

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const std::string pattern(reinterpret_cast<const char*>(data), size);
    try {
        const raypc::NumberedName name(pattern, "-o");
        const std::string a = name(0), b = name(1), c = name(250);
        if (a.size() > pattern.size() + 20 || c.size() > pattern.size() + 20)
            std::abort();
        if (name.numbered() && (a == b || b == c))
            std::abort();
        if (!name.numbered() && (a != b || a != c))
            std::abort();
    } catch (const raypc::Error&) {
    }
    return 0;
}
