#include "render/legend.h"

#include "core/error.h"

#include <fmt/format.h>
#include <ft2build.h>
#include FT_FREETYPE_H
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>

namespace raypc::render {
namespace {

std::string fontPath()
{
    if (const char* env = std::getenv("RAYPC_FONT"); env && *env)
        return env;
    return "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
}

// A FreeType face at one pixel size, closed on destruction.
class Font {
public:
    explicit Font(int pixelSize)
    {
        const std::string path = fontPath();
        if (FT_Init_FreeType(&m_library))
            fail("legend: FreeType could not be initialised");
        if (!std::filesystem::is_regular_file(path) || FT_New_Face(m_library, path.c_str(), 0, &m_face)) {
            FT_Done_FreeType(m_library);
            fail("legend: cannot read the font {} (Debian package fonts-dejavu-core, or set $RAYPC_FONT)", path);
        }
        FT_Set_Pixel_Sizes(m_face, 0, FT_UInt(pixelSize));
    }
    ~Font()
    {
        FT_Done_Face(m_face);
        FT_Done_FreeType(m_library);
    }
    Font(const Font&) = delete;
    Font& operator=(const Font&) = delete;

    // Draws UTF-8 `text` with its baseline at (x, y); returns the advance in pixels. With `draw`
    // false it only measures.
    int text(std::vector<uint8_t>& rgba, int width, int height, int x, int y, const std::string& text,
             const uint8_t color[3], bool draw = true)
    {
        int pen = x;
        for (size_t i = 0; i < text.size();) {
            const char32_t c = nextCodePoint(text, i);
            if (FT_Load_Char(m_face, c, FT_LOAD_RENDER))
                continue;
            const FT_GlyphSlot g = m_face->glyph;
            if (draw)
                for (unsigned row = 0; row < g->bitmap.rows; ++row)
                    for (unsigned col = 0; col < g->bitmap.width; ++col) {
                        const int px = pen + g->bitmap_left + int(col), py = y - g->bitmap_top + int(row);
                        if (px < 0 || py < 0 || px >= width || py >= height)
                            continue;
                        const float a = g->bitmap.buffer[row * unsigned(g->bitmap.pitch) + col] / 255.0f;
                        uint8_t* p = &rgba[(size_t(py) * size_t(width) + size_t(px)) * 4];
                        for (int k = 0; k < 3; ++k)
                            p[k] = uint8_t(std::lround(p[k] * (1 - a) + color[k] * a));
                    }
            pen += int(g->advance.x >> 6);
        }
        return pen - x;
    }

private:
    static char32_t nextCodePoint(const std::string& s, size_t& i)
    {
        const auto byte = [&](size_t k) { return k < s.size() ? char32_t(uint8_t(s[k])) : char32_t(0x80); };
        const char32_t b0 = byte(i);
        if (b0 < 0x80) {
            i += 1;
            return b0;
        }
        if ((b0 >> 5) == 0x6) {
            i += 2;
            return ((b0 & 0x1F) << 6) | (byte(i - 1) & 0x3F);
        }
        if ((b0 >> 4) == 0xE) {
            i += 3;
            return ((b0 & 0x0F) << 12) | ((byte(i - 2) & 0x3F) << 6) | (byte(i - 1) & 0x3F);
        }
        i += 4;
        return ((b0 & 0x07) << 18) | ((byte(i - 3) & 0x3F) << 12) | ((byte(i - 2) & 0x3F) << 6) | (byte(i - 1) & 0x3F);
    }

