#include <png.h>
#include <zlib.h>

#include <chrono>
#include <cmath>

#include "test_support.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/io/depth_png.hpp"

namespace viewpose {
namespace {

using test::expect_error;

DepthImage ramp(int w, int h, float step_m) {
  DepthImage d(w, h);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) d.at(u, v) = (u + v) % 5 == 0 ? NAN : 0.5f + step_m * static_cast<float>(u + w * v);
  return d;
}

TEST(DepthPng, RoundTripAtMillimetreAndTenthMillimetreScales) {
  for (const double scale : {0.001, 0.0001}) {
    const DepthImage in = ramp(37, 23, 0.0013f);
    const DepthImage out = decode_depth_png(encode_depth_png(in, scale), "mem", scale);
    ASSERT_EQ(out.width, 37);
    ASSERT_EQ(out.height, 23);
    for (std::size_t i = 0; i < in.depth_m.size(); ++i) {
      if (std::isnan(in.depth_m[i])) {
        EXPECT_TRUE(std::isnan(out.depth_m[i])) << i;
      } else {
        EXPECT_NEAR(out.depth_m[i], in.depth_m[i], scale / 2 + 1e-6) << i;  // rounded to the nearest unit
      }
    }
  }
}

TEST(DepthPng, ExactValuesSurviveExactly) {
  DepthImage in(3, 1);
  in.depth_m = {1.0f, 0.0f, 65.535f};
  const DepthImage out = decode_depth_png(encode_depth_png(in, 0.001), "mem", 0.001);
  EXPECT_FLOAT_EQ(out.depth_m[0], 1.0f);
  EXPECT_TRUE(std::isnan(out.depth_m[1]));  // 0 is "no measurement"
  EXPECT_FLOAT_EQ(out.depth_m[2], 65.535f);
}

TEST(DepthPng, RefusesDepthsThatDoNotFitAndBadScales) {
  DepthImage d(1, 1);
  d.depth_m = {7.0f};
  expect_error([&] { encode_depth_png(d, 0.0001); }, "does not fit in 16 bits");
  expect_error([&] { encode_depth_png(d, 0.0); }, "depth scale");
  expect_error([&] { decode_depth_png(encode_depth_png(d, 0.001), "x.png", -1.0); }, "x.png: depth scale");
}

// A PNG of any kind, written with libpng directly (viewpose itself only writes 16-bit grey).
std::vector<std::uint8_t> make_png(int w, int h, int bit_depth, int colour_type) {
  std::vector<std::uint8_t> out;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  png_set_write_fn(png, &out, [](png_structp p, png_bytep d, png_size_t n) {
    auto* o = static_cast<std::vector<std::uint8_t>*>(png_get_io_ptr(p));
    o->insert(o->end(), d, d + n);
  }, nullptr);
  png_set_IHDR(png, info, static_cast<png_uint_32>(w), static_cast<png_uint_32>(h), bit_depth, colour_type,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  const int channels = colour_type == PNG_COLOR_TYPE_RGB ? 3 : colour_type == PNG_COLOR_TYPE_RGB_ALPHA ? 4 : 1;
  std::vector<std::uint8_t> row(static_cast<std::size_t>(w * channels * bit_depth / 8 + 1), 7);
  for (int y = 0; y < h; ++y) png_write_row(png, row.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

TEST(DepthPng, AMedianOutsideADepthCamerasRangeNamesTheScaleThatFits) {
  DepthImage far(40, 30), near(40, 30), fine(40, 30), none(40, 30);
  for (std::size_t i = 0; i < far.depth_m.size(); ++i) {
    far.depth_m[i] = 7.0f + 0.002f * static_cast<float>(i);  // a YCB-Video PNG read at 1 mm per unit
    near.depth_m[i] = 0.06f;                                  // a 1 mm PNG read at 0.1 mm per unit
    fine.depth_m[i] = i % 3 ? 1.2f : NAN;
  }
  EXPECT_NEAR(median_depth_m(far), 7.0 + 0.002 * 600, 0.003);
  EXPECT_NE(depth_scale_warning(far, 1.0).find("--depth-scale 0.1 (median 0.82"), std::string::npos) << depth_scale_warning(far, 1.0);
  EXPECT_NE(depth_scale_warning(near, 0.1).find("--depth-scale 1 (median 0.6 m)"), std::string::npos) << depth_scale_warning(near, 0.1);
  EXPECT_TRUE(depth_scale_warning(fine, 1.0).empty());
  EXPECT_TRUE(std::isnan(median_depth_m(none)));
  EXPECT_TRUE(depth_scale_warning(none, 1.0).empty());
}

TEST(DepthPng, WrongKindsOfPngAreNamed) {
  expect_error([] { decode_depth_png(make_png(4, 4, 8, PNG_COLOR_TYPE_GRAY), "g8.png", 0.001); },
               "g8.png: is a 8-bit greyscale PNG; a depth image must be 16-bit greyscale");
  expect_error([] { decode_depth_png(make_png(4, 4, 8, PNG_COLOR_TYPE_RGB), "rgb.png", 0.001); }, "8-bit RGB PNG; a depth image must be 16-bit greyscale (this looks like the colour image: BOP keeps depth in depth/, colour in rgb/)");
  expect_error([] { decode_depth_png(make_png(4, 4, 16, PNG_COLOR_TYPE_RGB), "rgb16.png", 0.001); }, "16-bit RGB");
  EXPECT_NO_THROW(decode_depth_png(make_png(4, 4, 16, PNG_COLOR_TYPE_GRAY), "ok.png", 0.001));
}

TEST(DepthPng, TruncatedCorruptAndNonPngInput) {
  const auto full = encode_depth_png(ramp(64, 48, 0.01f), 0.001);
  expect_error([] { decode_depth_png({}, "e.png", 0.001); }, "e.png: empty file");
  expect_error([] { decode_depth_png(test::bytes_of("# .PCD v0.7\nVERSION"), "n.png", 0.001); }, "n.png: not a PNG file");
  for (std::size_t cut : {std::size_t{12}, std::size_t{40}, full.size() / 2, full.size() - 5}) {
    EXPECT_THROW(decode_depth_png(std::span(full.data(), cut), "cut.png", 0.001), Error) << cut;
  }
  std::vector<std::uint8_t> corrupt = full;
  for (std::size_t i = 60; i < corrupt.size(); i += 5) corrupt[i] ^= 0x5a;
  EXPECT_THROW(decode_depth_png(corrupt, "bad.png", 0.001), Error);
}

// Rewrites the size in the IHDR chunk (and its CRC) of a valid PNG.
std::vector<std::uint8_t> with_size(std::vector<std::uint8_t> png, std::uint32_t w, std::uint32_t h) {
  auto put = [&](std::size_t at, std::uint32_t v) {
    for (int k = 0; k < 4; ++k) png[at + static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(v >> (24 - 8 * k));
  };
  put(16, w);
  put(20, h);
  put(29, static_cast<std::uint32_t>(crc32(0, png.data() + 12, 17)));  // CRC over "IHDR" + 13 data bytes
  return png;
}

TEST(DepthPng, AbsurdSizesAreRefusedFast) {
  const auto small = encode_depth_png(ramp(8, 8, 0.01f), 0.001);
  const auto start = std::chrono::steady_clock::now();
  expect_error([&] { decode_depth_png(with_size(small, 16000, 16000), "big.png", 0.001); }, "more than its");
  expect_error([&] { decode_depth_png(with_size(small, 100000, 8), "wide.png", 0.001); }, "wide.png");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 1.0);
}

}  // namespace
}  // namespace viewpose
