#include "viewpose/core/camera.hpp"

#include <cmath>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"

namespace viewpose {

void CameraIntrinsics::validate() const {
  constexpr int kMaxSide = 1 << 15;  // no depth sensor comes near 32768 pixels a side
  if (!(std::isfinite(fx) && std::isfinite(fy) && fx > 0 && fy > 0)) {
    throw Error(fmt::format("camera intrinsics: focal lengths must be positive and finite (fx={}, fy={})", fx, fy));
  }
  if (!(std::isfinite(cx) && std::isfinite(cy))) {
    throw Error(fmt::format("camera intrinsics: principal point is not finite (cx={}, cy={})", cx, cy));
  }
  if (width <= 0 || height <= 0 || width > kMaxSide || height > kMaxSide) {
    throw Error(fmt::format("camera intrinsics: image size {}x{} is out of range (1..{})", width, height, kMaxSide));
  }
}

CameraIntrinsics CameraIntrinsics::kinect_v1() { return {525.0, 525.0, 319.5, 239.5, 640, 480}; }

}  // namespace viewpose
