#include "core/system_memory.h"

#include "core/error.h"

#include <malloc.h>
#include <unistd.h>

#include <fmt/format.h>
#include <sys/resource.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>

namespace raypc {
namespace {

// The value of `key` (in kB) in a /proc file of "Key:   123 kB" lines.
std::optional<uint64_t> procKilobytes(const char* path, const std::string& key)
{
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line))
        if (line.starts_with(key + ":")) {
            std::istringstream fields(line.substr(key.size() + 1));
            uint64_t kb = 0;
            if (fields >> kb)
                return kb * 1024;
        }
    return std::nullopt;
}

std::optional<uint64_t> fileNumber(const std::string& path)
{
    std::ifstream in(path);
    uint64_t value = 0;
    if (in >> value)
        return value;
    return std::nullopt;  // also "max": no limit
}

// memory.max - memory.current of this process's cgroup (v2, the "0::/path" line of /proc/self/cgroup).
std::optional<uint64_t> cgroupRemaining()
{
    std::ifstream in("/proc/self/cgroup");
    std::string line;
    while (std::getline(in, line))
        if (line.starts_with("0::")) {
            const std::string dir = "/sys/fs/cgroup" + line.substr(3);
            const auto max = fileNumber(dir + "/memory.max"), current = fileNumber(dir + "/memory.current");
            if (max && current)
                return *max > *current ? *max - *current : 0;
        }
    return std::nullopt;
}

std::optional<uint64_t> addressSpaceRemaining()
{
    rlimit limit{};
    if (getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY)
        return std::nullopt;
    const uint64_t used = procKilobytes("/proc/self/status", "VmSize").value_or(0);
    return limit.rlim_cur > used ? limit.rlim_cur - used : 0;
}

}  // namespace

AvailableMemory availableMemory()
{
    AvailableMemory a{std::numeric_limits<uint64_t>::max(), "no limit found"};
    auto consider = [&](std::optional<uint64_t> bytes, const char* what) {
        if (bytes && *bytes < a.bytes)
            a = {*bytes, what};
    };
    consider(procKilobytes("/proc/meminfo", "MemAvailable"), "MemAvailable");
    consider(cgroupRemaining(), "cgroup memory.max");
    consider(addressSpaceRemaining(), "ulimit -v");
    return a;
}

uint64_t parseMemorySize(const std::string& text, const std::string& option)
{
    const auto bad = [&](const char* why) {
        fail("{}: '{}' {}; expected a number with an optional unit K, M, G or T (binary: 1G = 1024M), e.g. 8G or 512M",
             option, text, why);
    };
    size_t digits = 0;
    while (digits < text.size() && (std::isdigit(static_cast<unsigned char>(text[digits])) || text[digits] == '.'))
        ++digits;
    if (digits == 0 || std::count(text.begin(), text.begin() + std::ptrdiff_t(digits), '.') > 1)
        bad("is not a size");
    const double number = std::strtod(text.substr(0, digits).c_str(), nullptr);
    std::string unit = text.substr(digits);
    for (char& c : unit)
        c = char(std::toupper(static_cast<unsigned char>(c)));
    if (unit.ends_with("IB"))
        unit.resize(unit.size() - 2);
    else if (unit.size() > 1 && unit.ends_with("B"))
        unit.pop_back();
    double scale = 1;
    if (unit == "K")
        scale = 0x1p10;
    else if (unit == "M")
        scale = 0x1p20;
    else if (unit == "G")
        scale = 0x1p30;
    else if (unit == "T")
        scale = 0x1p40;
    else if (!unit.empty() && unit != "B")
        bad("has an unknown unit");
    const double bytes = std::floor(number * scale);
    if (!(bytes >= 1))
        bad("is zero");
    if (bytes >= 0x1p63)
        bad("is too large");
    return uint64_t(bytes);
}

std::string formatBytes(uint64_t bytes)
{
    if (bytes >= 1'000'000'000)
        return fmt::format("{:.1f} GB", bytes / 1e9);
    if (bytes >= 1'000'000)
        return fmt::format("{:.0f} MB", bytes / 1e6);
    return fmt::format("{} kB", (bytes + 999) / 1000);
}

void restartWithTransparentHugePages(char** argv)
{
    constexpr const char* kTunable = "glibc.malloc.hugetlb=1";
    const char* optOut = std::getenv("RAYPC_HUGE_PAGES");
    if (optOut && std::string_view(optOut) == "0")
        return;
    const char* tunables = std::getenv("GLIBC_TUNABLES");
    if (tunables && std::string_view(tunables).find("glibc.malloc.hugetlb") != std::string_view::npos)
        return;
    std::ifstream policy("/sys/kernel/mm/transparent_hugepage/enabled");
    std::string line;
    if (!std::getline(policy, line) || line.find("[madvise]") == std::string::npos)
        return;
    const std::string value = tunables && *tunables ? std::string(kTunable) + ":" + tunables : kTunable;
    if (setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0)
        return;
    execv("/proc/self/exe", argv);
    // The exec failed (no /proc): carry on with 4 KB pages, and tell children nothing false.
    if (tunables)
        setenv("GLIBC_TUNABLES", tunables, 1);
    else
        unsetenv("GLIBC_TUNABLES");
}

void keepLargeBlocksForReuse()
{
    constexpr int kBytes = 256 << 20;
    mallopt(M_MMAP_THRESHOLD, kBytes);
    mallopt(M_TRIM_THRESHOLD, kBytes);
}

void keepLargeBlocksForReuseOnEveryThread()
{
    keepLargeBlocksForReuse();
    mallopt(M_ARENA_MAX, 1);
}

}  // namespace raypc