    FT_Library m_library = nullptr;
    FT_Face m_face = nullptr;
};

// This thread's face at `pixelSize`, opened once: server sessions draw shell labels and legends
// into frame after frame, and opening the font file per frame is needless I/O. FreeType faces are
// not shared between threads, hence one cache per thread.
Font& cachedFont(int pixelSize)
{
    thread_local std::map<std::pair<std::string, int>, std::unique_ptr<Font>> fonts;  // by (file, size)
    std::unique_ptr<Font>& font = fonts[{fontPath(), pixelSize}];
    if (!font)
        font = std::make_unique<Font>(pixelSize);
    return *font;
}

void blend(std::vector<uint8_t>& rgba, int width, int height, int x0, int y0, int x1, int y1, const float c[3], float a)
{
    for (int y = std::max(0, y0); y < std::min(height, y1); ++y)
        for (int x = std::max(0, x0); x < std::min(width, x1); ++x) {
            uint8_t* p = &rgba[(size_t(y) * size_t(width) + size_t(x)) * 4];
            for (int k = 0; k < 3; ++k)
                p[k] = uint8_t(std::lround(p[k] * (1 - a) + c[k] * 255.0f * a));
        }
}

}  // namespace

std::string displayUnits(const std::string& units)
{
    // src/render/display_units.json, compiled in (CMake writes display_units_json.inc), read once.
    struct Table {
        std::map<std::string, std::string> symbols, superscripts;
    };
    static const Table table = [] {
        const auto j = nlohmann::json::parse(
#include "display_units_json.inc"
        );
        return Table{j.at("symbols").get<std::map<std::string, std::string>>(),
                     j.at("superscripts").get<std::map<std::string, std::string>>()};
    }();
    if (const auto it = table.symbols.find(units); it != table.symbols.end())
        return it->second;
    std::string out;
    for (size_t i = 0; i < units.size(); ++i) {
        const auto sup = units[i] == '^' && i + 1 < units.size() ? table.superscripts.find(units.substr(i + 1, 1))
                                                                 : table.superscripts.end();
        if (sup != table.superscripts.end()) {
            out += sup->second;
            ++i;
        } else {
            out += units[i];
        }
    }
    return out;
}

std::string legendNumber(double v)
{
    const double m = std::abs(v);
    if (v == 0)
        return "0";
    if (m >= 1e5 || m < 1e-2)
        return fmt::format("{:.2e}", v);
    return fmt::format("{:.4g}", v);
}

namespace {

// The legends' font size for a picture: readable at 512 px, not dominant at 4K.
// The height of one legend's panel (title, bar, values) for the text size.
int legendBlockPx(int fontPx)
{
    const int pad = fontPx / 2, barH = std::max(6, fontPx * 3 / 4);
    return pad + fontPx + pad / 2 + barH + pad / 2 + fontPx + pad;
}

}  // namespace

// At least 12 px: legible in the UI's panes, where a picture's pixel is a CSS pixel (maps, sections,
// time–depth pictures a few hundred pixels high).
int legendFontPx(int width, int height)
{
    const int side = std::min(width, height);
    return std::clamp(side / 36, side < 120 ? 10 : 12, 48);
}

int legendBarPx(int width, int height)
{
    const int fontPx = legendFontPx(width, height);
    return std::clamp(width / 4, 8 * fontPx, 20 * fontPx);
}

int legendTextWidthPx(const std::string& text, int fontPx)
{
    std::vector<uint8_t> none;
    const uint8_t white[3] = {255, 255, 255};
    return cachedFont(fontPx).text(none, 0, 0, 0, 0, text, white, false);
}

int tickLabelLeftPx(float at, int labelPx, int barPx)
{
    return std::clamp(int(std::lround(at * float(barPx))) - labelPx / 2, 0, std::max(0, barPx - labelPx));
}

namespace {

// The smallest of 1, 2, 5 × 10^k at least `raw`.
double roundStep(double raw)
{
    const double base = std::pow(10.0, std::floor(std::log10(raw)));
    for (const double m : {1.0, 2.0, 5.0, 10.0})
        if (m * base >= raw * (1 - 1e-9))
            return m * base;
    return 10 * base;
}

// A tick's text: as many decimals as the step between ticks needs; exponent form for very large
// or small values (legendNumber's rule).
std::string tickText(double v, double step)
{
    if (std::abs(v) < step * 1e-6)
        return "0";
    const double m = std::abs(v);
    if (m >= 1e5 || m < 1e-2)
        return fmt::format("{:.3g}", v);
    const int decimals = std::max(0, -int(std::floor(std::log10(step) + 1e-9)));
    return fmt::format("{:.{}f}", v, decimals);
}

}  // namespace

std::vector<LegendSpec::Tick> colorBarTicks(const TransferFunction& colors, int barPx, int gapPx,
                                            const std::function<int(const std::string&)>& textWidthPx)
{
    const double lo = std::min(colors.range.min, colors.range.max), hi = std::max(colors.range.min, colors.range.max);
    const bool log = colors.logScale && lo > 0;
    // Position along the bar of a value (the bar runs from range.min to range.max, as drawn).
    const auto at = [&](double v) {
        const double u = log ? std::log(v / colors.range.min) / std::log(double(colors.range.max) / colors.range.min)
                             : (v - colors.range.min) / (double(colors.range.max) - colors.range.min);
        return float(u);
    };
    if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi))
        return {{0.5f, legendNumber(lo)}};
    // The ticks fit: labels inside the bar and `gapPx` apart, in order along it.
    const auto fits = [&](std::vector<LegendSpec::Tick>& ticks) {
        std::sort(ticks.begin(), ticks.end(), [](const auto& a, const auto& b) { return a.at < b.at; });
        int right = -1 << 20;
        for (const LegendSpec::Tick& t : ticks) {
            const int w = textWidthPx(t.text);
            if (w > barPx)
                return false;
            const int left = tickLabelLeftPx(t.at, w, barPx);
            if (left < right + gapPx)
                return false;
            right = left + w;
        }
        return !ticks.empty();
    };
    if (log && std::log10(hi / lo) >= 1) {
        // Powers of ten, every k-th decade.
        const int d0 = int(std::ceil(std::log10(lo) - 1e-9)), d1 = int(std::floor(std::log10(hi) + 1e-9));
        for (int every = 1; every <= std::max(1, d1 - d0); ++every) {
            std::vector<LegendSpec::Tick> ticks;
            for (int d = d0; d <= d1; d += every)
                ticks.push_back({at(std::pow(10.0, d)), fmt::format("{:g}", std::pow(10.0, d))});
            if (ticks.size() <= 6 && fits(ticks))
                return ticks;
        }
    }
    // Steps of 1, 2 or 5 × 10^k from the finest that gives at most 6 values, each also with every
    // other value (multiples of twice the step: -400, 0, 400 where -400 … 400 by 200 is too dense):
    // the first that fits with two values or more, else the first that fits with one.
    std::vector<LegendSpec::Tick> single;
    for (double step = roundStep((hi - lo) / 6); step <= 2 * (hi - lo); step = roundStep(step * 1.5)) {
        for (const int every : {1, 2}) {
            const double s = step * every;
            std::vector<LegendSpec::Tick> ticks;
            // (a millionth of the span of slack: a float range's 0.99 is 0.9900000095)
            const double slack = 1e-6 * (hi - lo);
            for (double k = std::ceil((lo - slack) / s); k * s <= hi + slack; k += 1) {
                const double v = k * s;
                if (log && v <= 0)
                    continue;
                ticks.push_back({std::clamp(at(v), 0.0f, 1.0f), tickText(v, s)});
            }
            if (ticks.size() > 6 || !fits(ticks))
                continue;
            if (ticks.size() >= 2)
                return ticks;
            if (single.empty())
                single = ticks;
        }
    }
    if (!single.empty())
        return single;
    return {{at(log ? std::sqrt(lo * hi) : (lo + hi) / 2), legendNumber(log ? std::sqrt(lo * hi) : (lo + hi) / 2)}};
}

