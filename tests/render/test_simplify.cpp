// The mesh verification draws: far fewer triangles, the same depth to within the error bound.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "test_support.hpp"
#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/shapes.hpp"
#include "viewpose/render/simplify.hpp"

namespace viewpose {
namespace {

const CameraIntrinsics K = CameraIntrinsics::kinect_v1();

RenderedFrame draw(const TriangleMesh& mesh, const Transform& T) {
  const MeshInstance inst{&mesh, T};
  RenderOptions o;
  o.instances = false;
  return render(std::span(&inst, 1), K, o);
}

// A box whose every face is an n x n grid of quads, each face with vertices of its own (as texture
// seams split a CAD mesh's vertices), wound counter-clockwise seen from outside.
TriangleMesh fine_box(const Eigen::Vector3f& size, int n) {
  TriangleMesh m;
  const Eigen::Vector3f h = 0.5f * size;
  for (int axis = 0; axis < 3; ++axis) {
    for (int side : {-1, 1}) {
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      const auto base = static_cast<std::uint32_t>(m.vertices.size());
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
          Eigen::Vector3f p;
          p[axis] = static_cast<float>(side) * h[axis];
          p[a] = -h[a] + size[a] * static_cast<float>(i) / static_cast<float>(n);
          p[b] = -h[b] + size[b] * static_cast<float>(j) / static_cast<float>(n);
          m.vertices.push_back(p);
        }
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          const auto at = [&](int di, int dj) { return base + static_cast<std::uint32_t>((i + di) * (n + 1) + j + dj); };
          // (a, b, axis) is right-handed: a x b = axis, so (i, j) order faces +axis.
          if (side > 0) {
            m.triangles.push_back({at(0, 0), at(1, 0), at(1, 1)});
            m.triangles.push_back({at(0, 0), at(1, 1), at(0, 1)});
          } else {
            m.triangles.push_back({at(0, 0), at(1, 1), at(1, 0)});
            m.triangles.push_back({at(0, 0), at(0, 1), at(1, 1)});
          }
        }
    }
  }
  return m;
}

// The largest depth difference where both draw the surface, and how many pixels only one draws.
struct Comparison {
  float max_depth_difference = 0;
  float p99_depth_difference = 0;
  std::size_t only_one = 0, both = 0;
};
Comparison compare(const TriangleMesh& a, const TriangleMesh& b, const Transform& T) {
  const RenderedFrame fa = draw(a, T), fb = draw(b, T);
  Comparison c;
  std::vector<float> differences;
  for (std::size_t i = 0; i < fa.depth.depth_m.size(); ++i) {
    const float za = fa.depth.depth_m[i], zb = fb.depth.depth_m[i];
    if (std::isfinite(za) != std::isfinite(zb)) ++c.only_one;
    if (std::isfinite(za) && std::isfinite(zb)) {
      ++c.both;
      differences.push_back(std::abs(za - zb));
      c.max_depth_difference = std::max(c.max_depth_difference, differences.back());
    }
  }
  if (!differences.empty()) {
    auto p99 = differences.begin() + static_cast<std::ptrdiff_t>(0.99 * static_cast<double>(differences.size() - 1));
    std::nth_element(differences.begin(), p99, differences.end());
    c.p99_depth_difference = *p99;
  }
  return c;
}

const Transform kPoses[] = {
    make_transform(Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, 0.5).normalized()).toRotationMatrix(), {0.02, -0.01, 0.7}),
    make_transform(Eigen::AngleAxisd(2.1, Eigen::Vector3d(-0.3, 1, 1).normalized()).toRotationMatrix(), {-0.05, 0.03, 1.1}),
};

TEST(SimplifyForDrawing, AFinelyCutBoxBecomesAFewTrianglesThatDrawTheSameDepth) {
  const TriangleMesh box = fine_box({0.21f, 0.16f, 0.07f}, 40);  // 19,200 triangles, seams on every edge
  ASSERT_EQ(closed_mesh_winding(box), 0);                          // the seams leave it open
  const TriangleMesh drawn = simplify_for_drawing(box, 0.001f);
  EXPECT_LE(drawn.triangles.size(), 100u);
  EXPECT_GE(drawn.triangles.size(), 12u);
  EXPECT_NE(closed_mesh_winding(drawn), 0) << "welded, the box is closed and keeps its winding";
  EXPECT_TRUE(drawn.normals.empty());
  drawn.check_consistent();
  for (const Transform& T : kPoses) {
    const Comparison c = compare(box, drawn, T);
    EXPECT_GT(c.both, 2000u);
    EXPECT_LT(c.max_depth_difference, 0.0005f);  // flat faces stay flat
    EXPECT_LT(static_cast<double>(c.only_one), 0.01 * static_cast<double>(c.both));  // the outline within a pixel
  }
}

