#include "core/atomic_file.h"
#include "core/error.h"
#include "core/huge_pages.h"
#include "core/json_input.h"
#include "core/lru_cache.h"
#include "core/mapped_file.h"
#include "core/numbered_name.h"
#include "core/spare_blocks.h"
#include "core/spherical.h"
#include "core/strings.h"
#include "core/system_memory.h"

#include <gtest/gtest.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <vector>
#include <thread>
#include <chrono>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <filesystem>
#include <fstream>
#include <optional>
#include <span>
#include <sstream>
#include <string>

namespace raypc {
namespace {

TEST(LruCache, KeepsTheMostRecentlyUsedAndCachesNoFailure)
{
    LruCache<int, std::string> cache(2);
    int made = 0;
    auto make = [&](int key) { return [&made, key] { ++made; return std::to_string(key); }; };
    const auto one = cache.get(1, make(1));
    EXPECT_EQ(*one, "1");
    EXPECT_EQ(cache.get(1, make(1)), one);  // the same shared value, not made again
    cache.get(2, make(2));
    cache.get(1, make(1));  // 1 is now the most recently used: 2 goes when 3 comes
    cache.get(3, make(3));
    EXPECT_EQ(made, 3);
    cache.get(1, make(1));
    EXPECT_EQ(made, 3);
    cache.get(2, make(2));
    EXPECT_EQ(made, 4);
    EXPECT_THROW(cache.get(5, []() -> std::string { fail("cannot read"); }), Error);
    EXPECT_EQ(*cache.get(5, make(5)), "5");  // the failure was not cached
    EXPECT_EQ(made, 5);
}

TEST(LruCache, CountsHitsAndMakingsAndEvictsTheLeastRecentlyUsed)
{
    LruCache<int, int> cache(2);
    int how = -1;
    cache.get(1, [] { return 10; }, &how);
    EXPECT_EQ(how, (LruCache<int, int>::kMade));
    EXPECT_EQ(*cache.get(1, []() -> int { ADD_FAILURE() << "made again"; return 0; }, &how), 10);
    EXPECT_EQ(how, (LruCache<int, int>::kHit));
    cache.get(2, [] { return 20; });
    cache.get(3, [] { return 30; });  // 1 was used before 2: 1 goes
    EXPECT_EQ(cache.size(), 2u);
    EXPECT_EQ(cache.find(1), nullptr);
    ASSERT_NE(cache.find(2), nullptr);
    EXPECT_EQ(*cache.find(2), 20);
    cache.put(4, std::make_shared<const int>(40));  // 2 was found last: 3 goes
    EXPECT_EQ(cache.find(3), nullptr);
    EXPECT_EQ(*cache.find(4), 40);
    const auto counts = cache.counts();
    EXPECT_EQ(counts.made, 3u);
    EXPECT_EQ(counts.hits, 1u);
    EXPECT_EQ(counts.shared, 0u);
}

// Callers that ask for a key while it is being made wait for that making instead of making it again;
// a failure reaches them all and is not cached.
TEST(LruCache, ConcurrentRequestsOfOneKeyShareOneMaking)
{
    constexpr int kThreads = 6;
    LruCache<std::string, int> cache(4);
    std::atomic<int> made{0};
    auto slowMake = [&](int value) {
        return [&, value] {
            ++made;
            // Hold the making until every other caller waits for it (counted by the cache).
            const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
            while (cache.counts().shared < size_t(kThreads - 1) && std::chrono::steady_clock::now() < until)
                std::this_thread::yield();
            if (value < 0)
                fail("cannot make {}", value);
            return value;
        };
    };
    std::vector<std::thread> threads;
    std::vector<int> got(kThreads, 0);
    for (int t = 0; t < kThreads; ++t)
        threads.emplace_back([&, t] { got[size_t(t)] = *cache.get("k", slowMake(7)); });
    for (auto& t : threads)
        t.join();
    EXPECT_EQ(made, 1);
    EXPECT_EQ(got, std::vector<int>(kThreads, 7));
    EXPECT_EQ(cache.counts().made, 1u);
    EXPECT_EQ(cache.counts().shared, size_t(kThreads - 1));

    LruCache<std::string, int> failing(4);
    std::atomic<int> failures{0};
    made = 0;
    threads.clear();
    auto failingMake = [&] {
        ++made;
        const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
        while (failing.counts().shared < size_t(kThreads - 1) && std::chrono::steady_clock::now() < until)
            std::this_thread::yield();
        fail("cannot read");
        return 0;
    };
    for (int t = 0; t < kThreads; ++t)
        threads.emplace_back([&] {
            try {
                failing.get("k", failingMake);
            } catch (const Error& e) {
                EXPECT_NE(std::string(e.what()).find("cannot read"), std::string::npos);
                ++failures;
            }
        });
    for (auto& t : threads)
        t.join();
    EXPECT_EQ(made, 1);
    EXPECT_EQ(failures, kThreads);
    EXPECT_EQ(failing.size(), 0u);
    EXPECT_EQ(*failing.get("k", [] { return 3; }), 3);
}

TEST(Strings, NaturalOrderComparesDigitRunsByValue)
{
    std::vector<std::string> names = {"spherical10.nc", "spherical2.nc", "spherical001.nc", "spherical100.nc",
                                      "a.nc"};
    std::sort(names.begin(), names.end(), [](const auto& a, const auto& b) { return naturalLess(a, b); });
    EXPECT_EQ(names, (std::vector<std::string>{"a.nc", "spherical001.nc", "spherical2.nc", "spherical10.nc",
                                               "spherical100.nc"}));
    EXPECT_FALSE(naturalLess("x2", "x2"));
}

TEST(Strings, FileSafeNames)
{
    EXPECT_EQ(fileSafeName("spin transition-induced density anomaly"), "spin_transition-induced_density_anomaly");
    EXPECT_EQ(fileSafeName("a/../b"), "a_.._b");
}

TEST(Strings, CsvQuoting)
{
    EXPECT_EQ(csvQuote("temperature [K]"), "temperature [K]");
    EXPECT_EQ(csvQuote("a,b"), "\"a,b\"");
    EXPECT_EQ(csvQuote("say \"hi\""), "\"say \"\"hi\"\"\"");
}

TEST(Spherical, CartesianRoundTripAndContestFrame)
{
    const Vec3d p = sphericalToCartesianKm(30.0, 120.0, 5000.0);
    EXPECT_NEAR(p.x, 5000 * std::cos(degToRad(30)) * std::cos(degToRad(120)), 1e-9);
    EXPECT_NEAR(p.z, 2500.0, 1e-9);
    const auto s = cartesianToSpherical(p);
    EXPECT_NEAR(s.latDeg, 30.0, 1e-9);
    EXPECT_NEAR(s.lonDeg, 120.0, 1e-9);
    EXPECT_NEAR(s.rKm, 5000.0, 1e-9);
    EXPECT_NEAR(cartesianToSpherical(sphericalToCartesianKm(-10, 350, 4000)).lonDeg, 350.0, 1e-9);
    EXPECT_DOUBLE_EQ(wrapLonDeg(-10.0), 350.0);
    EXPECT_DOUBLE_EQ(wrapLonDeg(360.0), 0.0);
    EXPECT_DOUBLE_EQ(wrapLonDeg(725.0), 5.0);
}

// The resident kB of the mapping that holds `address`, from /proc/self/smaps (-1 when not found).
long residentKbOfMapping(const void* address)
{
    std::ifstream smaps("/proc/self/smaps");
    const auto at = reinterpret_cast<uintptr_t>(address);
    bool inside = false;
    for (std::string line; std::getline(smaps, line);) {
        unsigned long begin = 0, end = 0;
        if (std::sscanf(line.c_str(), "%lx-%lx ", &begin, &end) == 2 && line.find(':') > line.find(' '))
            inside = at >= begin && at < end;
        else if (inside && line.starts_with("Rss:"))
            return std::stol(line.substr(4));
    }
    return -1;
}

// A mapping read all over counts in the process's resident memory; dropResidentPages takes it out,
// and the file reads the same bytes after.
TEST(MappedFile, DroppingResidentPagesKeepsTheBytes)
{
    const auto path = std::filesystem::temp_directory_path() / ("raypc-mapped-" + std::to_string(getpid()));
    std::vector<char> bytes(size_t(8) << 20);
    for (size_t i = 0; i < bytes.size(); ++i)
        bytes[i] = char(i * 7919 % 251);
    writeFileAtomic(path, std::as_bytes(std::span(bytes)));
    {
        const MappedFile file(path);
        const auto view = file.bytes();
        const auto sum = [&] {
            uint64_t s = 0;
            for (size_t i = 0; i < view.size(); i += 97)
                s += uint8_t(view[i]);
            return s;
        };
        uint64_t want = 0;
        for (size_t i = 0; i < bytes.size(); i += 97)
            want += uint8_t(bytes[i]);
        ASSERT_EQ(sum(), want);
        EXPECT_GE(residentKbOfMapping(view.data()), 4096) << "a file read all over is resident";
        file.dropResidentPages();
        EXPECT_EQ(residentKbOfMapping(view.data()), 0);
        EXPECT_EQ(sum(), want);
    }
    std::filesystem::remove(path);
}

TEST(AtomicFile, WritesWholeFileAndLeavesNoTemporary)
{
    const auto dir = std::filesystem::temp_directory_path() / "raypc_atomic_test";
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    writeFileAtomic(dir / "a.txt", std::string_view("first"));
    writeFileAtomic(dir / "a.txt", std::string_view("second version"));
    EXPECT_EQ(readFile(dir / "a.txt"), "second version");
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), std::filesystem::directory_iterator()), 1);
    EXPECT_THROW(writeFileAtomic(dir / "missing" / "b.txt", std::string_view("x")), Error);
    EXPECT_THROW(readFile(dir / "nope.txt"), Error);
    std::filesystem::remove_all(dir);
}

