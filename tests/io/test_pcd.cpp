#include <bit>
#include <chrono>

#include "test_support.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/io/pcd.hpp"

namespace viewpose {
namespace {

using test::bytes_of;
using test::expect_error;

class PcdRoundTrip : public ::testing::TestWithParam<PcdEncoding> {};

TEST_P(PcdRoundTrip, UnorganizedXyzIsBitExact) {
  const PointCloud in = test::sample_cloud(500, 1, false, false, false);
  const PcdFile out = parse_pcd(encode_pcd(in, GetParam()), "mem");
  EXPECT_EQ(out.header.encoding, GetParam());
  EXPECT_EQ(out.header.points, 500u);
  test::expect_same_cloud(in, out.cloud);
}

TEST_P(PcdRoundTrip, OrganizedWithAllAttributesAndNaNIsBitExact) {
  const PointCloud in = test::sample_cloud(32, 24, true, true, true);
  ASSERT_LT(in.count_finite(), in.size());
  const PcdFile out = parse_pcd(encode_pcd(in, GetParam()), "mem");
  ASSERT_TRUE(out.cloud.organized());
  test::expect_same_cloud(in, out.cloud);
  std::vector<std::string> names;
  for (const auto& f : out.header.fields) names.push_back(f.name);
  EXPECT_EQ(names, (std::vector<std::string>{"x", "y", "z", "normal_x", "normal_y", "normal_z", "curvature", "rgba", "label"}));
}

TEST_P(PcdRoundTrip, EmptyCloud) {
  const PcdFile out = parse_pcd(encode_pcd(PointCloud::from_points({}), GetParam()), "mem");
  EXPECT_EQ(out.cloud.size(), 0u);
}

TEST_P(PcdRoundTrip, ThroughAFileWrittenAtomically) {
  test::TempDir dir;
  const PointCloud in = test::sample_cloud(64, 2, true, false, true);
  write_pcd(dir / "c.pcd", in, GetParam());
  test::expect_same_cloud(in, read_pcd(dir / "c.pcd").cloud);
  // Nothing but the file itself is left in the folder.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 1);
}

INSTANTIATE_TEST_SUITE_P(AllEncodings, PcdRoundTrip,
                         ::testing::Values(PcdEncoding::Ascii, PcdEncoding::Binary, PcdEncoding::BinaryCompressed),
                         [](const auto& p) { return std::string(to_string(p.param)); });

TEST(PcdRead, Version06WithPaddingCountsAndMixedTypes) {
  // No POINTS line (v0.6), a padding field, a field with COUNT 2, a 16-bit signed field and
  // double-precision coordinates.
  const std::string text =
      "VERSION .6\nFIELDS x y z _ intensity label\nSIZE 8 8 8 1 2 4\nTYPE F F F U I U\nCOUNT 1 1 1 4 2 1\n"
      "WIDTH 2\nHEIGHT 1\nDATA ascii\n1.5 -2 3e-1 0 0 0 0 7 -7 12\n+4 5 6 1 1 1 1 -3 3 4294967295\n";
  const PcdFile f = parse_pcd(bytes_of(text), "v06.pcd");
  EXPECT_EQ(f.header.version, "0.6");
  ASSERT_EQ(f.cloud.size(), 2u);
  EXPECT_EQ(f.cloud.points[0], Eigen::Vector3f(1.5f, -2.0f, 0.3f));
  EXPECT_EQ(f.cloud.points[1], Eigen::Vector3f(4, 5, 6));
  EXPECT_EQ(f.cloud.labels, (std::vector<std::uint32_t>{12u, 4294967295u}));
}

TEST(PcdRead, PclAsciiRgbIsAFloatHoldingTheColourBits) {
  const std::uint32_t colour = 0x00ff8040u;  // as PCL packs r=255 g=128 b=64
  const std::string text = fmt::format(
      "VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 1\nHEIGHT 1\n"
      "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n0 0 1 {}\n", std::bit_cast<float>(colour));
  EXPECT_EQ(parse_pcd(bytes_of(text), "rgb.pcd").cloud.rgba.at(0), colour);
}

TEST(PcdRead, NaNOnlyCloudIsReadWithNoValidPoint) {
  const std::string text = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n"
                           "nan nan nan\nnan nan nan\n";
  const PcdFile f = parse_pcd(bytes_of(text), "nan.pcd");
  EXPECT_EQ(f.cloud.size(), 2u);
  EXPECT_EQ(f.cloud.count_finite(), 0u);
}

std::string header(const std::string& fields_tail, const std::string& size_data) {
  return "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z" + fields_tail + "\n" + size_data;
}

TEST(PcdMalformed, EachGetsAOneLineErrorNamingTheFile) {
  const std::string ok_head = "SIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
  expect_error([] { parse_pcd({}, "empty.pcd"); }, "empty.pcd: empty file");
  expect_error([] { parse_pcd(bytes_of("ply\nformat ascii 1.0\n"), "a.pcd"); }, "not a PCD file");
  expect_error([] { parse_pcd(bytes_of(std::string("\x89PNG\r\n\x1a\n\0\0", 10)), "b.pcd"); }, "b.pcd");
  expect_error([&] { parse_pcd(bytes_of(header("", ok_head + "WIDTH 3\nHEIGHT 1\nPOINTS 3\n")), "c.pcd"); },
               "without a DATA line");
  expect_error([&] { parse_pcd(bytes_of(header("", ok_head + "WIDTH 3\nHEIGHT 1\nPOINTS 4\nDATA ascii\n")), "d.pcd"); },
               "POINTS 4 is not WIDTH x HEIGHT");
  expect_error([&] { parse_pcd(bytes_of(header("", ok_head + "WIDTH 3\nHEIGHT 1\nDATA lz4\n")), "e.pcd"); },
               "unknown DATA encoding");
  expect_error([&] { parse_pcd(bytes_of(header(" w", ok_head + "WIDTH 3\nHEIGHT 1\nDATA ascii\n")), "f.pcd"); },
               "SIZE has 3");
  expect_error([&] { parse_pcd(bytes_of("VERSION 0.7\nFIELDS a b c\n" + ok_head + "WIDTH 1\nHEIGHT 1\nDATA ascii\n1 2 3\n"),
                               "g.pcd"); },
               "no x y z");
  expect_error([&] { parse_pcd(bytes_of(header("", "SIZE 4 4 4\nTYPE F F F\nCOUNT 3 1 1\nWIDTH 1\nHEIGHT 1\nDATA ascii\n")),
                               "h.pcd"); },
               "COUNT 3");
  expect_error([&] { parse_pcd(bytes_of(header("", ok_head + "WIDTH 2\nHEIGHT 1\nDATA ascii\n1 2 3\n4 5      \n")), "i.pcd"); },
               "point 1 has 2 values");
  expect_error([&] { parse_pcd(bytes_of(header("", ok_head + "WIDTH 1\nHEIGHT 1\nDATA ascii\n1 two 3\n")), "j.pcd"); },
               "'two' is not a number");
  expect_error([&] { parse_pcd(bytes_of(header("", ok_head + "WIDTH 1\nHEIGHT 1\nDATA ascii\n1 2 3\n4 5 6\n")), "k.pcd"); },
               "more data than");
  expect_error([&] { parse_pcd(bytes_of(header("", ok_head + "WIDTH -4\nHEIGHT 1\nDATA ascii\n")), "l.pcd"); }, "WIDTH");
}

TEST(PcdMalformed, HeaderClaimingMorePointsThanTheDataHolds) {
  for (const auto encoding : {PcdEncoding::Ascii, PcdEncoding::Binary, PcdEncoding::BinaryCompressed}) {
    std::vector<std::uint8_t> bytes = encode_pcd(test::sample_cloud(100, 1, false, false, false), encoding);
    std::string s(bytes.begin(), bytes.end());
    s.replace(s.find("WIDTH 100"), 9, "WIDTH 900");
    s.replace(s.find("POINTS 100"), 10, "POINTS 900");
    expect_error([&] { parse_pcd(bytes_of(s), "more.pcd"); }, "more.pcd: ");
  }
}

TEST(PcdMalformed, TruncatedAtEveryRegionOfTheFile) {
  for (const auto encoding : {PcdEncoding::Ascii, PcdEncoding::Binary, PcdEncoding::BinaryCompressed}) {
    const std::vector<std::uint8_t> full = encode_pcd(test::sample_cloud(40, 2, true, true, false), encoding);
    std::vector<std::size_t> cuts = {10, 100, full.size() / 2};
    if (encoding == PcdEncoding::Ascii) {
      // An ascii file cut inside its last number still reads as a complete file (in PCL too);
      // cutting off the last line must be caught.
      const std::string s(full.begin(), full.end() - 1);
      cuts.push_back(s.rfind('\n') + 1);
    } else {
      cuts.insert(cuts.end(), {full.size() - 9, full.size() - 1});
    }
    for (std::size_t cut : cuts) {
      const std::span<const std::uint8_t> part(full.data(), cut);
      EXPECT_THROW(parse_pcd(part, "cut.pcd"), Error) << to_string(encoding) << " cut at " << cut;
    }
  }
}

TEST(PcdMalformed, CorruptCompressedDataIsRefusedNotTrusted) {
  std::vector<std::uint8_t> bytes = encode_pcd(test::sample_cloud(200, 1, true, false, false), PcdEncoding::BinaryCompressed);
  const std::string s(bytes.begin(), bytes.end());
  const std::size_t data = s.find("DATA binary_compressed\n") + 23;
  // The stored unpacked size no longer matches the points: refused before unpacking.
  std::vector<std::uint8_t> wrong_size = bytes;
  wrong_size[data + 4] ^= 0x10;
  expect_error([&] { parse_pcd(wrong_size, "z.pcd"); }, "unpacks to");
  // Garbage in the LZF stream: refused, never read out of bounds (the sanitizer build checks).
  std::vector<std::uint8_t> garbage = bytes;
  for (std::size_t i = data + 8; i < garbage.size(); i += 3) garbage[i] = 0xff;
  EXPECT_THROW(parse_pcd(garbage, "g.pcd"), Error);
}

TEST(PcdMalformed, AbsurdSizesAreRefusedFastWithoutAllocating) {
  const auto start = std::chrono::steady_clock::now();
  const std::string base = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n";
  expect_error([&] { parse_pcd(bytes_of(base + "WIDTH 2000000000\nHEIGHT 2000000000\nDATA binary\n"), "huge.pcd"); },
               "limit");
  expect_error([&] { parse_pcd(bytes_of(base + "WIDTH 100000000\nHEIGHT 1\nDATA binary\nabc"), "big.pcd"); },
               "binary data holds 0");
  expect_error([&] { parse_pcd(bytes_of(base + "WIDTH 100000000\nHEIGHT 1\nDATA ascii\n1 2 3\n"), "big.pcd"); },
               "holds at most");
  // A compressed block promising 1.2 GB from 20 bytes.
  std::string c = base + "WIDTH 100000000\nHEIGHT 1\nDATA binary_compressed\n";
  const std::uint32_t sizes[2] = {20, 1200000000u};
  c.append(reinterpret_cast<const char*>(sizes), 8);
  c.append(20, '\x01');
  expect_error([&] { parse_pcd(bytes_of(c), "bomb.pcd"); }, "cannot unpack to");
  // A header that never ends (megabytes of comments).
  std::string endless;
  while (endless.size() < 200000) endless += "# a comment line that goes on and on\n";
  expect_error([&] { parse_pcd(bytes_of(endless), "endless.pcd"); }, "no DATA line in the first");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 1.0) << "refusals should not scan or allocate";
}

TEST(PcdFile, MissingFileAndDirectoryAreNamed) {
  expect_error([] { read_pcd("/nonexistent/dir/x.pcd"); }, "/nonexistent/dir/x.pcd: no such file");
  test::TempDir dir;
  expect_error([&] { read_pcd(dir.path()); }, "is a directory");
}

}  // namespace
}  // namespace viewpose