// How far the drawn surface lies from a sphere of radius r about the object's origin: each drawn
// pixel back-projected, its distance from the centre compared with r.
float largest_distance_from_sphere(const TriangleMesh& mesh, const Transform& T, double r) {
  const RenderedFrame f = draw(mesh, T);
  const Transform T_object_camera = T.inverse();
  double worst = 0;
  for (int v = 0; v < K.height; ++v)
    for (int u = 0; u < K.width; ++u) {
      const float z = f.depth.at(u, v);
      if (!std::isfinite(z)) continue;
      const Eigen::Vector3d p = T_object_camera * K.unproject(u, v, z).cast<double>();
      worst = std::max(worst, std::abs(p.norm() - r));
    }
  return static_cast<float>(worst);
}

TEST(SimplifyForDrawing, ASphereStaysWithinTheBound) {
  const double r = 0.05;
  const TriangleMesh sphere = make_sphere(r, 120);  // about 57,600 triangles
  std::size_t previous = sphere.triangles.size();
  for (float error : {0.0005f, 0.001f, 0.002f}) {
    const TriangleMesh drawn = simplify_for_drawing(sphere, error);
    EXPECT_LT(drawn.triangles.size(), previous) << "a looser bound keeps fewer triangles";
    previous = drawn.triangles.size();
    for (const Transform& T : kPoses) {
      const float original = largest_distance_from_sphere(sphere, T, r);
      // Chords cut inside the sphere, by less than the bound.
      EXPECT_LT(largest_distance_from_sphere(drawn, T, r), original + error) << error;
    }
  }
  EXPECT_LT(previous, sphere.triangles.size() / 20);
}

TEST(SimplifyForDrawing, ShapesWithHandlesAndEmptyMeshes) {
  const TriangleMesh mug = make_mug();
  const TriangleMesh drawn = simplify_for_drawing(mug, 0.002f);
  EXPECT_LT(drawn.triangles.size(), mug.triangles.size() / 2);
  for (const Transform& T : kPoses) {
    // The rim and the handle are depth steps, where a pixel's shift is a large depth; the sides
    // seen at a grazing angle turn a small shift of the surface into a larger one of depth. Away
    // from the steps (99 % of the pixels) the depth moves by less than twice the bound.
    const Comparison c = compare(mug, drawn, T);
    EXPECT_LT(c.p99_depth_difference, 0.004f);
    EXPECT_LT(static_cast<double>(c.only_one), 0.02 * static_cast<double>(c.both));
  }
  EXPECT_TRUE(simplify_for_drawing(TriangleMesh{}, 0.001f).triangles.empty());
  // A zero bound welds but removes nothing that changes the shape.
  const TriangleMesh box = fine_box({0.1f, 0.1f, 0.1f}, 4);
  EXPECT_LT(compare(box, simplify_for_drawing(box, 0.0f), kPoses[0]).max_depth_difference, 1e-5f);
}

TEST(SimplifyForDrawing, FacesStoredTwiceAreDrawnOnceAndTheMeshStaysClosed) {
  // As the YCB-Video models are stored: every face twice, each copy on vertices of its own. Welded,
  // the copies are one face; kept both, each edge ran four times one way and the mesh never counted
  // as closed, so its back faces were drawn as well.
  const TriangleMesh box = fine_box({0.1f, 0.08f, 0.06f}, 6);
  TriangleMesh twice = box;
  const auto offset = static_cast<std::uint32_t>(box.vertices.size());
  twice.vertices.insert(twice.vertices.end(), box.vertices.begin(), box.vertices.end());
  for (const auto& t : box.triangles) twice.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  for (float error : {0.0f, 0.002f}) {
    const TriangleMesh once = simplify_for_drawing(box, error), from_twice = simplify_for_drawing(twice, error);
    EXPECT_EQ(from_twice.triangles.size(), once.triangles.size()) << "error " << error;
    EXPECT_EQ(closed_mesh_winding(from_twice), 1) << "error " << error;
    EXPECT_LT(compare(box, from_twice, kPoses[0]).max_depth_difference, 1e-5f);
  }
}

}  // namespace
}  // namespace viewpose
