// Kinect v1 through libfreenect: raw 11-bit disparity frames, converted to metres (kinect_raw.hpp).
// The same code replays a fakenect recording when libfreenect's fakenect library is loaded in its
// place (LD_LIBRARY_PATH=/usr/lib/<arch>/fakenect, FAKENECT_PATH=DIR).
#include <sys/time.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include <fmt/format.h>
#include <libfreenect.h>

#include "backends.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/sensor/kinect_raw.hpp"

namespace viewpose::detail {

namespace {

class FreenectSource final : public DepthSource {
 public:
  explicit FreenectSource(int index) : index_(index) {
    if (freenect_init(&context_, nullptr) < 0 || !context_) {
      throw Error("freenect: libfreenect could not start (no USB access? try as root or add the udev rules)");
    }
    freenect_set_log_level(context_, FREENECT_LOG_FATAL);
    freenect_select_subdevices(context_, FREENECT_DEVICE_CAMERA);  // not the motor or the microphones
    const int devices = freenect_num_devices(context_);
    if (devices <= index) {
      freenect_shutdown(context_);
      throw Error(devices <= 0 ? std::string("freenect: no Kinect found (is it plugged in and powered?)")
                               : fmt::format("freenect: Kinect {} asked for, {} found", index, devices));
    }
    if (freenect_open_device(context_, &device_, index) < 0 || !device_) {
      freenect_shutdown(context_);
      throw Error(fmt::format("freenect: cannot open Kinect {} (in use by another program?)", index));
    }
    const freenect_frame_mode mode = freenect_find_depth_mode(FREENECT_RESOLUTION_MEDIUM, FREENECT_DEPTH_11BIT);
    if (!mode.is_valid || freenect_set_depth_mode(device_, mode) < 0) {
      close();
      throw Error("freenect: the Kinect refuses 640x480 11-bit depth");
    }
    width_ = mode.width;
    height_ = mode.height;
    freenect_set_user(device_, this);
    freenect_set_depth_callback(device_, &FreenectSource::on_depth);
    if (freenect_start_depth(device_) < 0) {
      close();
      throw Error("freenect: cannot start the depth stream");
    }
  }
  ~FreenectSource() override { close(); }
  FreenectSource(const FreenectSource&) = delete;
  FreenectSource& operator=(const FreenectSource&) = delete;

  std::optional<DepthImage> next(std::chrono::milliseconds timeout) override {
    if (ended_) return std::nullopt;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    fresh_ = false;
    // Callbacks run inside freenect_process_events, on this thread.
    while (!fresh_) {
      const auto left = std::chrono::duration_cast<std::chrono::microseconds>(deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return std::nullopt;
      timeval tv{static_cast<time_t>(left.count() / 1000000), static_cast<suseconds_t>(left.count() % 1000000)};
      if (freenect_process_events_timeout(context_, &tv) < 0) {
        // fakenect's recording has run out; a real Kinect is gone.
        if (!replaying_) throw Error(fmt::format("freenect: Kinect {} stopped (unplugged?)", index_));
        ended_ = true;
        if (!fresh_) return std::nullopt;
      }
    }
    return depth_from_kinect_disparity(raw_, width_, height_);
  }
  bool ended() const override { return ended_; }
  CameraIntrinsics intrinsics() const override {
    CameraIntrinsics K = CameraIntrinsics::kinect_v1();  // libfreenect reports none
    K.width = width_;
    K.height = height_;
    return K;
  }
  std::string description() const override { return fmt::format("Kinect {} through libfreenect", index_); }

 private:
  static void on_depth(freenect_device* device, void* depth, std::uint32_t) {
    auto* self = static_cast<FreenectSource*>(freenect_get_user(device));
    const auto n = static_cast<std::size_t>(self->width_) * static_cast<std::size_t>(self->height_);
    self->raw_.resize(n);
    std::memcpy(self->raw_.data(), depth, n * sizeof(std::uint16_t));
    self->fresh_ = true;
  }
  void close() {
    if (device_) {
      freenect_stop_depth(device_);
      freenect_close_device(device_);
      device_ = nullptr;
    }
    if (context_) {
      freenect_shutdown(context_);
      context_ = nullptr;
    }
  }

  int index_;
  freenect_context* context_ = nullptr;
  freenect_device* device_ = nullptr;
  int width_ = 640, height_ = 480;
  std::vector<std::uint16_t> raw_;
  bool fresh_ = false, ended_ = false;
  const bool replaying_ = std::getenv("FAKENECT_PATH") != nullptr;  // fakenect in libfreenect's place
};

}  // namespace

std::unique_ptr<DepthSource> open_freenect(int index) { return std::make_unique<FreenectSource>(index); }

}  // namespace viewpose::detail
