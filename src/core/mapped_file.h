// A read-only memory-mapped file: dataset arrays are mapped, not parsed, so a
// full-resolution step is ready to render as soon as the pages are touched.
//
// Thread safety: immutable after construction; share freely between threads.
#pragma once

#include <cstddef>
#include <filesystem>
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

private:
    void* m_data = nullptr;
    size_t m_size = 0;
};

}  // namespace raypc
