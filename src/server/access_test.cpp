#include "server/access.h"

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

TEST(MimeTypes, ByExtension)
{
    EXPECT_EQ(mimeType("a/index.html"), "text/html; charset=utf-8");
    EXPECT_EQ(mimeType("app.js"), "text/javascript; charset=utf-8");
    EXPECT_EQ(mimeType("x.wasm"), "application/wasm");
    EXPECT_EQ(mimeType("blob"), "application/octet-stream");
}

}  // namespace
}  // namespace raypc::server
