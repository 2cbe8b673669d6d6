// Access rules of docs/protocol.md: the token required off loopback, the Host and Origin checks
// against other web sites, and which static files may be served. No network types; everything here
// is tested on its own.
//
// Thread safety: all functions are reentrant.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace raypc::server {

// True for 127.0.0.0/8, ::1 and "localhost": the names a Host header may give on loopback.
bool isLoopbackHost(std::string_view host);

// True for the listening addresses that need no token: 127.0.0.1, ::1 and "localhost" (which the
// server binds as 127.0.0.1). Every other address, 127.0.0.2 included, needs the token
// (docs/protocol.md, Access): other loopback addresses are less expected and not worth the doubt.
bool isTokenFreeListenAddress(std::string_view host);

// 32 hex digits from std::random_device.
std::string makeAccessToken();

// What a request offers as credentials (any may be empty).
struct Credentials {
    std::string target;         // request target, e.g. "/api/info?token=abc"
    std::string authorization;  // Authorization header
    std::string cookie;         // Cookie header
};
// True when `expected` is empty (no token needed) or any of the query parameter `token`, the
// header "Bearer <token>" or the cookie `raypc_token` equals it (compared in constant time).
bool tokenAccepted(const Credentials& request, const std::string& expected);

// Cross-site protection. A web page the user visits must not drive or read the server: on a loopback
// address (no token) the Host header must name a loopback host (localhost, 127.x.y.z, [::1]) or the
// host of an allowed origin, which defeats DNS rebinding; on any address, a request that carries an
// Origin header must come from the server's own origin (http or https with the authority of the Host
// header) or an allowed origin, which refuses cross-site WebSocket upgrades and cross-site simple
// POSTs. Requests without Origin (not from a browser page) pass the second check.
struct SitePolicy {
    bool loopback = true;                     // listening on a loopback address
    std::vector<std::string> allowedOrigins;  // as returned by normaliseOrigin (`--allow-origin`)
};
// "scheme://host[:port]" in lower case, scheme http or https, no path, query or user. Throws
// raypc::Error naming `what` (e.g. "--allow-origin") and the value otherwise.
std::string normaliseOrigin(std::string_view origin, std::string_view what);
// nullopt when a request with these headers (nullopt: header absent) may pass; otherwise the reason
// for answering 403, naming the header, its value and how to allow it.
std::optional<std::string> crossSiteRefusal(const SitePolicy& policy, std::optional<std::string_view> host,
                                            std::optional<std::string_view> origin);

// Splits "/a/b?x=1" into path and query.
std::string_view targetPath(std::string_view target);
std::string_view targetQuery(std::string_view target);
// The percent-decoded value of query parameter `name`, if present. Control characters (%00 …
// %1F, %7F) come back written out as \xNN: no name or number RayPC takes holds one, and a NUL
// would cut short the error message that quotes the value.
std::optional<std::string> queryParameter(std::string_view query, std::string_view name);
// Decodes %XX and (when `plusIsSpace`) '+'. Returns nullopt on a malformed escape.
std::optional<std::string> percentDecode(std::string_view text, bool plusIsSpace = false);

// The file under `root` that URL path `urlPath` (without query) names, or nullopt when it is refused:
// malformed escapes, NUL, backslashes, "." or ".." segments (also encoded), a path that resolves
// (through symlinks) outside `root`, or no regular file there. "/" and directories map to index.html.
std::optional<std::filesystem::path> resolveStaticPath(const std::filesystem::path& root, std::string_view urlPath);

// Content-Type for a file name by extension (application/octet-stream when unknown).
std::string_view mimeType(const std::filesystem::path& file);

}  // namespace raypc::server