// Outputs never replace what is not a regular file: a link is written through, a character device
// or FIFO written straight to, a directory refused (resolveOutputTarget).
TEST(AtomicFile, WritesThroughLinksAndNeverReplacesDevices)
{
    namespace fs = std::filesystem;
    const auto dir = fs::temp_directory_path() / "raypc_output_targets_test";
    fs::remove_all(dir);
    fs::create_directories(dir / "real");
    writeFileAtomic(dir / "real" / "target.csv", std::string_view("old"));
    fs::create_symlink("real/target.csv", dir / "link.csv");
    writeFileAtomic(dir / "link.csv", std::string_view("new"));
    EXPECT_TRUE(fs::is_symlink(dir / "link.csv"));
    EXPECT_EQ(readFile(dir / "real" / "target.csv"), "new");
    // A dangling link names the file to create; a chain of links is followed to its end.
    fs::create_symlink("real/later.csv", dir / "dangling.csv");
    fs::create_symlink("dangling.csv", dir / "chain.csv");
    writeFileAtomic(dir / "chain.csv", std::string_view("made"));
    EXPECT_TRUE(fs::is_symlink(dir / "chain.csv") && fs::is_symlink(dir / "dangling.csv"));
    EXPECT_EQ(readFile(dir / "real" / "later.csv"), "made");
    // Nothing but the links and their targets: no temporary file left anywhere.
    EXPECT_EQ(std::distance(fs::directory_iterator(dir / "real"), fs::directory_iterator()), 2);

    // Devices: /dev/null takes the bytes and stays a device; /dev/full refuses them with an error.
    writeFileAtomic("/dev/null", std::string_view("discarded"));
    EXPECT_TRUE(fs::is_character_file("/dev/null"));
    if (fs::is_character_file("/dev/full")) {
        EXPECT_THROW(writeFileAtomic("/dev/full", std::string_view("x")), Error);
        EXPECT_TRUE(fs::is_character_file("/dev/full"));
    }
    fs::create_symlink("/dev/null", dir / "null-link");
    writeFileAtomic(dir / "null-link", std::string_view("discarded"));
    EXPECT_TRUE(fs::is_symlink(dir / "null-link"));
    EXPECT_TRUE(fs::is_character_file("/dev/null"));
    // A FIFO without a reader fails at once instead of waiting for one.
    ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0600), 0);
    EXPECT_THROW(writeFileAtomic(dir / "fifo", std::string_view("x")), Error);
    EXPECT_TRUE(fs::is_fifo(dir / "fifo"));
    // A directory is refused, and so is a netCDF-style whole-file output to a device.
    try {
        writeFileAtomic(dir / "real", std::string_view("x"));
        ADD_FAILURE() << "a directory was written";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("it is a directory"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(fs::is_directory(dir / "real"));
    EXPECT_THROW(regularOutputPath("/dev/null", "a netCDF file"), Error);
    EXPECT_EQ(regularOutputPath(dir / "link.csv", "a table"), dir / "real" / "target.csv");
    fs::remove_all(dir);
}

TEST(AtomicFile, AnExtensionNamingAnotherFormatIsRefused)
{
    EXPECT_NO_THROW(checkOutputExtension("map.png", {".png"}, "PNG", "-o"));
    EXPECT_NO_THROW(checkOutputExtension("MAP.PNG", {".png"}, "PNG", "-o"));
    EXPECT_NO_THROW(checkOutputExtension("map", {".png"}, "PNG", "-o"));
    EXPECT_NO_THROW(checkOutputExtension("map.figure", {".png"}, "PNG", "-o"));
    try {
        checkOutputExtension("out/map.nc", {".png"}, "PNG", "-o");
        ADD_FAILURE() << "map.nc accepted for a PNG";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "-o out/map.nc: the name says .nc but -o writes PNG (name it .png)");
    }
    EXPECT_THROW(checkOutputExtension("table.png", {".csv", ".txt"}, "CSV", "--tracks"), Error);
}

