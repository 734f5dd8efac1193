#pragma once
// Whole-file reads with a size bound, and atomic writes: a write goes to a temporary file beside the
// target, is flushed to disk, then renamed over it, so a failed or killed run never leaves half a file.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <span>
#include <string_view>
#include <vector>

namespace viewpose {

/// Files larger than this are refused before anything is allocated (override per call).
inline constexpr std::size_t kMaxInputFileBytes = std::size_t{4} << 30;

/// The bytes of `path`. Throws viewpose::Error naming the file when it is missing, a directory,
/// unreadable, or larger than `max_bytes`.
std::vector<std::uint8_t> read_file_bytes(const std::filesystem::path& path,
                                          std::size_t max_bytes = kMaxInputFileBytes);

/// The first `count` bytes of `path` (fewer where the file is shorter), and in `file_size` its
/// whole size: the parts of a large file that are needed, without reading the rest. The same errors
/// as read_file_bytes.
std::vector<std::uint8_t> read_file_prefix(const std::filesystem::path& path, std::size_t count, std::size_t max_bytes,
                                           std::uint64_t& file_size);

/// The `count` bytes of `path` from byte `offset` on (fewer where the file is shorter; none past its
/// end), and in `file_size` its whole size. The same errors as read_file_bytes (`max_bytes` bounds
/// the whole file).
std::vector<std::uint8_t> read_file_range(const std::filesystem::path& path, std::uint64_t offset, std::size_t count,
                                          std::size_t max_bytes, std::uint64_t& file_size);

/// Writes `bytes` to `path` atomically. Throws viewpose::Error on failure, leaving any previous
/// file at `path` untouched and no temporary file behind.
void write_file_atomic(const std::filesystem::path& path, std::span<const std::uint8_t> bytes);
void write_file_atomic(const std::filesystem::path& path, std::string_view text);

/// Streams into `path` atomically: `write` fills the stream; the file appears only if it returns
/// normally and everything reached the disk.
void write_file_atomic(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write);

}  // namespace viewpose
