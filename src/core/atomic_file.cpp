#include "core/atomic_file.h"

#include "core/error.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace raypc {

std::filesystem::path temporarySibling(const std::filesystem::path& path)
{
    static std::atomic<unsigned> counter{0};
    auto name = path.filename().string();
    return path.parent_path() /
           fmt::format(".{}.tmp-{}-{}", name, static_cast<long>(::getpid()), counter.fetch_add(1));
}

void writeFileAtomic(const std::filesystem::path& path, std::span<const std::byte> bytes)
{
    const auto tmp = temporarySibling(path);
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0)
        fail("{}: cannot create: {}", tmp.string(), std::strerror(errno));
    const std::byte* p = bytes.data();
    size_t left = bytes.size();
    while (left > 0) {
        const ssize_t n = ::write(fd, p, left);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            const int err = errno;
            ::close(fd);
            ::unlink(tmp.c_str());
            fail("{}: write failed: {}", path.string(), std::strerror(err));
        }
        p += n;
        left -= static_cast<size_t>(n);
    }
    if (::close(fd) != 0) {
        const int err = errno;
        ::unlink(tmp.c_str());
        fail("{}: close failed: {}", path.string(), std::strerror(err));
    }
    renameAtomic(tmp, path);
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
