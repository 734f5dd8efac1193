// ASUS Xtion, PrimeSense and Kinect cameras, and .oni recordings, through OpenNI2: millimetre depth.
#include <cmath>
#include <cstdint>
#include <string>

#include <fmt/format.h>
#include <openni2/OpenNI.h>

#include "backends.hpp"
#include "viewpose/core/error.hpp"

namespace viewpose::detail {

namespace {

std::string openni_error() {
  std::string e = openni::OpenNI::getExtendedError();
  // OpenNI's messages come with tabs and line breaks: one line.
  for (char& c : e)
    if (c == '\n' || c == '\t') c = ' ';
  const auto first = e.find_first_not_of(' '), last = e.find_last_not_of(' ');
  return first == std::string::npos ? std::string("no reason given") : e.substr(first, last - first + 1);
}

class OpenNi2Source final : public DepthSource {
 public:
  explicit OpenNi2Source(const std::string& uri) : uri_(uri) {
    if (openni::OpenNI::initialize() != openni::STATUS_OK) {
      throw Error(fmt::format("openni2: cannot start OpenNI2: {}", openni_error()));
    }
    if (device_.open(uri.empty() ? openni::ANY_DEVICE : uri.c_str()) != openni::STATUS_OK) {
      const std::string why = openni_error();
      openni::OpenNI::shutdown();
      throw Error(uri.empty() ? fmt::format("openni2: no depth camera found ({})", why)
                              : fmt::format("openni2: cannot open '{}' ({})", uri, why));
    }
    if (device_.isFile() && device_.getPlaybackControl()) {
      device_.getPlaybackControl()->setRepeatEnabled(false);
      device_.getPlaybackControl()->setSpeed(1.0f);  // as recorded
    }
    if (!device_.hasSensor(openni::SENSOR_DEPTH) || stream_.create(device_, openni::SENSOR_DEPTH) != openni::STATUS_OK) {
      close();
      throw Error(fmt::format("openni2: '{}' has no depth stream", description()));
    }
    // 640x480 millimetres at 30 Hz when offered, else the first millimetre mode.
    const openni::Array<openni::VideoMode>& modes = stream_.getSensorInfo().getSupportedVideoModes();
    int chosen = -1;
    for (int k = 0; k < modes.getSize(); ++k) {
      const openni::VideoMode& m = modes[k];
      if (m.getPixelFormat() != openni::PIXEL_FORMAT_DEPTH_1_MM) continue;
      if (chosen < 0 || (m.getResolutionX() == 640 && m.getResolutionY() == 480 && m.getFps() == 30)) chosen = k;
    }
    if (chosen >= 0 && !device_.isFile()) stream_.setVideoMode(modes[chosen]);
    stream_.setMirroringEnabled(false);
    const openni::VideoMode mode = stream_.getVideoMode();
    if (mode.getPixelFormat() != openni::PIXEL_FORMAT_DEPTH_1_MM && mode.getPixelFormat() != openni::PIXEL_FORMAT_DEPTH_100_UM) {
      close();
      throw Error("openni2: the depth stream offers no millimetre format");
    }
    metres_per_unit_ = mode.getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_1_MM ? 0.001f : 0.0001f;
    K_.width = mode.getResolutionX();
    K_.height = mode.getResolutionY();
    // A pinhole with the stream's fields of view, centred: OpenNI2 reports no other calibration.
    // A device that reports none gets the nominal Kinect / Xtion focal length at its resolution.
    const double hfov = stream_.getHorizontalFieldOfView(), vfov = stream_.getVerticalFieldOfView();
    const bool fov_known = hfov > 0.1 && hfov < 3.0 && vfov > 0.1 && vfov < 3.0;
    K_.fx = fov_known ? 0.5 * K_.width / std::tan(0.5 * hfov) : 525.0 * K_.width / 640.0;
    K_.fy = fov_known ? 0.5 * K_.height / std::tan(0.5 * vfov) : 525.0 * K_.width / 640.0;
    K_.cx = 0.5 * (K_.width - 1);
    K_.cy = 0.5 * (K_.height - 1);
    if (stream_.start() != openni::STATUS_OK) {
      close();
      throw Error(fmt::format("openni2: cannot start the depth stream: {}", openni_error()));
    }
    if (device_.isFile() && device_.getPlaybackControl()) frames_in_file_ = device_.getPlaybackControl()->getNumberOfFrames(stream_);
  }
  ~OpenNi2Source() override { close(); }
  OpenNi2Source(const OpenNi2Source&) = delete;
  OpenNi2Source& operator=(const OpenNi2Source&) = delete;

  std::optional<DepthImage> next(std::chrono::milliseconds timeout) override {
    if (ended_) return std::nullopt;
    openni::VideoStream* streams[] = {&stream_};
    int ready = -1;
    const openni::Status waited = openni::OpenNI::waitForAnyStream(streams, 1, &ready, static_cast<int>(timeout.count()));
    if (waited == openni::STATUS_TIME_OUT) return std::nullopt;
    if (waited != openni::STATUS_OK) throw Error(fmt::format("openni2: the depth stream failed: {}", openni_error()));
    openni::VideoFrameRef frame;
    if (stream_.readFrame(&frame) != openni::STATUS_OK || !frame.isValid()) {
      throw Error(fmt::format("openni2: cannot read a depth frame: {}", openni_error()));
    }
    if (frame.getWidth() != K_.width || frame.getHeight() != K_.height) {
      throw Error(fmt::format("openni2: a {}x{} frame from a {}x{} stream", frame.getWidth(), frame.getHeight(), K_.width, K_.height));
    }
    DepthImage depth(K_.width, K_.height);
    const auto* bytes = static_cast<const std::uint8_t*>(frame.getData());
    for (int v = 0; v < K_.height; ++v) {
      const auto* row = reinterpret_cast<const openni::DepthPixel*>(bytes + static_cast<std::ptrdiff_t>(v) * frame.getStrideInBytes());
      for (int u = 0; u < K_.width; ++u) depth.at(u, v) = row[u] == 0 ? NAN : metres_per_unit_ * static_cast<float>(row[u]);
    }
    if (frames_in_file_ > 0 && frame.getFrameIndex() >= frames_in_file_) ended_ = true;
    return depth;
  }
  bool ended() const override { return ended_; }
  CameraIntrinsics intrinsics() const override { return K_; }
  std::string description() const override {
    if (device_.isValid()) {
      const openni::DeviceInfo& info = device_.getDeviceInfo();
      return fmt::format("{} {} through OpenNI2{}", info.getVendor(), info.getName(), device_.isFile() ? " (recording)" : "");
    }
    return uri_.empty() ? std::string("an OpenNI2 camera") : uri_;
  }

 private:
  void close() {
    if (stream_.isValid()) {
      stream_.stop();
      stream_.destroy();
    }
    if (device_.isValid()) device_.close();
    openni::OpenNI::shutdown();
  }

  std::string uri_;
  openni::Device device_;
  openni::VideoStream stream_;
  CameraIntrinsics K_;
  float metres_per_unit_ = 0.001f;
  int frames_in_file_ = 0;
  bool ended_ = false;
};

}  // namespace

std::unique_ptr<DepthSource> open_openni2(const std::string& uri) { return std::make_unique<OpenNi2Source>(uri); }

}  // namespace viewpose::detail
