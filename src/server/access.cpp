#include "server/access.h"

#include "core/error.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <random>
#include <system_error>

namespace raypc::server {

namespace fs = std::filesystem;

bool isLoopbackHost(std::string_view host)
{
    if (host == "localhost" || host == "::1" || host == "[::1]")
        return true;
    // 127.x.y.z: four dotted decimal numbers starting with 127.
    if (!host.starts_with("127."))
        return false;
    int dots = 0, digits = 0;
    for (char c : host.substr(4)) {
        if (c == '.') {
            if (digits == 0)
                return false;
            ++dots;
            digits = 0;
        } else if (c >= '0' && c <= '9' && digits < 3) {
            ++digits;
        } else {
            return false;
        }
    }
    return dots == 2 && digits > 0;
}

bool isTokenFreeListenAddress(std::string_view host)
{
    return host == "127.0.0.1" || host == "localhost" || host == "::1" || host == "[::1]";
}

std::string makeAccessToken()
{
    std::random_device device;
    static constexpr char kHex[] = "0123456789abcdef";
    std::string token;
    for (int i = 0; i < 32; ++i)
        token.push_back(kHex[device() & 15u]);
    return token;
}

namespace {

bool constantTimeEqual(std::string_view a, std::string_view b)
{
    if (a.size() != b.size())
        return false;
    unsigned diff = 0;
    for (size_t i = 0; i < a.size(); ++i)
        diff |= unsigned(uint8_t(a[i]) ^ uint8_t(b[i]));
    return diff == 0;
}

std::string_view trimSpaces(std::string_view s)
{
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t'))
        s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t'))
        s.remove_suffix(1);
    return s;
}

int hexValue(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

std::string lowerCase(std::string_view s)
{
    std::string out(s);
    std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return out;
}

// The host name of a Host header or URL authority "host[:port]" / "[v6]:port", lower case. An
// authority of another form ("127.0.0.1:1@evil.example", a port that is not a number, characters
// no host name has) comes back whole, so that it matches no host name.
std::string hostName(std::string_view authority)
{
    std::string_view host = authority, rest;
    if (authority.starts_with('[')) {
        const size_t close = authority.find(']');
        if (close == std::string_view::npos)
            return lowerCase(authority);
        host = authority.substr(0, close + 1);
        rest = authority.substr(close + 1);
        const bool v6 = std::all_of(host.begin() + 1, host.end() - 1,
                                    [](char c) { return std::isxdigit(static_cast<unsigned char>(c)) || c == ':' || c == '.'; });
        if (!v6)
            return lowerCase(authority);
    } else {
        const size_t colon = authority.rfind(':');
        if (colon != std::string_view::npos) {
            host = authority.substr(0, colon);
            rest = authority.substr(colon);
        }
        const bool name = std::all_of(host.begin(), host.end(), [](char c) {
            return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-';
        });
        if (!name)
            return lowerCase(authority);
    }
    if (!rest.empty()) {
        const std::string_view port = rest.substr(1);
        if (rest[0] != ':' || port.empty() || port.size() > 5 ||
            !std::all_of(port.begin(), port.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); }))
            return lowerCase(authority);
    }
    return lowerCase(host);
}

// "scheme://authority" split, or nullopt when `origin` is not of that form.
std::optional<std::pair<std::string, std::string>> splitOrigin(std::string_view origin)
{
    const size_t sep = origin.find("://");
    if (sep == std::string_view::npos || sep == 0)
        return std::nullopt;
    const std::string scheme = lowerCase(origin.substr(0, sep));
    const std::string authority = lowerCase(origin.substr(sep + 3));
    if ((scheme != "http" && scheme != "https") || authority.empty() ||
        authority.find_first_of("/?#@ \t") != std::string::npos)
        return std::nullopt;
    return std::pair(scheme, authority);
}

}  // namespace

std::string normaliseOrigin(std::string_view origin, std::string_view what)
{
    std::string_view text = origin;
    if (text.ends_with('/'))
        text.remove_suffix(1);  // "http://host:8080/" as copied from an address bar
    const auto parts = splitOrigin(text);
    if (!parts)
        fail("{} '{}': expected an origin such as http://host:8080 (http or https, no path)", what,
             std::string(origin.substr(0, 200)));
    return parts->first + "://" + parts->second;
}

std::optional<std::string> crossSiteRefusal(const SitePolicy& policy, std::optional<std::string_view> host,
                                            std::optional<std::string_view> origin)
{
    auto allowedHost = [&](const std::string& name) {
        return std::any_of(policy.allowedOrigins.begin(), policy.allowedOrigins.end(),
                           [&](const std::string& o) { return hostName(o.substr(o.find("://") + 3)) == name; });
    };
    if (policy.loopback && host) {
        const std::string name = hostName(*host);
        if (!isLoopbackHost(name) && !allowedHost(name))
            return "Host '" + std::string(host->substr(0, 200)) +
                   "' is not a loopback name: refused as a possible DNS-rebinding attack (this server answers "
                   "localhost, 127.0.0.1 and [::1]; allow another name with --allow-origin)";
    }
    if (!origin)
        return std::nullopt;
    const std::string shown(origin->substr(0, 200));
    if (const auto parts = splitOrigin(*origin)) {
        const std::string normalised = parts->first + "://" + parts->second;
        if (std::find(policy.allowedOrigins.begin(), policy.allowedOrigins.end(), normalised) !=
            policy.allowedOrigins.end())
            return std::nullopt;
        if (host && parts->second == lowerCase(*host))
            return std::nullopt;  // the server's own page
    }
    return "Origin '" + shown + "' is not this server's origin" +
           (host ? " (http://" + std::string(host->substr(0, 200)) + ")" : std::string(" (no Host header)")) +
           ": cross-site request refused; allow a trusted page with --allow-origin";
}

