// Whole-file reads with a bound, and atomic writes, including a write that runs out of room.
#include <sys/resource.h>

#include <algorithm>
#include <csignal>
#include <string>
#include <vector>

#include "test_support.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/core/file.hpp"

namespace viewpose {
namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& path) {
  const auto bytes = read_file_bytes(path);
  return {bytes.begin(), bytes.end()};
}

// Every entry of `dir` but the ones named: a temporary file left behind shows up here.
std::vector<std::string> entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// The file-size limit (what `ulimit -f` sets) stands in for a full disk: a write past it fails
// with EFBIG, as one on a full disk fails with ENOSPC, and neither needs root or a mount.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &before_);
    old_handler_ = std::signal(SIGXFSZ, SIG_IGN);  // else the process is killed at the limit
    rlimit limit = before_;
    limit.rlim_cur = bytes;
    ::setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &before_);
    std::signal(SIGXFSZ, old_handler_);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  rlimit before_{};
  void (*old_handler_)(int) = nullptr;
};

TEST(AtomicWrite, ReplacesTheFileWholeAndLeavesNothingElse) {
  test::TempDir dir;
  write_file_atomic(dir.path() / "a.txt", "first version\n");
  write_file_atomic(dir.path() / "a.txt", "second\n");
  EXPECT_EQ(read_text(dir.path() / "a.txt"), "second\n");
  write_file_atomic(dir.path() / "a.txt", [](std::ostream& out) { out << "third " << 3 << "\n"; });
  EXPECT_EQ(read_text(dir.path() / "a.txt"), "third 3\n");
  EXPECT_EQ(entries(dir.path()), std::vector<std::string>{"a.txt"});
}

TEST(AtomicWrite, AFullDiskLeavesThePreviousFileAndNoTemporary) {
  test::TempDir dir;
  const fs::path path = dir.path() / "db.bin";
  write_file_atomic(path, "the database that was there\n");
  const std::vector<std::uint8_t> big(1 << 20, 0x5a);
  {
    const FileSizeLimit limit(64 * 1024);
    test::expect_error([&] { write_file_atomic(path, std::span<const std::uint8_t>(big)); },
                       "db.bin: write failed: File too large");
  }
  EXPECT_EQ(read_text(path), "the database that was there\n");
  EXPECT_EQ(entries(dir.path()), std::vector<std::string>{"db.bin"});
  // Room again: the same write goes through.
  write_file_atomic(path, std::span<const std::uint8_t>(big));
  EXPECT_EQ(fs::file_size(path), big.size());
}

TEST(AtomicWrite, AStreamThatThrowsWritesNothing) {
  test::TempDir dir;
  const fs::path path = dir.path() / "out.json";
  write_file_atomic(path, "{}\n");
  EXPECT_THROW(write_file_atomic(path, [](std::ostream& out) {
                 out << "{\"half\": ";
                 throw Error("the writer failed half way");
               }),
               Error);
  EXPECT_EQ(read_text(path), "{}\n");
  EXPECT_EQ(entries(dir.path()), std::vector<std::string>{"out.json"});
}

TEST(AtomicWrite, AMissingOrReadOnlyFolderIsNamed) {
  test::TempDir dir;
  test::expect_error([&] { write_file_atomic(dir.path() / "no-such-folder" / "x.txt", "x"); },
                     "x.txt: cannot create a file in");
  if (::geteuid() != 0) {  // root writes anywhere
    fs::create_directory(dir.path() / "ro");
    fs::permissions(dir.path() / "ro", fs::perms::owner_read | fs::perms::owner_exec);
    EXPECT_THROW(write_file_atomic(dir.path() / "ro" / "x.txt", "x"), Error);
    fs::permissions(dir.path() / "ro", fs::perms::owner_all);
  }
}

TEST(ReadFileBytes, RefusesMissingFoldersAndFilesOverTheLimit) {
  test::TempDir dir;
  write_file_atomic(dir.path() / "ten.bin", "0123456789");
  EXPECT_EQ(read_file_bytes(dir.path() / "ten.bin", 10).size(), 10u);
  test::expect_error([&] { read_file_bytes(dir.path() / "ten.bin", 9); }, "file is 10 bytes, more than the limit of 9");
  EXPECT_THROW(read_file_bytes(dir.path() / "missing.bin"), Error);
  EXPECT_THROW(read_file_bytes(dir.path()), Error);
}

}  // namespace
}  // namespace viewpose
