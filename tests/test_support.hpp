#pragma once
// Helpers shared by the tests: temporary folders, the shared real data, deterministic sample clouds.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <span>
#include <unistd.h>
#include <string>
#include <string_view>
#include <vector>

#include "viewpose/core/mesh.hpp"
#include "viewpose/core/point_cloud.hpp"

namespace viewpose::test {

namespace fs = std::filesystem;

/// ../shared beside the checkout (data, reference fixtures), or $VIEWPOSE_SHARED_DIR when set.
/// Absent in a user's clone.
inline fs::path shared_dir() {
  const char* env = std::getenv("VIEWPOSE_SHARED_DIR");
  return fs::path(env && *env ? env : VIEWPOSE_SHARED_DIR);
}
inline fs::path shared_data() { return shared_dir() / "data"; }

/// Skips the calling test, with a clear message, when ../shared/data is not there.
#define VIEWPOSE_REQUIRE_SHARED_DATA()                                                                  \
  do {                                                                                                  \
    if (!std::filesystem::is_directory(::viewpose::test::shared_data())) {                              \
      GTEST_SKIP() << "skipped: " << ::viewpose::test::shared_data().string()                          \
                   << " is absent (real captures live there in CI; see the README)";                  \
    }                                                                                                   \
  } while (0)

/// A fresh folder under the system temp dir, removed with everything in it at scope exit.
class TempDir {
 public:
  TempDir() {
    static int counter = 0;
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::temp_directory_path() /
            ("viewpose-test-" + std::string(info ? info->name() : "x") + "-" + std::to_string(::getpid()) + "-" +
             std::to_string(counter++));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

inline std::span<const std::uint8_t> bytes_of(std::string_view s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

inline std::vector<std::uint8_t> to_bytes(std::string_view s) { return {s.begin(), s.end()}; }

/// A deterministic cloud. Organized clouds get NaN holes, as a real frame has.
inline PointCloud sample_cloud(int width, int height, bool normals, bool colours, bool labels, unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> coord(-1.0f, 1.0f);
  PointCloud c;
  c.width = width;
  c.height = height;
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < n; ++i) {
    const bool hole = height > 1 && i % 7 == 3;
    c.points.push_back(hole ? Eigen::Vector3f(nan, nan, nan) : Eigen::Vector3f(coord(rng), coord(rng), 1.0f + coord(rng)));
    if (normals) c.normals.push_back(Eigen::Vector3f(coord(rng), coord(rng), coord(rng)).normalized());
    if (normals) c.curvature.push_back(0.5f * (1.0f + coord(rng)));
    if (colours) c.rgba.push_back(0xff000000u | static_cast<std::uint32_t>(rng() & 0xffffffu));
    if (labels) c.labels.push_back(static_cast<std::uint32_t>(rng() % 40));
  }
  return c;
}

/// A square of side 2 * half in the z = 0 plane (two triangles): a wall, a card, a floor tile.
inline TriangleMesh square(float half) {
  TriangleMesh m;
  m.vertices = {{-half, -half, 0}, {half, -half, 0}, {half, half, 0}, {-half, half, 0}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

/// Bitwise equality of float vectors, so that NaN == NaN.
inline bool same_bits(const std::vector<Eigen::Vector3f>& a, const std::vector<Eigen::Vector3f>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Eigen::Vector3f)) == 0);
}

inline void expect_same_cloud(const PointCloud& a, const PointCloud& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_TRUE(same_bits(a.points, b.points));
  EXPECT_TRUE(same_bits(a.normals, b.normals));
  EXPECT_EQ(a.curvature.size(), b.curvature.size());
  for (std::size_t i = 0; i < std::min(a.curvature.size(), b.curvature.size()); ++i) {
    EXPECT_EQ(a.curvature[i], b.curvature[i]) << i;
  }
  EXPECT_EQ(a.rgba, b.rgba);
  EXPECT_EQ(a.labels, b.labels);
}

/// Runs `f`: the message of the exception it throws, or "no error" when it returns.
template <typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

/// Runs `f`, expects a viewpose::Error whose message is one line containing `needle`.
template <typename F>
void expect_error(F&& f, std::string_view needle) {
  try {
    f();
    ADD_FAILURE() << "expected an error containing '" << needle << "'";
  } catch (const std::exception& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(needle), std::string::npos) << "message: " << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "message is not one line: " << msg;
  }
}

}  // namespace viewpose::test
