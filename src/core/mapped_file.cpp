#include "core/mapped_file.h"

#include "core/error.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace raypc {

MappedFile::MappedFile(const std::filesystem::path& path) : m_path(path)
{
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        fail("{}: cannot open: {}", path.string(), std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0) {
        const int err = errno;
        ::close(fd);
        fail("{}: cannot stat: {}", path.string(), std::strerror(err));
    }
    m_size = static_cast<size_t>(st.st_size);
    m_device = static_cast<unsigned long>(st.st_dev);
    m_inode = static_cast<unsigned long>(st.st_ino);
    if (m_size > 0) {
        m_data = ::mmap(nullptr, m_size, PROT_READ, MAP_SHARED, fd, 0);
        if (m_data == MAP_FAILED) {
            const int err = errno;
            m_data = nullptr;
            ::close(fd);
            fail("{}: cannot map: {}", path.string(), std::strerror(err));
        }
    }
    ::close(fd);
}

MappedFile::~MappedFile()
{
    if (m_data)
        ::munmap(m_data, m_size);
}

void MappedFile::adviseWillNeed() const noexcept
{
    if (m_data)
        ::madvise(m_data, m_size, MADV_WILLNEED);
}

void MappedFile::dropResidentPages() const noexcept
{
    if (m_data)
        ::madvise(m_data, m_size, MADV_DONTNEED);
}

std::optional<size_t> MappedFile::cutShort() const noexcept
{
    if (m_path.empty())
        return std::nullopt;
    struct stat st {};
    if (::stat(m_path.c_str(), &st) != 0 || static_cast<unsigned long>(st.st_dev) != m_device ||
        static_cast<unsigned long>(st.st_ino) != m_inode)
        return std::nullopt;
    if (static_cast<size_t>(st.st_size) >= m_size)
        return std::nullopt;
    return static_cast<size_t>(st.st_size);
}

void MappedFile::checkNotCutShort() const
{
    if (const auto now = cutShort())
        fail("{}: {} bytes now, {} when it was mapped: the file was cut short while in use (a damaged dataset; "
             "preprocess the step again)",
             m_path.string(), *now, m_size);
}

MappedFile::MappedFile(MappedFile&& other) noexcept
    : m_data(std::exchange(other.m_data, nullptr)), m_size(std::exchange(other.m_size, 0)),
      m_path(std::move(other.m_path)), m_device(other.m_device), m_inode(other.m_inode)
{
}

MappedFile& MappedFile::operator=(MappedFile&& other) noexcept
{
    if (this != &other) {
        if (m_data)
            ::munmap(m_data, m_size);
        m_data = std::exchange(other.m_data, nullptr);
        m_size = std::exchange(other.m_size, 0);
        m_path = std::move(other.m_path);
        m_device = other.m_device;
        m_inode = other.m_inode;
    }
    return *this;
}

}  // namespace raypc