TEST(Error, FailFormatsTheMessage)
{
    try {
        fail("{}: dims {}, expected {}", "spherical001.nc", "(r, lat)", 3);
        FAIL() << "fail() returned";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "spherical001.nc: dims (r, lat), expected 3");
    }
}

// JSON from outside: nesting bounded before nlohmann's recursive parser sees it (deep input crashed it).
TEST(JsonInput, NestingIsBoundedBeforeParsing)
{
    const auto nested = [](int depth) { return std::string(size_t(depth), '[') + std::string(size_t(depth), ']'); };
    EXPECT_EQ(parseJsonInput(nested(kMaxJsonDepth), "x").size(), 1u);
    for (int depth : {kMaxJsonDepth + 1, 100000}) {
        try {
            parseJsonInput(nested(depth), "deep.json");
            ADD_FAILURE() << "depth " << depth << " parsed";
        } catch (const Error& e) {
            EXPECT_EQ(std::string(e.what()), fmt::format("deep.json: JSON nested deeper than {} levels (at byte {})",
                                                         kMaxJsonDepth, kMaxJsonDepth));
        }
    }
    // Brackets inside strings (escaped quotes included) are text, not nesting.
    const std::string inString = "{\"a\": \"\\\"" + std::string(1000, '[') + "\"}";
    EXPECT_EQ(parseJsonInput(inString, "x")["a"].get<std::string>().size(), 1001u);
    EXPECT_THROW(parseJsonInput("{\"a\": ", "x"), Error);
    EXPECT_THROW(parseJsonInput("1e999", "x"), Error);
}

