#pragma once
// A one-frame mailbox between a camera thread and the recognition loop: a camera delivers frames
// faster than they are recognized, so only the newest waits, and the frames it replaced are counted
// as dropped rather than queued (a queue would only grow, and the poses would lag ever further).
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>

#include "viewpose/core/depth_image.hpp"

namespace viewpose {

class LatestFrame {
 public:
  /// Leaves `frame` for the taker, replacing (and counting as dropped) one not yet taken.
  void put(DepthImage frame);
  /// The newest frame, waiting at most `timeout`; nullopt on time-out, or once closed and empty.
  std::optional<DepthImage> take(std::chrono::milliseconds timeout);
  /// No more frames will come: wakes the taker.
  void close();
  bool closed() const;
  std::uint64_t dropped() const;
  std::uint64_t delivered() const;

 private:
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::optional<DepthImage> frame_;
  bool closed_ = false;
  std::uint64_t dropped_ = 0, delivered_ = 0;
};

}  // namespace viewpose
