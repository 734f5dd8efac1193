#include "viewpose/sensor/latest_frame.hpp"

namespace viewpose {

void LatestFrame::put(DepthImage frame) {
  {
    const std::lock_guard lock(mutex_);
    if (frame_) ++dropped_;
    frame_ = std::move(frame);
    ++delivered_;
  }
  ready_.notify_one();
}

std::optional<DepthImage> LatestFrame::take(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  ready_.wait_for(lock, timeout, [&] { return frame_.has_value() || closed_; });
  std::optional<DepthImage> out;
  out.swap(frame_);
  return out;
}

void LatestFrame::close() {
  {
    const std::lock_guard lock(mutex_);
    closed_ = true;
  }
  ready_.notify_all();
}

bool LatestFrame::closed() const {
  const std::lock_guard lock(mutex_);
  return closed_;
}

std::uint64_t LatestFrame::dropped() const {
  const std::lock_guard lock(mutex_);
  return dropped_;
}

std::uint64_t LatestFrame::delivered() const {
  const std::lock_guard lock(mutex_);
  return delivered_;
}

}  // namespace viewpose