TEST(JsonInput, ExcerptsAreShort)
{
    EXPECT_EQ(jsonExcerpt(nlohmann::json(42)), "42");
    const nlohmann::json big = nlohmann::json::parse(std::string(60, '[') + std::string(60, ']'));
    const std::string e = jsonExcerpt(big, 20);
    EXPECT_EQ(e, std::string(20, '[') + "…");
    // Never cut inside a UTF-8 sequence.
    const std::string u = jsonExcerpt(nlohmann::json("ééééééééééééééééééééé"), 4);
    EXPECT_EQ(u, "\"é…");
}

// `raypc render -o` patterns, never printf formats: one %d / %0Nd, %% for %, nothing else.
TEST(NumberedName, ExpandsOneStepNumberWithoutPrintf)
{
    EXPECT_EQ(NumberedName("f_%03d.png", "-o")(7), "f_007.png");
    EXPECT_EQ(NumberedName("f_%d.png", "-o")(1234), "f_1234.png");
    EXPECT_EQ(NumberedName("f_%02d.png", "-o")(1234), "f_1234.png");  // a width is a minimum
    EXPECT_EQ(NumberedName("%%_%09d_100%%.png", "-o")(42), "%_000000042_100%.png");
    EXPECT_EQ(NumberedName("f_%03d.png", "-o")(-5), "f_-05.png");
    const NumberedName plain("plain%%.png", "-o");
    EXPECT_FALSE(plain.numbered());
    EXPECT_EQ(plain(3), "plain%.png");
    EXPECT_TRUE(NumberedName("a%d", "-o").numbered());
}

