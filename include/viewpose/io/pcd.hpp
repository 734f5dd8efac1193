#pragma once
// PCD (PCL's Point Cloud Data format), versions 0.6 and 0.7, DATA ascii, binary and
// binary_compressed (LZF). Read fields: x y z, normal_x/y/z, curvature, rgb/rgba, label; any other
// field (padding "_", intensity, ...) is skipped. Coordinates are taken as metres, as PCL writes them.
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "viewpose/core/point_cloud.hpp"

namespace viewpose {

enum class PcdEncoding { Ascii, Binary, BinaryCompressed };
std::string_view to_string(PcdEncoding encoding);
/// "ascii", "binary" or "binary_compressed"; throws viewpose::Error otherwise.
PcdEncoding parse_pcd_encoding(std::string_view text);

struct PcdField {
  std::string name;
  int size = 4;     ///< bytes per value: 1, 2, 4 or 8
  char type = 'F';  ///< F float, U unsigned, I signed
  int count = 1;    ///< values per point
};

struct PcdHeader {
  std::string version;  ///< "0.7" or "0.6"
  std::vector<PcdField> fields;
  int width = 0;
  int height = 0;
  std::size_t points = 0;
  PcdEncoding encoding = PcdEncoding::Ascii;
};

struct PcdFile {
  PcdHeader header;
  PointCloud cloud;
};

/// Limits that keep a hostile header from making the reader allocate or loop without bound.
inline constexpr std::size_t kMaxPcdHeaderBytes = 64 * 1024;
inline constexpr std::size_t kMaxCloudPoints = std::size_t{1} << 27;  // 134 M points

PcdFile read_pcd(const std::filesystem::path& path);
/// Parses PCD bytes; `name` is used in error messages.
PcdFile parse_pcd(std::span<const std::uint8_t> bytes, std::string_view name);

/// Writes x y z, plus normal_x/y/z, curvature, rgba and label when the cloud has them. Atomic.
void write_pcd(const std::filesystem::path& path, const PointCloud& cloud, PcdEncoding encoding);
std::vector<std::uint8_t> encode_pcd(const PointCloud& cloud, PcdEncoding encoding);

}  // namespace viewpose
