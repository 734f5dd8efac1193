// Recognition on a live depth stream: a Kinect v1 (freenect), an Xtion (openni2), or a recording.
//
//   live_camera objects.vpdb freenect
//   live_camera objects.vpdb recording:some/folder
//
// Each frame's detections are printed as they come; the program ends with the stream.
#include <chrono>
#include <cstdio>

#include "viewpose/core/error.hpp"
#include "viewpose/recognize/frame.hpp"
#include "viewpose/recognize/recognizer.hpp"
#include "viewpose/sensor/depth_source.hpp"

int main(int argc, char** argv) {
  using namespace viewpose;
  if (argc != 3) {
    std::fprintf(stderr, "usage: live_camera DB.vpdb SOURCE   (freenect, openni2, recording:DIR)\n");
    return 2;
  }
  try {
    const Recognizer recognizer(ViewDatabase::load(argv[1]));  // the recognizer keeps the database
    const auto source = open_depth_source(argv[2]);
    std::printf("%s\n", source->description().c_str());
    int frame_index = 0;
    while (!source->ended()) {
      std::optional<DepthImage> depth = source->next(std::chrono::milliseconds(1000));
      if (!depth) continue;
      const Recognition r = recognizer.recognize(frame_from_depth(std::move(*depth), source->intrinsics()));
      std::printf("frame %d: %zu detections, %.1f ms\n", frame_index++, r.detections.size(), r.times.total_ms);
      for (const Detection& d : r.detections) {
        const Eigen::Vector3d t = d.T_camera_object.translation();
        std::printf("  %s  score %.3f  t = (%.3f, %.3f, %.3f) m\n", d.object_name.c_str(), d.score, t.x(), t.y(), t.z());
      }
    }
  } catch (const Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