TEST(NumberedName, RefusesEveryOtherConversion)
{
    for (const char* bad : {"f_%s%03d.png", "f_%n.png", "f_%x%d.png", "f_%p%d.png", "f_%999999999d.png", "f_%.0d.png",
                            "f_%d_%d.png", "f_%.png", "f_%", "f_%0d.png", "f_%010d.png", "f_%3d.png", "f_%ld.png",
                            "f_%-3d.png", "f_%+d.png", "f_% d.png", "f_%i.png"}) {
        try {
            NumberedName name(bad, "-o");
            ADD_FAILURE() << bad << " accepted";
        } catch (const Error& e) {
            const std::string m = e.what();
            EXPECT_EQ(m.rfind(std::string("-o '") + bad + "': ", 0), 0u) << m;
            EXPECT_NE(m.find("%03d"), std::string::npos) << m;  // says what to write instead
        }
    }
    try {
        NumberedName name(std::string(10000, 'x') + "%s", "-o");
        ADD_FAILURE();
    } catch (const Error& e) {
        EXPECT_LT(std::string(e.what()).size(), 300u);
    }
}

// The mapping of this process holding `address`, as /proc/self/smaps lists it: its range and its
// VmFlags ("hg": advised MADV_HUGEPAGE).
struct Mapping {
    uintptr_t begin = 0, end = 0;
    std::string flags;
};

Mapping mappingOf(const void* address)
{
    const auto at = reinterpret_cast<uintptr_t>(address);
    std::ifstream smaps("/proc/self/smaps");
    std::string line;
    Mapping m;
    bool inside = false;
    while (std::getline(smaps, line)) {
        uintptr_t begin = 0, end = 0;
        char dash = 0;
        std::istringstream range(line);
        if (range >> std::hex >> begin >> dash >> end && dash == '-') {
            inside = begin <= at && at < end;
            if (inside)
                m = {begin, end, ""};
        } else if (inside && line.starts_with("VmFlags:")) {
            m.flags = line.substr(8) + " ";
            return m;
        }
    }
    return m;
}

bool transparentHugePagesBuiltIn()
{
    return std::filesystem::exists("/sys/kernel/mm/transparent_hugepage/enabled");
}

// RAYPC_HUGE_PAGES as a test sets it, restored afterwards.
class HugePagesVariable {
public:
    explicit HugePagesVariable(const char* value)
    {
        if (const char* old = std::getenv("RAYPC_HUGE_PAGES"))
            m_old = old;
        value ? setenv("RAYPC_HUGE_PAGES", value, 1) : unsetenv("RAYPC_HUGE_PAGES");
    }
    ~HugePagesVariable() { m_old ? setenv("RAYPC_HUGE_PAGES", m_old->c_str(), 1) : unsetenv("RAYPC_HUGE_PAGES"); }

private:
    std::optional<std::string> m_old;
};

