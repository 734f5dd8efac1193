#pragma once
// A progress bar on stderr, shown only on a terminal (never in logs or CI).
#include <cstddef>
#include <cstdio>
#include <string>

#include <unistd.h>

#include <fmt/format.h>

namespace viewpose::cli {

class ProgressBar {
 public:
  ProgressBar(std::string label, std::size_t total) : label_(std::move(label)), total_(total), shown_(isatty(STDERR_FILENO) != 0) {}
  ~ProgressBar() {
    if (shown_ && drawn_) fmt::print(stderr, "\n");
  }
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  void update(std::size_t done) {
    if (!shown_ || total_ == 0) return;
    const int width = 30, filled = static_cast<int>(width * done / total_);
    fmt::print(stderr, "\r{} [{}{}] {}/{}", label_, std::string(static_cast<std::size_t>(filled), '#'),
               std::string(static_cast<std::size_t>(width - filled), ' '), done, total_);
    std::fflush(stderr);
    drawn_ = true;
  }

 private:
  std::string label_;
  std::size_t total_;
  bool shown_;
  bool drawn_ = false;
};

}  // namespace viewpose::cli
