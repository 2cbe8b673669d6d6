#include "core/atomic_file.h"

#include "core/error.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace raypc {
namespace fs = std::filesystem;

std::filesystem::path temporarySibling(const std::filesystem::path& path)
{
    static std::atomic<unsigned> counter{0};
    auto name = path.filename().string();
    return path.parent_path() /
           fmt::format(".{}.tmp-{}-{}", name, static_cast<long>(::getpid()), counter.fetch_add(1));
}

OutputTarget resolveOutputTarget(const std::filesystem::path& path)
{
    fs::path target = path;
    // Follow links one at a time (a dangling link's target is the file to create); as the kernel,
    // give up after 40.
    for (int hops = 0;; ++hops) {
        struct stat st {};
        if (::lstat(target.c_str(), &st) != 0) {
            if (errno == ENOENT)
                return {target, false};
            fail("{}: cannot write: {}", path.string(), std::strerror(errno));
        }
        if (S_ISLNK(st.st_mode)) {
            if (hops == 40)
                fail("{}: cannot write: too many levels of symbolic links", path.string());
            std::error_code ec;
            const fs::path next = fs::read_symlink(target, ec);
            if (ec)
                fail("{}: cannot read the symbolic link {}: {}", path.string(), target.string(), ec.message());
            target = next.is_absolute() ? next : target.parent_path() / next;
            continue;
        }
        const std::string shown =
            target == path ? path.string() : fmt::format("{} (the target of the link {})", target.string(), path.string());
        if (S_ISREG(st.st_mode))
            return {target, false};
        if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode))
            return {target, true};
        fail("{}: cannot write an output there: it is {}", shown,
             S_ISDIR(st.st_mode) ? "a directory" : S_ISBLK(st.st_mode) ? "a block device" : "a socket");
    }
}

std::filesystem::path regularOutputPath(const std::filesystem::path& path, std::string_view what)
{
    const OutputTarget target = resolveOutputTarget(path);
    if (target.direct)
        fail("{}: not a regular file (a device or a pipe); {} is written to a regular file", path.string(), what);
    return target.path;
}

void checkOutputExtension(const std::filesystem::path& path, std::initializer_list<std::string_view> accepted,
                          std::string_view format, std::string_view option)
{
    static constexpr std::string_view kFormats[] = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".pdf", ".svg",
                                                    ".nc", ".nc4", ".cdf", ".h5", ".hdf5", ".csv", ".tsv",
                                                    ".json", ".pfm", ".vtp", ".vtu", ".vtk", ".pvd", ".txt"};
    std::string extension = path.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (std::find(std::begin(kFormats), std::end(kFormats), extension) == std::end(kFormats) ||
        std::find(accepted.begin(), accepted.end(), extension) != accepted.end())
        return;
    std::string names;
    for (const std::string_view a : accepted)
        names += fmt::format("{}{}", names.empty() ? "" : ", ", a);
    fail("{} {}: the name says {} but {} writes {} (name it {})", option, path.string(), extension, option, format,
         names);
}

namespace {

// Writes all of `bytes` to `fd`; returns 0 or the errno of the failure.
int writeAll(int fd, std::span<const std::byte> bytes)
{
    const std::byte* p = bytes.data();
    size_t left = bytes.size();
    while (left > 0) {
        const ssize_t n = ::write(fd, p, left);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            return errno;
        }
        p += n;
        left -= static_cast<size_t>(n);
    }
    return 0;
}

// A character device or FIFO: written in place. A FIFO is opened without waiting for a reader
// (ENXIO when there is none) and then written with blocking writes.
void writeDirect(const std::filesystem::path& shown, const std::filesystem::path& target, std::span<const std::byte> bytes)
{
    const int fd = ::open(target.c_str(), O_WRONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
    if (fd < 0)
        fail("{}: cannot open for writing: {}", shown.string(),
             errno == ENXIO ? "no process reads this FIFO" : std::strerror(errno));
    ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
    const int err = writeAll(fd, bytes);
    ::close(fd);
    if (err != 0)
        fail("{}: write failed: {}", shown.string(), std::strerror(err));
}

}  // namespace

void writeFileAtomic(const std::filesystem::path& path, std::span<const std::byte> bytes)
{
    const OutputTarget target = resolveOutputTarget(path);
    if (target.direct)
        return writeDirect(path, target.path, bytes);
    const auto tmp = temporarySibling(target.path);
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0)
        fail("{}: cannot create {}: {}", path.string(), tmp.string(), std::strerror(errno));
    if (const int err = writeAll(fd, bytes); err != 0) {
        ::close(fd);
        ::unlink(tmp.c_str());
        fail("{}: write failed: {}", path.string(), std::strerror(err));
    }
    if (::close(fd) != 0) {
        const int err = errno;
        ::unlink(tmp.c_str());
        fail("{}: close failed: {}", path.string(), std::strerror(err));
    }
    renameAtomic(tmp, target.path);
}

void writeFileAtomic(const std::filesystem::path& path, std::string_view text)
{
    writeFileAtomic(path, std::as_bytes(std::span(text.data(), text.size())));
}

void renameAtomic(const std::filesystem::path& from, const std::filesystem::path& to)
{
    if (std::rename(from.c_str(), to.c_str()) != 0) {
        const int err = errno;
        std::error_code ignored;
        std::filesystem::remove_all(from, ignored);
        fail("{}: cannot rename from {}: {}", to.string(), from.string(), std::strerror(err));
    }
}

std::string readFile(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in)
        fail("{}: cannot open for reading", path.string());
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad())
        fail("{}: read failed", path.string());
    return ss.str();
}

}  // namespace raypc
