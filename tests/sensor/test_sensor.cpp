// Live input without a camera: Kinect disparity conversion, the fakenect recording format, the
// one-frame mailbox between the camera thread and recognition, recording and replaying, and the
// errors a user meets when a source cannot be opened.
#include <chrono>
#include <cmath>
#include <fstream>
#include <thread>

#include "test_support.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/core/file.hpp"
#include "viewpose/sensor/depth_source.hpp"
#include "viewpose/sensor/kinect_raw.hpp"
#include "viewpose/sensor/latest_frame.hpp"

namespace viewpose {
namespace {

using namespace std::chrono_literals;

TEST(KinectRaw, DisparityRoundTripsWithinHalfAQuantizationStep) {
  std::uint16_t previous = 0;
  for (float z = 0.5f; z <= 4.0f; z += 0.01f) {
    const std::uint16_t raw = kinect_depth_to_disparity(z);
    ASSERT_LT(raw, kKinectNoDisparity) << z;
    EXPECT_GE(raw, previous) << "disparity grows with depth in the Kinect's raw units";
    previous = raw;
    // One raw step is about 0.0031 z^2 metres: 3 mm at 1 m, 5 cm at 4 m.
    const float step = 0.0031f * z * z;
    EXPECT_NEAR(kinect_disparity_to_depth_m(raw), z, 0.5f * step + 1e-5f) << z;
  }
  EXPECT_NEAR(kinect_disparity_to_depth_m(kinect_depth_to_disparity(1.0f)), 1.0f, 0.002f);
}

TEST(KinectRaw, NoMeasurementAndOutOfRangeDepths) {
  EXPECT_TRUE(std::isnan(kinect_disparity_to_depth_m(kKinectNoDisparity)));
  EXPECT_TRUE(std::isnan(kinect_disparity_to_depth_m(1500)));  // 1/z would be negative
  EXPECT_EQ(kinect_depth_to_disparity(NAN), kKinectNoDisparity);
  EXPECT_EQ(kinect_depth_to_disparity(0.1f), kKinectNoDisparity);
  EXPECT_EQ(kinect_depth_to_disparity(20.0f), kKinectNoDisparity);
  const std::vector<std::uint16_t> raw = {kinect_depth_to_disparity(1.0f), kKinectNoDisparity, 0, 700};
  const DepthImage d = depth_from_kinect_disparity(raw, 2, 2);
  EXPECT_NEAR(d.at(0, 0), 1.0f, 0.002f);
  EXPECT_TRUE(std::isnan(d.at(1, 0)));
  EXPECT_NEAR(d.at(0, 1), 0.3002f, 1e-4f);  // the nearest the fit reaches
  EXPECT_NEAR(d.at(1, 1), 0.8466f, 1e-4f);
  EXPECT_THROW(depth_from_kinect_disparity(raw, 3, 2), Error);
}

TEST(KinectRaw, FakenectRecordingHoldsTheRawBufferBehindAOneLineHeader) {
  test::TempDir dir;
  DepthImage a(640, 480), b(640, 480);
  a.at(10, 20) = 1.0f;
  b.at(639, 479) = 2.0f;
  const std::vector<DepthImage> frames = {a, b};
  write_fakenect_recording(dir.path() / "rec", frames, 30.0);
  const auto index_bytes = read_file_bytes(dir.path() / "rec" / "INDEX.txt");
  const std::string index(index_bytes.begin(), index_bytes.end());
  EXPECT_EQ(index, "d-1000.000000-0.pgm\nd-1000.033333-1000.pgm\n");
  const auto bytes = read_file_bytes(dir.path() / "rec" / "d-1000.033333-1000.pgm");
  const std::string header = "P5 640 480 65535\n";
  ASSERT_EQ(bytes.size(), header.size() + 640u * 480u * 2u);
  EXPECT_EQ(std::string(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(header.size())), header);
  const auto value = [&](std::size_t pixel) {
    return static_cast<std::uint16_t>(bytes[header.size() + 2 * pixel] | (bytes[header.size() + 2 * pixel + 1] << 8));
  };
  EXPECT_EQ(value(0), kKinectNoDisparity);
  EXPECT_EQ(value(640u * 480u - 1u), kinect_depth_to_disparity(2.0f));
  EXPECT_THROW(write_fakenect_recording(dir.path() / "x", std::vector<DepthImage>{DepthImage(320, 240)}), Error);
  EXPECT_THROW(write_fakenect_recording(dir.path() / "y", std::vector<DepthImage>{}), Error);
}

TEST(LatestFrame, KeepsTheNewestAndCountsTheFramesItReplaced) {
  LatestFrame box;
  for (int k = 1; k <= 3; ++k) box.put(DepthImage(k, 1));
  std::optional<DepthImage> got = box.take(0ms);
  ASSERT_TRUE(got);
  EXPECT_EQ(got->width, 3);
  EXPECT_EQ(box.dropped(), 2u);
  EXPECT_EQ(box.delivered(), 3u);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(box.take(30ms)) << "nothing new";
  EXPECT_GE(std::chrono::steady_clock::now() - t0, 25ms);
  // A taker waiting for a frame wakes when one comes, and when the camera closes.
  std::thread camera([&] {
    std::this_thread::sleep_for(20ms);
    box.put(DepthImage(7, 1));
    std::this_thread::sleep_for(20ms);
    box.close();
  });
  got = box.take(5s);
  ASSERT_TRUE(got);
  EXPECT_EQ(got->width, 7);
  const auto t1 = std::chrono::steady_clock::now();
  EXPECT_FALSE(box.take(5s));
  EXPECT_LT(std::chrono::steady_clock::now() - t1, 2s) << "close() must wake the taker";
  EXPECT_TRUE(box.closed());
  camera.join();
  EXPECT_EQ(box.dropped(), 2u);
}

TEST(Recording, ReplaysWhatWasRecordedInOrderAndEnds) {
  test::TempDir dir;
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  {
    DepthRecorder recorder(dir.path() / "rec", K);
    for (int k = 0; k < 3; ++k) {
      DepthImage d(640, 480);
      d.at(100 + k, 200) = 1.0f + 0.25f * static_cast<float>(k);
      recorder.add(d);
    }
    EXPECT_EQ(recorder.frames(), 3u);
    EXPECT_THROW(recorder.add(DepthImage(320, 240)), Error);
  }
  EXPECT_THROW(DepthRecorder(dir.path() / "rec", K), Error) << "an existing recording is not overwritten";
  const std::unique_ptr<DepthSource> source = open_depth_source("recording:" + (dir.path() / "rec").string());
  EXPECT_EQ(source->intrinsics().width, 640);
  EXPECT_DOUBLE_EQ(source->intrinsics().fx, K.fx);
  for (int k = 0; k < 3; ++k) {
    std::optional<DepthImage> d;
    for (int tries = 0; tries < 20 && !d; ++tries) d = source->next(100ms);
    ASSERT_TRUE(d) << k;
    EXPECT_FLOAT_EQ(d->at(100 + k, 200), 1.0f + 0.25f * static_cast<float>(k)) << "millimetres keep quarter metres exact";
    EXPECT_EQ(d->count_valid(), 1u);
  }
  EXPECT_TRUE(source->ended());
  EXPECT_FALSE(source->next(10ms));
}

TEST(DepthSources, SayWhatIsWrongInOneLine) {
  const auto message = [](const std::string& spec) { return test::error_of([&] { open_depth_source(spec); }); };
  EXPECT_NE(message("webcam").find("unknown source 'webcam'"), std::string::npos);
  EXPECT_NE(message("recording:").find("needs a folder"), std::string::npos);
  EXPECT_NE(message("recording:/no/such/folder").find("no such folder"), std::string::npos);
  EXPECT_NE(message("freenect:abc").find("must be a number"), std::string::npos);
  test::TempDir empty;
  EXPECT_NE(message("recording:" + empty.path().string()).find("no scene_camera.json"), std::string::npos);
  // (Opening a camera through its driver is tested in test_camera_drivers.cpp, a program of its
  // own: the driver libraries keep memory to the end, which the leak checker must not count here.)
  const std::vector<std::string> backends = camera_backends();
  if (std::find(backends.begin(), backends.end(), "openni2") == backends.end()) {
    EXPECT_NE(message("openni2").find("no OpenNI2 support"), std::string::npos);
  }
  if (std::find(backends.begin(), backends.end(), "freenect") == backends.end()) {
    EXPECT_NE(message("freenect").find("no Kinect support"), std::string::npos);
  }
}

}  // namespace
}  // namespace viewpose
