// Atomic outputs: write under a temporary name in the same directory, then rename.
// A killed process leaves either the old file, or no file, never a half-written one.
#pragma once

#include <cstddef>
#include <filesystem>
#include <span>
#include <string_view>

namespace raypc {

// Writes `bytes` to `path` atomically (temporary file + fsync + rename).
// Throws raypc::Error naming the path on any I/O failure.
void writeFileAtomic(const std::filesystem::path& path, std::span<const std::byte> bytes);
void writeFileAtomic(const std::filesystem::path& path, std::string_view text);

// A unique temporary sibling of `path` (same directory, so rename is atomic).
std::filesystem::path temporarySibling(const std::filesystem::path& path);

// Renames `from` to `to` atomically (replacing `to` if it is a file; for a directory
// `to` must not exist). Throws raypc::Error on failure.
void renameAtomic(const std::filesystem::path& from, const std::filesystem::path& to);

// Reads a whole file; throws raypc::Error naming the path if it cannot.
std::string readFile(const std::filesystem::path& path);

}  // namespace raypc