int legendsHeightPx(int width, int height, size_t count)
{
    if (count == 0)
        return 0;
    const int fontPx = legendFontPx(width, height);
    return fontPx + int(count) * (legendBlockPx(fontPx) + fontPx / 2);
}

int labelFontPx(int width, int height) { return std::max(12, legendFontPx(width, height) * 5 / 6); }

void drawTextLabels(std::vector<uint8_t>& rgba, int width, int height, std::span<const TextLabel> labels)
{
    if (labels.empty())
        return;
    if (rgba.size() != size_t(width) * size_t(height) * 4)
        fail("labels: image of {} bytes for {}x{} pixels", rgba.size(), width, height);
    const int fontPx = labelFontPx(width, height);
    Font& font = cachedFont(fontPx);
    const int pad = std::max(2, fontPx / 4);
    const float panel[3] = {0.05f, 0.06f, 0.08f};
    for (const TextLabel& l : labels) {
        const uint8_t c[3] = {uint8_t(std::lround(std::clamp(l.color.r, 0.0f, 1.0f) * 255)),
                              uint8_t(std::lround(std::clamp(l.color.g, 0.0f, 1.0f) * 255)),
                              uint8_t(std::lround(std::clamp(l.color.b, 0.0f, 1.0f) * 255))};
        const int w = font.text(rgba, width, height, 0, 0, l.text, c, false);
        const int left = int(std::lround(l.x)) - (l.rightAligned ? w + pad : w / 2), top = int(std::lround(l.y)) - fontPx / 2 - pad;
        blend(rgba, width, height, left - pad, top, left + w + pad, top + fontPx + 2 * pad, panel, 0.7f);
        font.text(rgba, width, height, left, top + pad + fontPx * 4 / 5, l.text, c);
    }
}

