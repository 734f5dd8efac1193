#include "test_support.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/io/ply.hpp"

namespace viewpose {
namespace {

using test::bytes_of;
using test::expect_error;

class PlyRoundTrip : public ::testing::TestWithParam<PlyEncoding> {};

TEST_P(PlyRoundTrip, CloudWithNormalsAndColoursIsExact) {
  PointCloud in = test::sample_cloud(300, 1, true, true, false);
  in.curvature.clear();  // PLY carries no curvature
  const PlyFile out = parse_ply(encode_ply(in, GetParam()), "mem");
  EXPECT_EQ(out.encoding, GetParam());
  EXPECT_FALSE(out.has_faces());
  test::expect_same_cloud(in, out.cloud);
}

TEST_P(PlyRoundTrip, MeshIsExact) {
  TriangleMesh in = make_box_mesh({0.1f, 0.2f, 0.3f});
  for (const auto& v : in.vertices) in.normals.push_back(v.normalized());
  const PlyFile out = parse_ply(encode_ply(in, GetParam()), "mem");
  ASSERT_TRUE(out.has_faces());
  EXPECT_TRUE(test::same_bits(out.mesh.vertices, in.vertices));
  EXPECT_TRUE(test::same_bits(out.mesh.normals, in.normals));
  EXPECT_EQ(out.mesh.triangles, in.triangles);
}

TEST_P(PlyRoundTrip, ThroughAFile) {
  test::TempDir dir;
  const TriangleMesh in = make_box_mesh({1, 2, 3});
  write_ply(dir / "m.ply", in, GetParam());
  EXPECT_EQ(read_ply(dir / "m.ply").mesh.triangles, in.triangles);
}

INSTANTIATE_TEST_SUITE_P(AllEncodings, PlyRoundTrip,
                         ::testing::Values(PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian, PlyEncoding::BinaryBigEndian),
                         [](const auto& p) { return std::string(to_string(p.param)); });

TEST(PlyRead, BigEndianReallyIsBigEndian) {
  const auto le = encode_ply(PointCloud::from_points({{1.0f, 2.0f, 3.0f}}), PlyEncoding::BinaryLittleEndian);
  const auto be = encode_ply(PointCloud::from_points({{1.0f, 2.0f, 3.0f}}), PlyEncoding::BinaryBigEndian);
  // 1.0f is 3f 80 00 00 in big-endian order: the body's first float, read byte by byte.
  const std::string s(be.begin(), be.end());
  const std::size_t body = s.find("end_header\n") + 11;
  EXPECT_EQ(be[body], 0x3f);
  EXPECT_EQ(be[body + 1], 0x80);
  EXPECT_EQ(le[le.size() - 12 + 3], 0x3f);
}

TEST(PlyRead, PolygonsBecomeFansAndUnknownDataIsSkipped) {
  const std::string text =
      "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 5\nproperty float x\nproperty float y\n"
      "property float z\nproperty float texture_u\nproperty list uchar int extra\nproperty uchar red\n"
      "element material 1\nproperty int id\n"
      "element face 2\nproperty uchar flags\nproperty list uchar uint vertex_index\nend_header\n"
      "0 0 0 0.5 2 7 8 255\n1 0 0 0.5 0 128\n1 1 0 0.5 1 9 64\n0 1 0 0.5 0 0\n0 0 1 0.5 0 1\n"
      "42\n"
      "0 4 0 1 2 3\n0 3 0 1 4\n";
  const PlyFile f = parse_ply(bytes_of(text), "hand.ply");
  ASSERT_EQ(f.cloud.size(), 5u);
  EXPECT_EQ(f.cloud.points[2], Eigen::Vector3f(1, 1, 0));
  EXPECT_EQ(f.cloud.rgba[0], 0xffff0000u);  // red only, opaque
  EXPECT_EQ(f.cloud.rgba[2], 0xff400000u);
  EXPECT_TRUE(f.cloud.normals.empty());
  ASSERT_EQ(f.mesh.triangles.size(), 3u);  // a quad (2) and a triangle (1)
  EXPECT_EQ(f.mesh.triangles[0], (std::array<std::uint32_t, 3>{0, 1, 2}));
  EXPECT_EQ(f.mesh.triangles[1], (std::array<std::uint32_t, 3>{0, 2, 3}));
  ASSERT_EQ(f.elements.size(), 3u);
  EXPECT_EQ(f.elements[1].name, "material");
}

TEST(PlyMalformed, EachGetsAOneLineErrorNamingTheFile) {
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n";
  expect_error([] { parse_ply({}, "e.ply"); }, "e.ply: empty file");
  expect_error([] { parse_ply(bytes_of("# .PCD v0.7\n"), "a.ply"); }, "a.ply: not a PLY file");
  expect_error([] { parse_ply(bytes_of("ply\nformat ascii 1.0\nelement vertex 1\n"), "b.ply"); }, "without end_header");
  expect_error([] { parse_ply(bytes_of("ply\nformat binary_middle_endian 1.0\nend_header\n"), "c.ply"); }, "unknown PLY format");
  expect_error([] { parse_ply(bytes_of("ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n"), "d.ply"); },
               "no vertex element");
  expect_error([&] { parse_ply(bytes_of(head + "end_header\n1 2 3\n4 5\n"), "f.ply"); }, "too short");
  expect_error([&] { parse_ply(bytes_of(head + "end_header\n1 2 3\n4 5        \n"), "f2.ply"); }, "ends early");
  expect_error([&] { parse_ply(bytes_of(head + "end_header\n1 2 3\n4 5 six\n"), "g.ply"); }, "'six' is not a valid");
  expect_error([&] { parse_ply(bytes_of(head + "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                               "0 0 0\n1 1 1\n3 0 1 2\n"), "h.ply"); },
               "face 0 names vertex 2 of 2");
  expect_error([&] { parse_ply(bytes_of(head + "property bool flag\nend_header\n"), "i.ply"); }, "malformed property");
  expect_error([&] { parse_ply(bytes_of(head + "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                               "0 0 0\n1 1 1\n2 0 1\n"), "j.ply"); },
               "face 0 has 2 vertices");
}

TEST(PlyMalformed, TruncatedBinaryAndHugeCountsAreRefused) {
  const auto full = encode_ply(make_box_mesh({1, 1, 1}), PlyEncoding::BinaryLittleEndian);
  for (std::size_t cut : {std::size_t{5}, std::size_t{60}, full.size() - 20, full.size() - 1}) {
    EXPECT_THROW(parse_ply(std::span(full.data(), cut), "cut.ply"), Error) << cut;
  }
  expect_error([] { parse_ply(bytes_of("ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
                                       "property float y\nproperty float z\nend_header\nabcdefghijkl"), "huge.ply"); },
               "too short");
  std::string endless = "ply\n";
  while (endless.size() < 100000) endless += "comment and on and on\n";
  expect_error([&] { parse_ply(bytes_of(endless), "endless.ply"); }, "no end_header in the first");
}

}  // namespace
}  // namespace viewpose