// A block taken is replaced by a spare of its size made in the background, a block given back is
// kept as the spare of its size only when there is none, and the spares never exceed their bound.
// (The pool is the process's: this binary's other tests take no blocks.)
TEST(SpareBlocks, ASpareOfEachSizeTakenIsMadeWithinTheBound)
{
    const size_t small = size_t(8) << 20, big = kMaxSpareBytes - small / 2;
    // Off (a CLI command): no spare is made.
    void* fresh = takeBlock(small);
    ASSERT_NE(fresh, nullptr);
    EXPECT_EQ(waitForSpareBlocks(), 0u) << "a spare made without keepSpareBlocks(true)";
    giveBackBlock(fresh, small);
    EXPECT_EQ(waitForSpareBlocks(), 0u) << "a block given back kept without keepSpareBlocks(true)";

    keepSpareBlocks(true);
    void* a = takeBlock(small);
    ASSERT_NE(a, nullptr);
    std::fill_n(static_cast<char*>(a), small, char(1));
    EXPECT_EQ(waitForSpareBlocks(), small) << "no spare made of a size taken";
    giveBackBlock(a, small);  // its size has a spare: freed
    EXPECT_EQ(waitForSpareBlocks(), small);

    // The spare is handed out, and another made in its place.
    SpareArray<float> b = makeSpareArray<float>(small / sizeof(float));
    std::fill_n(b.get(), small / sizeof(float), 2.0f);
    EXPECT_EQ(waitForSpareBlocks(), small);

    // A size whose spare would take the spares over their bound gets none, taken or given back.
    void* c = takeBlock(big);
    ASSERT_NE(c, nullptr);
    EXPECT_EQ(waitForSpareBlocks(), small) << "a spare over kMaxSpareBytes was kept";
    giveBackBlock(c, big);
    EXPECT_EQ(waitForSpareBlocks(), small);

    // With no spare of its size, a block given back becomes it.
    const size_t other = size_t(5) << 20;
    void* d = takeBlock(other);
    EXPECT_EQ(waitForSpareBlocks(), small + other);
    void* e = takeBlock(other);  // the spare; another is being made
    EXPECT_EQ(waitForSpareBlocks(), small + other);
    giveBackBlock(d, other);
    giveBackBlock(e, other);
    b.reset();  // its size has a spare: freed
    EXPECT_EQ(waitForSpareBlocks(), small + other);
    keepSpareBlocks(false);
    EXPECT_EQ(waitForSpareBlocks(), 0u) << "spares kept after keepSpareBlocks(false)";
}

// Without spares made ahead, blocks given back are kept for reuse only when asked, several of a
// size, within their bound, and handed out again by takes of their exact size.
TEST(SpareBlocks, BlocksGivenBackAreReusedWithinTheirBound)
{
    const size_t small = size_t(8) << 20, other = size_t(6) << 20;
    ASSERT_EQ(waitForSpareBlocks(), 0u);
    reuseGivenBackBlocks(2 * small + other);
    void* a = takeBlock(small);
    void* b = takeBlock(small);
    void* c = takeBlock(small);
    std::fill_n(static_cast<char*>(a), small, char(1));
    giveBackBlock(a, small);
    giveBackBlock(b, small);
    EXPECT_EQ(waitForSpareBlocks(), 2 * small) << "two blocks of one size kept";
    giveBackBlock(c, small);  // over the bound: freed
    EXPECT_EQ(waitForSpareBlocks(), 2 * small);
    void* d = takeBlock(other);  // no block of its size kept: a fresh one
    EXPECT_TRUE(d != a && d != b);
    EXPECT_EQ(waitForSpareBlocks(), 2 * small);
    void* e = takeBlock(small);
    EXPECT_TRUE(e == a || e == b) << "a kept block handed out again";
    EXPECT_EQ(waitForSpareBlocks(), small);
    giveBackBlock(d, other);
    giveBackBlock(e, small);
    EXPECT_EQ(waitForSpareBlocks(), 2 * small + other);
    reuseGivenBackBlocks(small + other);  // a smaller bound frees what exceeds it
    EXPECT_LE(waitForSpareBlocks(), small + other);
    reuseGivenBackBlocks(0);
    EXPECT_EQ(waitForSpareBlocks(), 0u) << "blocks kept after reuseGivenBackBlocks(0)";
}

