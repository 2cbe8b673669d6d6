// A read-only memory-mapped file: dataset arrays are mapped, not parsed, so a
// full-resolution step is ready to render as soon as the pages are touched.
//
// A file cut short while it is mapped makes a read of the lost pages raise SIGBUS: callers that
// read a mapping long after mapping it (a server's cached steps) ask `cutShort` first
// (docs/reliability.md says what remains: a file cut during such a read).
//
// Thread safety: immutable after construction; share freely between threads.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <span>

namespace raypc {

class MappedFile {
public:
    MappedFile() = default;
    // Throws raypc::Error naming the path if it cannot be opened or mapped.
    explicit MappedFile(const std::filesystem::path& path);
    ~MappedFile();
    MappedFile(MappedFile&& other) noexcept;
    MappedFile& operator=(MappedFile&& other) noexcept;
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;

    std::span<const std::byte> bytes() const { return {static_cast<const std::byte*>(m_data), m_size}; }
    size_t size() const { return m_size; }
    const std::filesystem::path& path() const { return m_path; }

    // The file's size now if the mapped file (same device and inode) is still at path() and
    // shorter than the mapping, else nullopt: a file replaced (renamed over) or removed keeps
    // its mapped inode whole. One stat(2); never throws.
    std::optional<size_t> cutShort() const noexcept;
    // Throws raypc::Error naming the file when cutShort().
    void checkNotCutShort() const;
    // Asks the kernel to read the whole file into the page cache now, in the background
    // (madvise MADV_WILLNEED), for a reader that will touch it all over rather than in order. Only
    // advice: never throws, and a failure changes nothing but the speed.
    void adviseWillNeed() const noexcept;
    // Drops the file's pages from this process's resident memory (madvise MADV_DONTNEED): they stay
    // in the page cache and a later read maps them again. For a reader that touched points all over
    // the file and holds the mapping for later: a touched page maps a whole 2 MB folio of the page
    // cache on kernels that keep files in large folios, so a few hundred scattered reads of a 26 MB
    // file leave most of it counted in the process's RSS. Never throws.
    void dropResidentPages() const noexcept;

private:
    void* m_data = nullptr;
    size_t m_size = 0;
    std::filesystem::path m_path;
    unsigned long m_device = 0, m_inode = 0;
};

}  // namespace raypc