void drawLegends(std::vector<uint8_t>& rgba, int width, int height, std::span<const LegendSpec> legends,
                 std::span<const TextLabel> shellKey, int leftPx)
{
    if (legends.empty() && shellKey.empty())
        return;
    if (rgba.size() != size_t(width) * size_t(height) * 4)
        fail("legend: image of {} bytes for {}x{} pixels", rgba.size(), width, height);
    // Sizes follow the picture: readable at 512 px, not dominant at 4K.
    const int fontPx = legendFontPx(width, height);
    Font& font = cachedFont(fontPx);
    const int margin = fontPx, pad = fontPx / 2;
    const int barW = legendBarPx(width, height), barH = std::max(6, fontPx * 3 / 4);
    const int blockH = legendBlockPx(fontPx);
    const uint8_t white[3] = {235, 235, 235};
    const float panel[3] = {0.05f, 0.06f, 0.08f};
    for (size_t n = 0; n < legends.size(); ++n) {
        const LegendSpec& l = legends[n];
        const int top = height - margin - int(legends.size() - n) * (blockH + pad);
        const int left = leftPx >= 0 ? leftPx : margin;
        const int titleW = font.text(rgba, width, height, 0, 0, l.title, white, false);
        const int panelW = std::max(barW, titleW) + 2 * pad;
        blend(rgba, width, height, left, top, left + panelW, top + blockH, panel, 0.6f);
        int y = top + pad + fontPx * 4 / 5;
        font.text(rgba, width, height, left + pad, y, l.title, white);
        const int barTop = top + pad + fontPx + pad / 2;
        // The value at a position along the bar (logarithmic with a log scale), as the renderer maps it.
        const TransferFunction& tf = l.colors;
        auto valueAt = [&](double u) {
            return tf.logScale ? tf.range.min * std::pow(double(tf.range.max) / tf.range.min, u)
                               : tf.range.min + u * (double(tf.range.max) - tf.range.min);
        };
        for (int x = 0; x < barW; ++x) {
            const Rgb c = tf.colorOf(float(valueAt((float(x) + 0.5f) / float(barW))));
            const float cc[3] = {c.r, c.g, c.b};
            blend(rgba, width, height, left + pad + x, barTop, left + pad + x + 1, barTop + barH, cc, 1.0f);
        }
        y = barTop + barH + pad / 2 + fontPx * 4 / 5;
        // Categories' labels as given; a variable's round values, each with a mark under the bar.
        const bool values = l.ticks.empty();
        const std::vector<LegendSpec::Tick> ticks =
            values ? colorBarTicks(tf, barW, std::max(4, fontPx / 2), [&](const std::string& t) { return font.text(rgba, width, height, 0, 0, t, white, false); })
                   : l.ticks;
        const float markColor[3] = {0.92f, 0.92f, 0.92f};
        for (const LegendSpec::Tick& t : ticks) {
            const int tw = font.text(rgba, width, height, 0, 0, t.text, white, false);
            font.text(rgba, width, height, left + pad + tickLabelLeftPx(t.at, tw, barW), y, t.text, white);
            if (values) {
                const int x = left + pad + std::clamp(int(std::lround(t.at * float(barW))), 0, barW - 1);
                blend(rgba, width, height, x, barTop + barH, x + std::max(1, fontPx / 12), barTop + barH + std::max(2, pad / 2), markColor, 1.0f);
            }
        }
    }
    if (shellKey.empty())
        return;
    // The shells' key: "shells" and a swatch of each shell's colour before its depth, in one row
    // above the colour bars.
    const int keyH = pad + fontPx + pad;
    const int top = height - margin - int(legends.size()) * (blockH + pad) - keyH - pad;
    const int left = leftPx >= 0 ? leftPx : margin, swatchW = fontPx, gap = fontPx / 2;
    int rowW = font.text(rgba, width, height, 0, 0, "shells", white, false);
    for (const TextLabel& k : shellKey)
        rowW += gap + swatchW + pad / 2 + font.text(rgba, width, height, 0, 0, k.text, white, false);
    blend(rgba, width, height, left, top, left + rowW + 2 * pad, top + keyH, panel, 0.6f);
    const int baseline = top + pad + fontPx * 4 / 5;
    int x = left + pad + font.text(rgba, width, height, left + pad, baseline, "shells", white);
    for (const TextLabel& k : shellKey) {
        x += gap;
        const float c[3] = {k.color.r, k.color.g, k.color.b};
        const int mid = top + keyH / 2, thick = std::max(2, fontPx / 5);
        blend(rgba, width, height, x, mid - thick / 2, x + swatchW, mid - thick / 2 + thick, c, 1.0f);
        x += swatchW + pad / 2;
        x += font.text(rgba, width, height, x, baseline, k.text, white);
    }
}

}  // namespace raypc::render
