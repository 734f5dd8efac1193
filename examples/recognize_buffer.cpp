// Recognizing a depth buffer held in memory, as a robot's program gets it from its camera driver:
// 16-bit depth in millimetres, row-major, with the camera's intrinsics. Nothing is read from files:
// the database is built from a mesh made in code (a soup can), and the "camera" is a rendering of
// it 0.8 m away, so that the printed pose can be checked against the one it was drawn at.
//
//   recognize_buffer
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "viewpose/database/view_database.hpp"
#include "viewpose/recognize/frame.hpp"
#include "viewpose/recognize/recognizer.hpp"
#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/shapes.hpp"

int main() {
  using namespace viewpose;
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();

  // The objects to find, in metres, and their views (a few seconds; save() keeps them for next time).
  const std::vector<ObjectModel> objects = {{1, "can", make_can()}};
  const ViewDatabase db = build_view_database(objects, DatabaseParams{});

  // What a driver hands over: millimetres, 0 where the sensor saw nothing.
  const Transform T_camera_can_true = make_transform(
      Eigen::AngleAxisd(-1.2, Eigen::Vector3d::UnitX()).toRotationMatrix(), Eigen::Vector3d(0.05, 0.02, 0.8));
  const MeshInstance can{&objects[0].mesh, T_camera_can_true};
  const DepthImage rendered = render({&can, 1}, K).depth;
  std::vector<std::uint16_t> buffer(rendered.depth_m.size());
  for (std::size_t i = 0; i < buffer.size(); ++i) {
    const float z = rendered.depth_m[i];
    buffer[i] = std::isfinite(z) ? static_cast<std::uint16_t>(std::lround(z * 1000.0f)) : 0;
  }

  // The buffer into a frame: metres inside, 0 becomes "no measurement".
  DepthImage depth(K.width, K.height);
  for (std::size_t i = 0; i < buffer.size(); ++i) {
    if (buffer[i] > 0) depth.depth_m[i] = 0.001f * static_cast<float>(buffer[i]);
  }
  const Recognizer recognizer(db);
  const Recognition r = recognizer.recognize(frame_from_depth(std::move(depth), K));

  for (const Detection& d : r.detections) {
    const Eigen::Vector3d t = d.T_camera_object.translation();
    const double moved_mm = 1000.0 * (t - T_camera_can_true.translation()).norm();
    std::printf("%s  score %.3f  t = (%.3f, %.3f, %.3f) m  (%.1f mm from where it was drawn)  %.1f ms\n",
                d.object_name.c_str(), d.score, t.x(), t.y(), t.z(), moved_mm, r.times.total_ms);
  }
  if (r.detections.empty()) std::printf("nothing found (%.1f ms)\n", r.times.total_ms);
  return r.detections.size() == 1 ? 0 : 1;
}
