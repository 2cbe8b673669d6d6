// Outputs: a regular file is written under a temporary name in the same directory, then renamed
// over its path, so that a killed process leaves either the old file or the whole new one, never a
// half-written one. A symbolic link is written through (its target is written, the link stays); a
// character device or a FIFO (/dev/null, /dev/stdout, a named pipe) is written straight to, never
// replaced; a directory, a block device or a socket is refused.
#pragma once

#include <cstddef>
#include <filesystem>
#include <initializer_list>
#include <span>
#include <string_view>

namespace raypc {

// Where an output named `path` goes: `path` with every symbolic link followed (a dangling link
// names the file to create), and whether it is written straight to (a character device or FIFO).
// Throws raypc::Error naming the path for a directory, a block device, a socket or a loop of links.
struct OutputTarget {
    std::filesystem::path path;
    bool direct = false;  // not a regular file: opened and written, no temporary file, no rename
};
OutputTarget resolveOutputTarget(const std::filesystem::path& path);

// The regular file an output named `path` is written to (links followed, as above), for writers
// that must rename a whole temporary file (netCDF, dataset directories). Throws raypc::Error
// naming the path when it names something other than a regular file or nothing: `what` says what
// is written ("a netCDF file").
std::filesystem::path regularOutputPath(const std::filesystem::path& path, std::string_view what);

// Refuses an output whose extension names another format than the one written (`map -o map.nc`
// writing a PNG): an extension RayPC knows as a format (.png, .nc, .csv, .json, .pfm …) that is not
// among `accepted` (lower case, with the dot) throws raypc::Error naming `option`, the path and
// `format`. Other extensions, none, and the case of letters are accepted.
void checkOutputExtension(const std::filesystem::path& path, std::initializer_list<std::string_view> accepted,
                          std::string_view format, std::string_view option);

// Writes `bytes` to `path`: a regular file atomically (temporary file + rename), a device or FIFO
// directly (resolveOutputTarget). Throws raypc::Error naming the path on any failure (a FIFO
// without a reader fails at once instead of waiting).
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
