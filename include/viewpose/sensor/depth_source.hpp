#pragma once
// Where live depth frames come from: a camera through its driver library, or a recording.
//   freenect[:INDEX]        Kinect v1 through libfreenect (raw 11-bit disparity, see kinect_raw.hpp);
//                           a fakenect recording when run with libfreenect's fakenect library
//   openni2[:URI|FILE.oni]  ASUS Xtion, PrimeSense or Kinect through OpenNI2 (millimetre depth), or
//                           an OpenNI2 recording
//   recording:DIR           a folder `viewpose live --record DIR` wrote (a BOP scene folder)
// The camera back-ends are built when their libraries are found (libfreenect-dev, libopenni2-dev);
// a build without one says so when it is asked for.
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"

namespace viewpose {

class DepthSource {
 public:
  virtual ~DepthSource() = default;
  /// The next depth frame, waiting at most `timeout`; nullopt when none came in time or the source
  /// has ended. Throws viewpose::Error when the device fails.
  virtual std::optional<DepthImage> next(std::chrono::milliseconds timeout) = 0;
  /// A recording has no more frames (a camera never ends by itself).
  virtual bool ended() const = 0;
  /// The intrinsics the device reports, or the nominal ones of its kind.
  virtual CameraIntrinsics intrinsics() const = 0;
  /// What is open, in words ("Kinect 0 through libfreenect").
  virtual std::string description() const = 0;
};

/// Opens a source given as above; a missing device, file or back-end gives a one-line Error.
std::unique_ptr<DepthSource> open_depth_source(std::string_view spec);

/// The camera back-ends this build has ("freenect", "openni2").
std::vector<std::string> camera_backends();

/// Writes frames as a BOP scene folder, DIR/depth/NNNNNN.png (millimetres) and
/// DIR/scene_camera.json, so that `recording:DIR` replays them and `viewpose bop` can score them
/// once a scene_gt.json is added. Every file is written atomically; scene_camera.json lists the
/// frames written so far (rewritten with each of the first 300 frames, then once every 30, and on
/// flush() and destruction), so a recording cut short is whole up to its last listed frame.
class DepthRecorder {
 public:
  /// Refuses a folder that already holds a recording.
  DepthRecorder(std::filesystem::path dir, const CameraIntrinsics& K);
  ~DepthRecorder();
  DepthRecorder(const DepthRecorder&) = delete;
  DepthRecorder& operator=(const DepthRecorder&) = delete;
  void add(const DepthImage& depth);
  void flush();
  std::size_t frames() const { return frames_; }

 private:
  std::filesystem::path dir_;
  CameraIntrinsics K_;
  std::size_t frames_ = 0, listed_ = 0;
};

}  // namespace viewpose