std::string_view targetPath(std::string_view target)
{
    return target.substr(0, target.find('?'));
}

std::string_view targetQuery(std::string_view target)
{
    const size_t q = target.find('?');
    return q == std::string_view::npos ? std::string_view() : target.substr(q + 1);
}

std::optional<std::string> percentDecode(std::string_view text, bool plusIsSpace)
{
    std::string out;
    out.reserve(text.size());
    for (size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (c == '%') {
            if (i + 2 >= text.size())
                return std::nullopt;
            const int hi = hexValue(text[i + 1]), lo = hexValue(text[i + 2]);
            if (hi < 0 || lo < 0)
                return std::nullopt;
            out.push_back(char(hi * 16 + lo));
            i += 2;
        } else if (c == '+' && plusIsSpace) {
            out.push_back(' ');
        } else {
            out.push_back(c);
        }
    }
    return out;
}

std::optional<std::string> queryParameter(std::string_view query, std::string_view name)
{
    while (!query.empty()) {
        const size_t amp = query.find('&');
        const std::string_view pair = query.substr(0, amp);
        const size_t eq = pair.find('=');
        const auto key = percentDecode(pair.substr(0, eq), true);
        if (key && *key == name) {
            if (eq == std::string_view::npos)
                return std::string();
            const auto value = percentDecode(pair.substr(eq + 1), true);
            if (!value)
                return value;
            std::string shown;
            for (const char c : *value)
                shown += (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
                             ? fmt::format("\\x{:02X}", static_cast<unsigned>(static_cast<unsigned char>(c)))
                             : std::string(1, c);
            return shown;
        }
        if (amp == std::string_view::npos)
            break;
        query.remove_prefix(amp + 1);
    }
    return std::nullopt;
}

bool tokenAccepted(const Credentials& request, const std::string& expected)
{
    if (expected.empty())
        return true;
    if (const auto t = queryParameter(targetQuery(request.target), "token"); t && constantTimeEqual(*t, expected))
        return true;
    if (std::string_view auth = trimSpaces(request.authorization); auth.starts_with("Bearer ")) {
        if (constantTimeEqual(trimSpaces(auth.substr(7)), expected))
            return true;
    }
    std::string_view cookies = request.cookie;
    while (!cookies.empty()) {
        const size_t semi = cookies.find(';');
        const std::string_view item = trimSpaces(cookies.substr(0, semi));
        if (item.starts_with("raypc_token=") && constantTimeEqual(item.substr(12), expected))
            return true;
        if (semi == std::string_view::npos)
            break;
        cookies.remove_prefix(semi + 1);
    }
    return false;
}

std::optional<fs::path> resolveStaticPath(const fs::path& root, std::string_view urlPath)
{
    if (!urlPath.starts_with('/'))
        return std::nullopt;
    const auto decoded = percentDecode(urlPath);
    if (!decoded)
        return std::nullopt;
    const std::string& p = *decoded;
    // Refuse anything that could name a file outside the root or confuse a later layer.
    if (p.find('\0') != std::string::npos || p.find('\\') != std::string::npos || p.starts_with("//") ||
        p.find(':') != std::string::npos)
        return std::nullopt;
    fs::path relative;
    size_t start = 1;
    while (start <= p.size()) {
        size_t end = p.find('/', start);
        if (end == std::string::npos)
            end = p.size();
        const std::string_view segment = std::string_view(p).substr(start, end - start);
        if (segment == "." || segment == "..")
            return std::nullopt;
        if (!segment.empty())
            relative /= fs::path(std::string(segment));
        start = end + 1;
    }
    std::error_code ec;
    const fs::path base = fs::weakly_canonical(root, ec);
    if (ec)
        return std::nullopt;
    fs::path file = base / relative;
    if (fs::is_directory(file, ec))
        file /= "index.html";
    const fs::path real = fs::weakly_canonical(file, ec);
    if (ec)
        return std::nullopt;
    // The resolved file must still lie below the root (a symlink may point elsewhere).
    const auto [rootEnd, fileIt] = std::mismatch(base.begin(), base.end(), real.begin(), real.end());
    if (rootEnd != base.end())
        return std::nullopt;
    if (!fs::is_regular_file(real, ec))
        return std::nullopt;
    return real;
}

std::string_view mimeType(const fs::path& file)
{
    static const std::array<std::pair<std::string_view, std::string_view>, 14> kTypes{{
        {".html", "text/html; charset=utf-8"},
        {".htm", "text/html; charset=utf-8"},
        {".js", "text/javascript; charset=utf-8"},
        {".mjs", "text/javascript; charset=utf-8"},
        {".css", "text/css; charset=utf-8"},
        {".json", "application/json"},
        {".map", "application/json"},
        {".png", "image/png"},
        {".jpg", "image/jpeg"},
        {".svg", "image/svg+xml"},
        {".ico", "image/x-icon"},
        {".wasm", "application/wasm"},
        {".woff2", "font/woff2"},
        {".txt", "text/plain; charset=utf-8"},
    }};
    const std::string ext = file.extension().string();
    for (const auto& [e, type] : kTypes)
        if (ext == e)
            return type;
    return "application/octet-stream";
}

}  // namespace raypc::server
