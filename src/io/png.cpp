// PNG reading and writing through libpng: 16-bit depth images and 8-bit RGB pictures.
#include "viewpose/io/depth_png.hpp"

#include <algorithm>
#include "viewpose/io/image_png.hpp"

#include <png.h>

#include <bit>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstring>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"
#include "viewpose/core/file.hpp"

namespace viewpose {

namespace {

// deflate cannot expand data more than about 1032 times; a header promising more pixels than the
// file could hold is refused before the pixel buffer is allocated.
constexpr std::size_t kDeflateMaxRatio = 1100;

// libpng reports errors by longjmp. Everything it touches lives in this plain struct, owned by the
// caller, so no C++ object with a destructor is ever jumped over.
struct PngIo {
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
  std::size_t pos = 0;
  std::vector<std::uint8_t>* out = nullptr;  // for writing
  char message[256] = {};
};

void on_error(png_structp png, png_const_charp msg) {
  auto* io = static_cast<PngIo*>(png_get_error_ptr(png));
  std::snprintf(io->message, sizeof io->message, "%s", msg);
  png_longjmp(png, 1);
}
void on_warning(png_structp, png_const_charp) {}

void on_read(png_structp png, png_bytep dst, png_size_t n) {
  auto* io = static_cast<PngIo*>(png_get_io_ptr(png));
  if (n > io->size - io->pos) png_error(png, "PNG data ends early (truncated file)");
  std::memcpy(dst, io->data + io->pos, n);
  io->pos += n;
}

void on_write(png_structp png, png_bytep src, png_size_t n) {
  auto* io = static_cast<PngIo*>(png_get_io_ptr(png));
  io->out->insert(io->out->end(), src, src + n);
}
void on_flush(png_structp) {}

const char* colour_type_name(int t) {
  switch (t) {
    case PNG_COLOR_TYPE_GRAY: return "greyscale";
    case PNG_COLOR_TYPE_GRAY_ALPHA: return "greyscale+alpha";
    case PNG_COLOR_TYPE_RGB: return "RGB";
    case PNG_COLOR_TYPE_RGB_ALPHA: return "RGBA";
    case PNG_COLOR_TYPE_PALETTE: return "palette";
    default: return "unknown";
  }
}

// Decodes into `pixels` (host byte order). Returns false with io.message set on any failure. The
// buffers belong to the caller so that a longjmp out of libpng skips no destructor.
bool decode(PngIo& io, std::vector<std::uint16_t>& pixels, std::vector<png_bytep>& rows, int& width, int& height) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &io, on_error, on_warning);
  if (!png) return std::snprintf(io.message, sizeof io.message, "out of memory"), false;
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
    if (!io.message[0]) std::snprintf(io.message, sizeof io.message, "corrupt PNG");
    return false;
  }
  png_set_read_fn(png, &io, on_read);
  png_set_user_limits(png, kMaxDepthImageSide, kMaxDepthImageSide);
  png_read_info(png, info);
  const png_uint_32 w = png_get_image_width(png, info), h = png_get_image_height(png, info);
  const int bit_depth = png_get_bit_depth(png, info), colour = png_get_color_type(png, info);
  if (bit_depth != 16 || colour != PNG_COLOR_TYPE_GRAY) {
    std::snprintf(io.message, sizeof io.message,
                  "is a %d-bit %s PNG; a depth image must be 16-bit greyscale%s", bit_depth, colour_type_name(colour),
                  colour == PNG_COLOR_TYPE_RGB || colour == PNG_COLOR_TYPE_RGB_ALPHA
                      ? " (this looks like the colour image: BOP keeps depth in depth/, colour in rgb/)"
                      : "");
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  if (std::size_t{w} * h * 2 > io.size * kDeflateMaxRatio + 4096) {
    std::snprintf(io.message, sizeof io.message, "claims %ux%u pixels, more than its %zu bytes can hold", w, h, io.size);
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  if constexpr (std::endian::native == std::endian::little) png_set_swap(png);  // PNG stores big-endian
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  pixels.resize(std::size_t{w} * h);
  rows.resize(h);
  for (png_uint_32 y = 0; y < h; ++y) rows[y] = reinterpret_cast<png_bytep>(pixels.data() + std::size_t{y} * w);
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  width = static_cast<int>(w);
  height = static_cast<int>(h);
  return true;
}

// Encodes rows of `row_bytes` bytes each; 16-bit samples are given in host order.
bool encode(PngIo& io, const std::uint8_t* pixels, std::size_t row_bytes, int width, int height, int bit_depth,
            int colour_type) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &io, on_error, on_warning);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, info ? &info : nullptr);
    return false;
  }
  png_set_write_fn(png, &io, on_write, on_flush);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), bit_depth, colour_type,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, 3);  // depth compresses well at low levels; writing stays fast
  png_write_info(png, info);
  if constexpr (std::endian::native == std::endian::little) {
    if (bit_depth == 16) png_set_swap(png);
  }
  for (int y = 0; y < height; ++y) png_write_row(png, pixels + static_cast<std::size_t>(y) * row_bytes);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

