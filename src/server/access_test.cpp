#include "server/access.h"

#include "core/error.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace raypc::server {
namespace {

namespace fs = std::filesystem;

TEST(Token, LoopbackNeedsNoToken)
{
    EXPECT_TRUE(isLoopbackHost("127.0.0.1"));
    EXPECT_TRUE(isLoopbackHost("127.1.2.3"));
    EXPECT_TRUE(isLoopbackHost("::1"));
    EXPECT_TRUE(isLoopbackHost("localhost"));
    EXPECT_FALSE(isLoopbackHost("0.0.0.0"));
    EXPECT_FALSE(isLoopbackHost("::"));
    EXPECT_FALSE(isLoopbackHost("192.168.1.4"));
    EXPECT_FALSE(isLoopbackHost("127.0.0.1.evil.com"));
    EXPECT_FALSE(isLoopbackHost("1270.0.0.1"));
}

TEST(Token, OnlyTheTwoLoopbackAddressesNeedNoToken)
{
    // Only the two loopback addresses go without a token: --host 127.0.0.2 once answered without one.
    for (const char* host : {"127.0.0.1", "::1", "[::1]", "localhost"})
        EXPECT_TRUE(isTokenFreeListenAddress(host)) << host;
    for (const char* host : {"127.0.0.2", "127.1.2.3", "0.0.0.0", "::", "192.168.1.4", "127.0.0.1.evil.com", ""})
        EXPECT_FALSE(isTokenFreeListenAddress(host)) << host;
}

TEST(Token, RandomHex)
{
    const std::string a = makeAccessToken(), b = makeAccessToken();
    EXPECT_EQ(a.size(), 32u);
    EXPECT_NE(a, b);
    EXPECT_EQ(a.find_first_not_of("0123456789abcdef"), std::string::npos);
}

TEST(Token, AcceptedFromQueryHeaderOrCookieOnly)
{
    const std::string t = "0123456789abcdef0123456789abcdef";
    EXPECT_TRUE(tokenAccepted({"/api/info", "", ""}, ""));  // no token configured
    EXPECT_FALSE(tokenAccepted({"/api/info", "", ""}, t));
    EXPECT_TRUE(tokenAccepted({"/api/info?token=" + t, "", ""}, t));
    EXPECT_TRUE(tokenAccepted({"/?a=1&token=" + t + "&b=2", "", ""}, t));
    EXPECT_FALSE(tokenAccepted({"/api/info?token=" + t.substr(1), "", ""}, t));
    EXPECT_FALSE(tokenAccepted({"/api/info?token=" + t + "0", "", ""}, t));
    EXPECT_FALSE(tokenAccepted({"/api/info?xtoken=" + t, "", ""}, t));
    EXPECT_FALSE(tokenAccepted({"/api/info?token=", "", ""}, t));
    EXPECT_TRUE(tokenAccepted({"/api/info", "Bearer " + t, ""}, t));
    EXPECT_FALSE(tokenAccepted({"/api/info", "Basic " + t, ""}, t));
    EXPECT_FALSE(tokenAccepted({"/api/info", t, ""}, t));
    EXPECT_TRUE(tokenAccepted({"/api/info", "", "a=b; raypc_token=" + t}, t));
    EXPECT_FALSE(tokenAccepted({"/api/info", "", "raypc_token=nope; other=" + t}, t));
}

TEST(QueryParameters, DecodeAndSplit)
{
    EXPECT_EQ(targetPath("/a/b?x=1"), "/a/b");
    EXPECT_EQ(targetQuery("/a/b?x=1"), "x=1");
    EXPECT_EQ(targetQuery("/a/b"), "");
    EXPECT_EQ(queryParameter("step=3&var=temperature+anomaly", "var"), "temperature anomaly");
    EXPECT_EQ(queryParameter("var=radial%20velocity", "var"), "radial velocity");
    EXPECT_FALSE(queryParameter("step=3", "var"));
    // A NUL or another control character is written out, so that a message quoting it is whole.
    EXPECT_EQ(queryParameter("job=ab%00cd&x=1", "job"), "ab\\x00cd");
    EXPECT_EQ(queryParameter("job=a%0Ab%7F", "job"), "a\\x0Ab\\x7F");
    EXPECT_FALSE(percentDecode("%2"));
    EXPECT_FALSE(percentDecode("%zz"));
    EXPECT_EQ(percentDecode("%2e%2E"), "..");
}

class StaticPaths : public ::testing::Test {
protected:
    void SetUp() override
    {
        base = fs::temp_directory_path() / ("raypc_static_" + std::to_string(::getpid()));
        fs::remove_all(base);
        fs::create_directories(base / "dist" / "assets");
        fs::create_directories(base / "dist" / "sub");
        std::ofstream(base / "dist" / "index.html") << "<html>";
        std::ofstream(base / "dist" / "assets" / "app.js") << "js";
        std::ofstream(base / "dist" / "sub" / "index.html") << "sub";
        std::ofstream(base / "secret.txt") << "secret";
        fs::create_symlink(base / "secret.txt", base / "dist" / "link.txt");
        root = base / "dist";
    }
    void TearDown() override { fs::remove_all(base); }
    fs::path base, root;
};

TEST_F(StaticPaths, ServesFilesInsideTheRoot)
{
    EXPECT_EQ(resolveStaticPath(root, "/"), fs::canonical(root / "index.html"));
    EXPECT_EQ(resolveStaticPath(root, "/index.html"), fs::canonical(root / "index.html"));
    EXPECT_EQ(resolveStaticPath(root, "/assets/app.js"), fs::canonical(root / "assets" / "app.js"));
    EXPECT_EQ(resolveStaticPath(root, "/assets//app.js"), fs::canonical(root / "assets" / "app.js"));
    EXPECT_EQ(resolveStaticPath(root, "/%61ssets/app.js"), fs::canonical(root / "assets" / "app.js"));
    EXPECT_EQ(resolveStaticPath(root, "/sub/"), fs::canonical(root / "sub" / "index.html"));
    EXPECT_FALSE(resolveStaticPath(root, "/missing.js"));
    EXPECT_FALSE(resolveStaticPath(root, "/assets"));  // a directory without index.html
}

TEST_F(StaticPaths, RefusesEscapes)
{
    for (const char* bad : {"/../secret.txt", "/assets/../../secret.txt", "/%2e%2e/secret.txt", "/%2E%2E/secret.txt",
                            "/.%2e/secret.txt", "/assets/%2e%2e/%2e%2e/secret.txt", "/..%2fsecret.txt",
                            "/..%5csecret.txt", "/..\\secret.txt", "/assets\\..\\..\\secret.txt", "//etc/passwd",
                            "/%2fetc/passwd", "/index.html%00.js", "/./index.html", "/link.txt", "etc/passwd",
                            "/%zz", "/C:/Windows/win.ini"}) {
        EXPECT_FALSE(resolveStaticPath(root, bad)) << bad;
    }
    // An absolute path as target never reaches outside either.
    const std::string absolute = (base / "secret.txt").string();
    const auto r = resolveStaticPath(root, absolute);
    EXPECT_FALSE(r) << absolute;
}

// DNS rebinding: a page of evil.example whose name now resolves to 127.0.0.1 sends Host: evil.example.
TEST(CrossSite, LoopbackAnswersOnlyLoopbackHostNames)
{
    const SitePolicy loopback{true, {}};
    for (const char* host : {"127.0.0.1:8080", "localhost:8080", "LOCALHOST", "[::1]:8080", "127.0.0.1", "127.3.4.5:1"})
        EXPECT_FALSE(crossSiteRefusal(loopback, host, std::nullopt)) << host;
    for (const char* host : {"evil.example", "evil.example:8080", "127.0.0.1.evil.example:8080", "localhost.evil:8080",
                             "192.168.1.2:8080", "[::2]:8080", "", "127.0.0.1:1@evil.example",
                             "127.0.0.1:80/x", "localhost:abc", "[::1]x", "127.0.0.1 :8080"}) {
        const auto why = crossSiteRefusal(loopback, host, std::nullopt);
        ASSERT_TRUE(why) << host;
        EXPECT_NE(why->find("Host '" + std::string(host) + "'"), std::string::npos) << *why;
        EXPECT_NE(why->find("DNS-rebinding"), std::string::npos) << *why;
    }
    EXPECT_FALSE(crossSiteRefusal(loopback, std::nullopt, std::nullopt)) << "no Host: not a browser";
    // Off loopback the token guards; any Host name may reach the machine.
    EXPECT_FALSE(crossSiteRefusal(SitePolicy{false, {}}, "evil.example:8080", std::nullopt));
    // An allowed origin's host is a name of this server (a proxy or an /etc/hosts alias).
    const SitePolicy alias{true, {normaliseOrigin("http://viz.lab:8080", "--allow-origin")}};
    EXPECT_FALSE(crossSiteRefusal(alias, "viz.lab:8080", std::nullopt));
    EXPECT_TRUE(crossSiteRefusal(alias, "evil.example:8080", std::nullopt));
}

TEST(CrossSite, OriginMustBeTheServersOwnOrAllowed)
{
    for (const bool loopback : {true, false}) {
        const SitePolicy policy{loopback, {normaliseOrigin("https://Proxy.Example/", "--allow-origin")}};
        // The server's own page, under each of its names.
        EXPECT_FALSE(crossSiteRefusal(policy, "127.0.0.1:8080", "http://127.0.0.1:8080"));
        EXPECT_FALSE(crossSiteRefusal(policy, "localhost:8080", "http://localhost:8080"));
        EXPECT_FALSE(crossSiteRefusal(policy, "localhost:8080", "HTTP://LocalHost:8080"));
        EXPECT_FALSE(crossSiteRefusal(policy, "127.0.0.1:8080", "https://proxy.example"));
        for (const char* origin : {"http://evil.example", "http://127.0.0.1:9999", "http://localhost:8080",
                                   "null", "", "file://", "http://127.0.0.1:8080/path", "ftp://127.0.0.1:8080",
                                   "http://127.0.0.1:8080@evil.example"}) {
            const auto why = crossSiteRefusal(policy, "127.0.0.1:8080", origin);
            ASSERT_TRUE(why) << origin;
            EXPECT_NE(why->find("Origin '" + std::string(origin) + "'"), std::string::npos) << *why;
            EXPECT_NE(why->find("--allow-origin"), std::string::npos) << *why;
        }
        EXPECT_TRUE(crossSiteRefusal(policy, std::nullopt, "http://127.0.0.1:8080")) << "nothing to compare with";
    }
}

TEST(CrossSite, AllowOriginValuesAreCheckedAndNormalised)
{
    EXPECT_EQ(normaliseOrigin("HTTP://Viz.Lab:8080/", "--allow-origin"), "http://viz.lab:8080");
    EXPECT_EQ(normaliseOrigin("https://a.b", "--allow-origin"), "https://a.b");
    for (const char* bad : {"viz.lab:8080", "ftp://a.b", "http://", "http://a.b/path", "http://u@a.b", "*", ""}) {
        try {
            normaliseOrigin(bad, "--allow-origin");
            ADD_FAILURE() << bad << " accepted";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("--allow-origin '" + std::string(bad) + "'"), std::string::npos)
                << e.what();
        }
    }
}

TEST(MimeTypes, ByExtension)
{
    EXPECT_EQ(mimeType("a/index.html"), "text/html; charset=utf-8");
    EXPECT_EQ(mimeType("app.js"), "text/javascript; charset=utf-8");
    EXPECT_EQ(mimeType("x.wasm"), "application/wasm");
    EXPECT_EQ(mimeType("blob"), "application/octet-stream");
}

}  // namespace
}  // namespace raypc::server
