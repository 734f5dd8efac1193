#include "viewpose/sensor/depth_source.hpp"

#include <algorithm>
#include <charconv>
#include <thread>

#include <fmt/format.h>

#include "backends.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/io/depth_png.hpp"
#include "viewpose/core/file.hpp"

namespace viewpose {

namespace {

// Replays a folder DepthRecorder wrote, at 30 frames a second as the camera gave them.
class RecordingSource final : public DepthSource {
 public:
  explicit RecordingSource(const std::filesystem::path& dir) : dir_(dir) {
    const std::filesystem::path cameras = dir / "scene_camera.json";
    if (!std::filesystem::is_regular_file(cameras)) {
      throw Error(fmt::format("recording {}: no scene_camera.json (not a folder viewpose live --record wrote)", dir.string()));
    }
    const std::vector<std::uint8_t> text = read_file_bytes(cameras, std::size_t{256} << 20);
    const SceneCameras all = parse_scene_camera(std::string_view(reinterpret_cast<const char*>(text.data()), text.size()),
                                                cameras.string());
    for (const auto& [id, camera] : all) {
      frames_.push_back({dir / "depth" / fmt::format("{:06d}.png", id), camera});
    }
    if (frames_.empty()) throw Error(fmt::format("recording {}: no frames", dir.string()));
    K_ = frames_.front().second.K;
    if (K_.width <= 0 || K_.height <= 0) {
      const DepthImage first = read_depth_png(frames_.front().first, frames_.front().second.depth_scale_mm / 1000.0);
      K_.width = first.width;
      K_.height = first.height;
    }
  }
  std::optional<DepthImage> next(std::chrono::milliseconds timeout) override {
    if (ended()) return std::nullopt;
    const auto due = last_ + std::chrono::microseconds(33333);
    const auto now = std::chrono::steady_clock::now();
    if (due > now) {
      if (due - now > timeout) {
        std::this_thread::sleep_for(timeout);
        return std::nullopt;
      }
      std::this_thread::sleep_until(due);
    }
    last_ = std::chrono::steady_clock::now();
    const auto& [path, camera] = frames_[next_++];
    DepthImage depth = read_depth_png(path, camera.depth_scale_mm / 1000.0);
    if (depth.width != K_.width || depth.height != K_.height) {
      throw Error(fmt::format("recording {}: {} is {}x{}, the recording {}x{}", dir_.string(), path.filename().string(),
                              depth.width, depth.height, K_.width, K_.height));
    }
    return depth;
  }
  bool ended() const override { return next_ >= frames_.size(); }
  CameraIntrinsics intrinsics() const override { return K_; }
  std::string description() const override {
    return fmt::format("recording {} ({} frames)", dir_.string(), frames_.size());
  }

 private:
  std::filesystem::path dir_;
  std::vector<std::pair<std::filesystem::path, BopCamera>> frames_;
  CameraIntrinsics K_;
  std::size_t next_ = 0;
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace

namespace detail {

std::unique_ptr<DepthSource> open_recording(const std::filesystem::path& dir) {
  if (!std::filesystem::is_directory(dir)) throw Error(fmt::format("recording {}: no such folder", dir.string()));
  return std::make_unique<RecordingSource>(dir);
}

#ifndef VIEWPOSE_HAVE_FREENECT
std::unique_ptr<DepthSource> open_freenect(int) {
  throw Error("this build has no Kinect support: install libfreenect-dev and rebuild (make does both)");
}
#endif
#ifndef VIEWPOSE_HAVE_OPENNI2
std::unique_ptr<DepthSource> open_openni2(const std::string&) {
  throw Error("this build has no OpenNI2 support: install libopenni2-dev and rebuild (make does both)");
}
#endif

}  // namespace detail

std::unique_ptr<DepthSource> open_depth_source(std::string_view spec) {
  const std::size_t colon = spec.find(':');
  const std::string_view kind = spec.substr(0, colon);
  const std::string_view arg = colon == std::string_view::npos ? std::string_view{} : spec.substr(colon + 1);
  if (kind == "freenect") {
    int index = 0;
    if (!arg.empty()) {
      const auto [end, ec] = std::from_chars(arg.data(), arg.data() + arg.size(), index);
      if (ec != std::errc{} || end != arg.data() + arg.size() || index < 0 || index > 64) {
        throw Error(fmt::format("source '{}': the Kinect's index must be a number from 0", spec));
      }
    }
    return detail::open_freenect(index);
  }
  if (kind == "openni2") return detail::open_openni2(std::string(arg));
  if (kind == "recording") {
    if (arg.empty()) throw Error("source 'recording:' needs a folder: recording:DIR");
    return detail::open_recording(std::filesystem::path(std::string(arg)));
  }
  throw Error(fmt::format("unknown source '{}': use freenect[:INDEX], openni2[:URI or FILE.oni] or recording:DIR", spec));
}

std::vector<std::string> camera_backends() {
  std::vector<std::string> out;
#ifdef VIEWPOSE_HAVE_FREENECT
  out.emplace_back("freenect");
#endif
#ifdef VIEWPOSE_HAVE_OPENNI2
  out.emplace_back("openni2");
#endif
  return out;
}

DepthRecorder::DepthRecorder(std::filesystem::path dir, const CameraIntrinsics& K) : dir_(std::move(dir)), K_(K) {
  K_.validate();
  std::error_code ec;
  std::filesystem::create_directories(dir_ / "depth", ec);
  if (ec) throw Error(fmt::format("record: cannot create {}: {}", (dir_ / "depth").string(), ec.message()));
  if (std::filesystem::exists(dir_ / "scene_camera.json")) {
    throw Error(fmt::format("record: {} already holds a recording; choose a new folder", dir_.string()));
  }
}

void DepthRecorder::add(const DepthImage& depth) {
  if (depth.width != K_.width || depth.height != K_.height) {
    throw Error(fmt::format("record: a {}x{} frame from a {}x{} camera", depth.width, depth.height, K_.width, K_.height));
  }
  write_depth_png(dir_ / "depth" / fmt::format("{:06d}.png", frames_), depth, 0.001);
  ++frames_;
  // The frame's file first, then the list that names it: a recording cut short lists only whole
  // frames. The list is rewritten with every frame for the first ten seconds, then once a second
  // (a long recording would otherwise rewrite megabytes per frame).
  if (frames_ <= 300 || frames_ % 30 == 0) flush();
}

void DepthRecorder::flush() {
  if (frames_ == listed_) return;
  SceneCameras cameras;
  for (std::size_t k = 0; k < frames_; ++k) cameras[static_cast<ImageId>(k)] = BopCamera{K_, 1.0};
  write_file_atomic(dir_ / "scene_camera.json", format_scene_camera(cameras));
  listed_ = frames_;
}

DepthRecorder::~DepthRecorder() {
  try {
    flush();
  } catch (const std::exception&) {
    // A destructor cannot report; the frames listed so far stay readable.
  }
}

}  // namespace viewpose
