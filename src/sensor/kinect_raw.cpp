#include "viewpose/sensor/kinect_raw.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"
#include "viewpose/core/file.hpp"

namespace viewpose {

namespace {

constexpr double kA = 3.3309495161, kB = -0.0030711016;  // 1/z = a + b d
constexpr double kNearestM = 0.3, kFarthestM = 10.0;

}  // namespace

float kinect_disparity_to_depth_m(std::uint16_t raw) {
  if (raw >= kKinectNoDisparity) return NAN;
  const double inverse = kA + kB * raw;
  if (!(inverse > 1.0 / kFarthestM && inverse < 1.0 / kNearestM)) return NAN;
  return static_cast<float>(1.0 / inverse);
}

std::uint16_t kinect_depth_to_disparity(float z_m) {
  if (!(z_m >= kNearestM && z_m <= kFarthestM)) return kKinectNoDisparity;
  const double d = (1.0 / z_m - kA) / kB;
  return static_cast<std::uint16_t>(std::lround(std::clamp(d, 0.0, 2046.0)));
}

DepthImage depth_from_kinect_disparity(std::span<const std::uint16_t> raw, int width, int height) {
  if (width <= 0 || height <= 0 || raw.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw Error(fmt::format("kinect depth: {} values for a {}x{} image", raw.size(), width, height));
  }
  DepthImage depth(width, height);
  for (std::size_t i = 0; i < raw.size(); ++i) depth.depth_m[i] = kinect_disparity_to_depth_m(raw[i] & 0x07ff);
  return depth;
}

void write_fakenect_recording(const std::filesystem::path& dir, std::span<const DepthImage> frames, double fps) {
  if (frames.empty()) throw Error("fakenect recording: no frames to write");
  if (!(fps > 0 && fps <= 1000)) throw Error(fmt::format("fakenect recording: {} frames a second makes no sense", fps));
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Error(fmt::format("fakenect recording: cannot create {}: {}", dir.string(), ec.message()));
  std::string index;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const DepthImage& f = frames[k];
    if (f.width != 640 || f.height != 480) {
      throw Error(fmt::format("fakenect recording: frame {} is {}x{}; fakenect plays 640x480 only", k, f.width, f.height));
    }
    // fakenect reads "%c-%lf-%u": the type, the recording time in seconds, the device timestamp.
    const double time_s = 1000.0 + static_cast<double>(k) / fps;
    const auto timestamp = static_cast<unsigned>(k * 1000);
    const std::string name = fmt::format("d-{:.6f}-{}.pgm", time_s, timestamp);
    std::string bytes = fmt::format("P5 {} {} 65535\n", f.width, f.height);
    bytes.reserve(bytes.size() + f.depth_m.size() * 2);
    for (const float z : f.depth_m) {
      const std::uint16_t raw = kinect_depth_to_disparity(z);
      bytes.push_back(static_cast<char>(raw & 0xff));  // little-endian, as the USB buffer
      bytes.push_back(static_cast<char>(raw >> 8));
    }
    write_file_atomic(dir / name, bytes);
    index += name + "\n";
  }
  write_file_atomic(dir / "INDEX.txt", index);
}

}  // namespace viewpose