void check_scale(double metres_per_unit, std::string_view name) {
  if (!(std::isfinite(metres_per_unit) && metres_per_unit > 0 && metres_per_unit < 1)) {
    throw Error(fmt::format("{}: depth scale {} m per unit is not a positive fraction of a metre", name, metres_per_unit));
  }
}

}  // namespace

DepthPngUnits decode_depth_png_units(std::span<const std::uint8_t> bytes, std::string_view name) {
  if (bytes.empty()) throw Error(fmt::format("{}: empty file", name));
  if (bytes.size() < 8 || png_sig_cmp(bytes.data(), 0, 8) != 0) throw Error(fmt::format("{}: not a PNG file", name));
  PngIo io;
  io.data = bytes.data();
  io.size = bytes.size();
  std::vector<std::uint16_t> pixels;
  std::vector<png_bytep> rows;
  int width = 0, height = 0;
  if (!decode(io, pixels, rows, width, height)) throw Error(fmt::format("{}: {}", name, io.message));
  return DepthPngUnits{width, height, std::move(pixels)};
}

DepthImage decode_depth_png(std::span<const std::uint8_t> bytes, std::string_view name, double metres_per_unit) {
  check_scale(metres_per_unit, name);
  const DepthPngUnits png = decode_depth_png_units(bytes, name);
  return depth_from_units(png.units, png.width, png.height, metres_per_unit);
}

DepthImage read_depth_png(const std::filesystem::path& path, double metres_per_unit) {
  return decode_depth_png(read_file_bytes(path), path.string(), metres_per_unit);
}

DepthPngUnits read_depth_png_units(const std::filesystem::path& path) {
  return decode_depth_png_units(read_file_bytes(path), path.string());
}

std::vector<std::uint8_t> encode_depth_png(const DepthImage& depth, double metres_per_unit) {
  check_scale(metres_per_unit, "depth PNG");
  if (depth.width <= 0 || depth.height <= 0 || depth.width > kMaxDepthImageSide || depth.height > kMaxDepthImageSide ||
      depth.depth_m.size() != static_cast<std::size_t>(depth.width) * static_cast<std::size_t>(depth.height)) {
    throw Error(fmt::format("depth PNG: cannot write a {}x{} image of {} values", depth.width, depth.height,
                            depth.depth_m.size()));
  }
  std::vector<std::uint16_t> pixels(depth.depth_m.size(), 0);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const float z = depth.depth_m[i];
    if (!(std::isfinite(z) && z > 0)) continue;
    const double units = std::round(z / metres_per_unit);
    if (units > 65535.0) {
      throw Error(fmt::format("depth PNG: depth {} m does not fit in 16 bits at {} m per unit", z, metres_per_unit));
    }
    pixels[i] = static_cast<std::uint16_t>(units);
  }
  std::vector<std::uint8_t> out;
  PngIo io;
  io.out = &out;
  if (!encode(io, reinterpret_cast<const std::uint8_t*>(pixels.data()), 2 * static_cast<std::size_t>(depth.width),
              depth.width, depth.height, 16, PNG_COLOR_TYPE_GRAY)) {
    throw Error(fmt::format("depth PNG: encoding failed: {}", io.message));
  }
  return out;
}

void write_depth_png(const std::filesystem::path& path, const DepthImage& depth, double metres_per_unit) {
  write_file_atomic(path, encode_depth_png(depth, metres_per_unit));
}

std::vector<std::uint8_t> encode_rgb_png(const RgbImage& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != 3 * static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height)) {
    throw Error(fmt::format("PNG: cannot write a {}x{} RGB image of {} bytes", image.width, image.height, image.rgb.size()));
  }
  std::vector<std::uint8_t> out;
  PngIo io;
  io.out = &out;
  if (!encode(io, image.rgb.data(), 3 * static_cast<std::size_t>(image.width), image.width, image.height, 8,
              PNG_COLOR_TYPE_RGB)) {
    throw Error(fmt::format("PNG: encoding failed: {}", io.message));
  }
  return out;
}

void write_rgb_png(const std::filesystem::path& path, const RgbImage& image) {
  write_file_atomic(path, encode_rgb_png(image));
}

std::string depth_scale_warning(const DepthImage& depth, double mm_per_unit) {
  const double median = median_depth_m(depth);
  if (!std::isfinite(median) || within_depth_camera_range(median)) return {};
  const double factor = std::pow(10.0, std::round(std::log10(1.0 / median)));
  return fmt::format("median depth {:.3g} m at {:g} mm per unit, outside what depth cameras measure (0.3-5 m): is it "
                     "--depth-scale {:g} (median {:.3g} m)?",
                     median, mm_per_unit, mm_per_unit * factor, median * factor);
}

}  // namespace viewpose
