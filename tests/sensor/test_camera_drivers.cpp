// The camera back-ends through their real driver libraries, without a camera. ctest runs this
// program twice: with the driver libraries as installed (no device: clear errors), and with
// libfreenect's fakenect library in front of the real one (LD_LIBRARY_PATH), as its `fakenect`
// wrapper does, so that a simulated scene travels the path a Kinect's frames do: raw 11-bit
// disparity in freenect_process_events' depth callback, converted by viewpose, recognized, and
// checked against the ground truth of the simulation. Leak checks are off for both runs: the
// drivers keep memory to the end of the process, and they are not ours.
#include <cstdlib>

#include "test_support.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/eval/metrics.hpp"
#include "viewpose/recognize/recognizer.hpp"
#include "viewpose/render/shapes.hpp"
#include "viewpose/sensor/depth_source.hpp"
#include "viewpose/sensor/kinect_raw.hpp"
#include "viewpose/simulate/scene.hpp"

namespace viewpose {
namespace {

std::string open_error(const std::string& spec) {
  return test::error_of([&] { open_depth_source(spec); });
}

#ifdef VIEWPOSE_TEST_OPENNI2
TEST(CameraDrivers, OpenNi2SaysWhatIsMissing) {
  // A recording that is not there is always an error; with no camera attached, so is any device.
  EXPECT_EQ(open_error("openni2:/no/such/file.oni").rfind("openni2: cannot open '/no/such/file.oni'", 0), 0u);
  const std::string any = open_error("openni2");
  if (any != "no error") {
    EXPECT_EQ(any.rfind("openni2: no depth camera found", 0), 0u) << any;
  }
}
#endif

#ifdef VIEWPOSE_TEST_FREENECT
TEST(CameraDrivers, LibfreenectSaysWhatIsMissing) {
  if (std::getenv("FAKENECT_PATH")) GTEST_SKIP() << "running under fakenect";
  const std::string e = open_error("freenect:3");
  if (e != "no error") {
    EXPECT_EQ(e.rfind("freenect: ", 0), 0u) << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << "one line";
  }
}

TEST(FakenectReplay, PosesThroughLibfreenectMatchTheGroundTruth) {
  const ObjectModel jug{1, "jug", make_jug()};
  SeedExperimentOptions setup;
  setup.distances_m = {0.75, 1.00, 1.25};
  setup.orientations = 2;
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  const SimDataset scenes = make_seed_experiment(jug, K, setup, 5);
  std::vector<DepthImage> frames;
  std::vector<Transform> truth;
  for (const SimScene& scene : scenes.scenes) {
    for (std::size_t k = 0; k < scene.images.size(); ++k) {
      const SimulatedFrame f = simulate_image(scenes, scene.images[k], SensorModel::kinect_v1(), 10 * scene.scene_id + k);
      frames.push_back(f.depth);
      truth.push_back(f.gt.at(0).T_camera_object);
    }
  }
  test::TempDir dir;
  write_fakenect_recording(dir.path(), frames);
  ASSERT_EQ(::setenv("FAKENECT_PATH", dir.path().c_str(), 1), 0);

  // Fails with "no Kinect found" when the real libfreenect was loaded instead of fakenect.
  const std::unique_ptr<DepthSource> source = open_depth_source("freenect");
  EXPECT_EQ(source->intrinsics().width, 640);
  const ViewDatabase db = build_view_database(std::span(&jug, 1), DatabaseParams{});
  const Recognizer recognizer(db);
  std::size_t received = 0, right = 0;
  while (!source->ended() && received < frames.size()) {
    std::optional<DepthImage> depth = source->next(std::chrono::seconds(2));
    if (!depth) continue;
    const std::size_t k = received++;
    // The frame is the simulated one, quantized as a Kinect quantizes: about 3 mm per step at 1 m.
    const DepthImage& sent = frames[k];
    std::size_t both = 0;
    double worst = 0;
    for (std::size_t i = 0; i < sent.depth_m.size(); ++i) {
      if (!std::isfinite(sent.depth_m[i]) || !std::isfinite(depth->depth_m[i])) continue;
      ++both;
      worst = std::max(worst, static_cast<double>(std::abs(sent.depth_m[i] - depth->depth_m[i]) / (sent.depth_m[i] * sent.depth_m[i])));
    }
    EXPECT_GT(both, sent.count_valid() * 99 / 100) << k;
    EXPECT_LT(worst, 0.0031 / 2 + 1e-4) << "frame " << k << ": more than half a disparity step off";
    const Recognition r = recognizer.recognize(frame_from_depth(std::move(*depth), source->intrinsics()));
    ASSERT_EQ(r.detections.size(), 1u) << "frame " << k;
    const double error = add_s_error(r.detections[0].T_camera_object, truth[k], db.objects[0].model_points);
    EXPECT_LT(error, 0.1 * db.objects[0].diameter_m) << "frame " << k;
    right += error < 0.1 * db.objects[0].diameter_m ? 1 : 0;
  }
  EXPECT_EQ(received, frames.size()) << "every recorded frame arrives, in order";
  EXPECT_EQ(right, frames.size());
}
#endif

}  // namespace
}  // namespace viewpose
