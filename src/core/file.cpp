#include "viewpose/core/file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <system_error>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"

namespace viewpose {

namespace fs = std::filesystem;

std::vector<std::uint8_t> read_file_prefix(const fs::path& path, std::size_t count, std::size_t max_bytes, std::uint64_t& file_size) {
  return read_file_range(path, 0, count, max_bytes, file_size);
}

std::vector<std::uint8_t> read_file_range(const fs::path& path, std::uint64_t offset, std::size_t count, std::size_t max_bytes,
                                          std::uint64_t& file_size) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status)) throw Error(fmt::format("{}: no such file", path.string()));
  if (fs::is_directory(status)) throw Error(fmt::format("{}: is a directory, not a file", path.string()));
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw Error(fmt::format("{}: cannot read its size: {}", path.string(), ec.message()));
  if (size > max_bytes) {
    throw Error(fmt::format("{}: file is {} bytes, more than the limit of {}", path.string(), size, max_bytes));
  }
  file_size = size;
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(fmt::format("{}: cannot open: {}", path.string(), std::strerror(errno)));
  const std::uintmax_t start = std::min<std::uintmax_t>(size, offset);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(std::min<std::uintmax_t>(size - start, count)));
  if (start > 0 && !in.seekg(static_cast<std::streamoff>(start))) {
    throw Error(fmt::format("{}: cannot seek to byte {}: {}", path.string(), start, std::strerror(errno)));
  }
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (static_cast<std::size_t>(in.gcount()) != bytes.size()) {
    throw Error(fmt::format("{}: read {} of {} bytes (file changed while reading?)", path.string(), in.gcount(), bytes.size()));
  }
  return bytes;
}

std::vector<std::uint8_t> read_file_bytes(const fs::path& path, std::size_t max_bytes) {
  std::uint64_t size = 0;
  return read_file_prefix(path, std::numeric_limits<std::size_t>::max(), max_bytes, size);
}

namespace {

std::string errno_text() { return std::strerror(errno); }

// Writes all of `data` to `fd`, retrying short writes and interrupted calls.
bool write_all(int fd, const std::uint8_t* data, std::size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace

void write_file_atomic(const fs::path& path, std::span<const std::uint8_t> bytes) {
  static std::atomic<unsigned> counter{0};
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  const fs::path tmp = dir / fmt::format(".{}.tmp-{}-{}", path.filename().string(), ::getpid(), counter++);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) throw Error(fmt::format("{}: cannot create a file in {}: {}", path.string(), dir.string(), errno_text()));
  const bool written = write_all(fd, bytes.data(), bytes.size()) && ::fsync(fd) == 0;
  const std::string why = written ? std::string() : errno_text();
  const bool closed = ::close(fd) == 0;
  if (!written || !closed) {
    ::unlink(tmp.c_str());
    throw Error(fmt::format("{}: write failed: {}", path.string(), written ? errno_text() : why));
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string reason = errno_text();
    ::unlink(tmp.c_str());
    throw Error(fmt::format("{}: cannot replace the file: {}", path.string(), reason));
  }
  // Make the rename itself durable; a failure here loses nothing already written, so it is ignored.
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

void write_file_atomic(const fs::path& path, std::string_view text) {
  write_file_atomic(path, std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

void write_file_atomic(const fs::path& path, const std::function<void(std::ostream&)>& write) {
  std::ostringstream out;
  write(out);
  write_file_atomic(path, std::string_view(out.view()));
}

}  // namespace viewpose