TEST(HugePages, LargeArraysStartOnAHugePageAndAreAdvised)
{
    if (!transparentHugePagesBuiltIn())
        GTEST_SKIP() << "a kernel without transparent huge pages";
    const HugePagesVariable unset(nullptr);
    if (!hugePagesEnabled())
        GTEST_SKIP() << "glibc's malloc asks for huge pages itself here (GLIBC_TUNABLES)";
    const size_t bytes = 3 * kHugePageBytes + 12345;
    const std::unique_ptr<char[], void (*)(void*)> a(static_cast<char*>(allocateHugePageBacked(bytes)), std::free);
    const auto p = reinterpret_cast<uintptr_t>(a.get());
    EXPECT_EQ(p % kHugePageBytes, 0u);
    const Mapping m = mappingOf(a.get());
    EXPECT_NE(m.flags.find(" hg "), std::string::npos) << m.flags;
    // Its three whole huge pages are advised, not its last partial one.
    EXPECT_LE(m.begin, p);
    EXPECT_EQ(m.end, p + 3 * kHugePageBytes);
    // The memory is usable to its last byte.
    a[0] = 1;
    a[bytes - 1] = 2;
    EXPECT_EQ(a[0] + a[bytes - 1], 3);

    HugePageVector<int32_t> v(kHugePageBytes / sizeof(int32_t), 7);
    EXPECT_EQ(reinterpret_cast<uintptr_t>(v.data()) % kHugePageBytes, 0u);
    EXPECT_NE(mappingOf(v.data()).flags.find(" hg "), std::string::npos);
    EXPECT_EQ(std::count(v.begin(), v.end(), 7), std::ptrdiff_t(v.size()));
}

TEST(HugePages, AdviceCoversTheAlignedInteriorOnly)
{
    if (!transparentHugePagesBuiltIn())
        GTEST_SKIP() << "a kernel without transparent huge pages";
    const HugePagesVariable unset(nullptr);
    if (!hugePagesEnabled())
        GTEST_SKIP() << "glibc's malloc asks for huge pages itself here (GLIBC_TUNABLES)";
    // Eight huge pages of address space, of which a range from 4 KB past the first boundary to
    // 4 KB past the fourth: its aligned interior is the second and third huge pages.
    const size_t mapped = 8 * kHugePageBytes;
    void* base = mmap(nullptr, mapped, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    ASSERT_NE(base, MAP_FAILED);
    const uintptr_t boundary = (reinterpret_cast<uintptr_t>(base) + kHugePageBytes - 1) & ~(kHugePageBytes - 1);
    auto* start = reinterpret_cast<char*>(boundary + 4096);
    adviseHugePages(start, 3 * kHugePageBytes);
    const Mapping inside = mappingOf(reinterpret_cast<void*>(boundary + kHugePageBytes));
    EXPECT_NE(inside.flags.find(" hg "), std::string::npos) << inside.flags;
    EXPECT_EQ(inside.begin, boundary + kHugePageBytes);
    EXPECT_EQ(inside.end, boundary + 3 * kHugePageBytes);
    EXPECT_EQ(mappingOf(start).flags.find(" hg "), std::string::npos) << mappingOf(start).flags;
    EXPECT_EQ(mappingOf(start + 3 * kHugePageBytes - 1).flags.find(" hg "), std::string::npos);
    // A range without a whole aligned huge page inside is left alone.
    adviseHugePages(reinterpret_cast<char*>(boundary) + 5 * kHugePageBytes + 4096, kHugePageBytes);
    EXPECT_EQ(mappingOf(reinterpret_cast<char*>(boundary) + 5 * kHugePageBytes + 8192).flags.find(" hg "),
              std::string::npos);
    munmap(base, mapped);
}

TEST(HugePages, RaypcHugePagesZeroAsksForNothing)
{
    if (!transparentHugePagesBuiltIn())
        GTEST_SKIP() << "a kernel without transparent huge pages";
    const HugePagesVariable off("0");
    EXPECT_FALSE(hugePagesEnabled());
    const size_t mapped = 4 * kHugePageBytes;
    void* base = mmap(nullptr, mapped, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    ASSERT_NE(base, MAP_FAILED);
    adviseHugePages(base, mapped);
    EXPECT_EQ(mappingOf(static_cast<char*>(base) + 2 * kHugePageBytes).flags.find(" hg "), std::string::npos);
    munmap(base, mapped);
    {
        const HugePagesVariable on("1");
        const char* tunables = std::getenv("GLIBC_TUNABLES");
        EXPECT_EQ(hugePagesEnabled(), !(tunables && std::string(tunables).find("glibc.malloc.hugetlb=1") != std::string::npos));
        // glibc's malloc asking already: the library does not ask again; hugetlb=0 is no asking.
        const std::string old = tunables ? tunables : "";
        setenv("GLIBC_TUNABLES", "glibc.malloc.hugetlb=1", 1);
        EXPECT_FALSE(hugePagesEnabled());
        setenv("GLIBC_TUNABLES", "glibc.malloc.tcache_count=5:glibc.malloc.hugetlb=0", 1);
        EXPECT_TRUE(hugePagesEnabled());
        tunables ? setenv("GLIBC_TUNABLES", old.c_str(), 1) : unsetenv("GLIBC_TUNABLES");
    }
}

}  // namespace
}  // namespace raypc

