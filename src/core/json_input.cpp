#include "core/json_input.h"

#include "core/error.h"

namespace raypc {

namespace {

// The byte at which `text` first nests deeper than `maxDepth` arrays and objects, or npos. Brackets
// inside strings do not count; the text need not be valid JSON (the parser says what else is wrong).
size_t tooDeepAt(std::string_view text, int maxDepth)
{
    int depth = 0;
    bool inString = false;
    for (size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (inString) {
            if (c == '\\')
                ++i;  // the escaped character, whatever it is
            else if (c == '"')
                inString = false;
        } else if (c == '"') {
            inString = true;
        } else if (c == '[' || c == '{') {
            if (++depth > maxDepth)
                return i;
        } else if (c == ']' || c == '}') {
            --depth;
        }
    }
    return std::string_view::npos;
}

}  // namespace

nlohmann::json parseJsonInput(std::string_view text, const std::string& what)
{
    if (const size_t at = tooDeepAt(text, kMaxJsonDepth); at != std::string_view::npos)
        fail("{}: JSON nested deeper than {} levels (at byte {})", what, kMaxJsonDepth, at);
    try {
        return nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {  // parse_error, or out_of_range for 1e999
        fail("{}: not valid JSON: {}", what, e.what());
    }
}

std::string jsonExcerpt(const nlohmann::json& value, size_t maxChars)
{
    std::string text = value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    if (text.size() <= maxChars)
        return text;
    // Cut at a character boundary of UTF-8 (not inside a multi-byte sequence).
    size_t cut = maxChars;
    while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80)
        --cut;
    text.resize(cut);
    return text + "…";
}

}  // namespace raypc