TEST(SystemMemory, ParsesSizesWithBinaryUnitsAndNamesTheOptionOnBadOnes)
{
    using raypc::parseMemorySize;
    EXPECT_EQ(parseMemorySize("512M", "--step-cache"), uint64_t(512) << 20);
    EXPECT_EQ(parseMemorySize("8G", "--step-cache"), uint64_t(8) << 30);
    EXPECT_EQ(parseMemorySize("1.5GiB", "--step-cache"), uint64_t(3) << 29);
    EXPECT_EQ(parseMemorySize("64mb", "--step-cache"), uint64_t(64) << 20);
    EXPECT_EQ(parseMemorySize("2T", "--step-cache"), uint64_t(2) << 40);
    EXPECT_EQ(parseMemorySize("3000000", "--step-cache"), 3000000u);
    for (const char* bad : {"", "G", "12Q", "1.2.3G", "-5G", "0", "0.0000001K", "8 G", "9000000T"}) {
        try {
            parseMemorySize(bad, "--step-cache");
            ADD_FAILURE() << "accepted '" << bad << "'";
        } catch (const raypc::Error& e) {
            const std::string m = e.what();
            EXPECT_TRUE(m.starts_with(std::string("--step-cache: '") + bad + "'")) << m;
            EXPECT_NE(m.find("expected a number with an optional unit"), std::string::npos) << m;
        }
    }
}

// `raypc serve FILES` makes the series' step-sized arrays on a thread of its own: after
// keepLargeBlocksForReuseOnEveryThread such a thread allocates from the main heap (below the
// program break), where a freed block is reused, not from an arena of its own, whose heaps of at
// most 64 MB send a 100 MB block to a fresh mapping (far above the break) every time.
TEST(SystemMemory, ThreadsAllocateLargeBlocksFromTheMainHeapOnceAsked)
{
#if defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "ASan's allocator replaces glibc's";
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
    GTEST_SKIP() << "ASan's allocator replaces glibc's";
#endif
#endif
    raypc::keepLargeBlocksForReuseOnEveryThread();
    uintptr_t block = 0, brk = 0;
    std::thread([&] {
        void* p = std::malloc(size_t(100) << 20);
        block = reinterpret_cast<uintptr_t>(p);
        brk = reinterpret_cast<uintptr_t>(::sbrk(0));
        std::free(p);
    }).join();
    ASSERT_NE(block, 0u);
    EXPECT_LT(block, brk) << "a thread's 100 MB block was mapped outside the main heap";
}
