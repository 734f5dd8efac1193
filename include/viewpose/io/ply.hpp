#pragma once
// PLY (Stanford polygon format): ascii, binary_little_endian and binary_big_endian. Reads the vertex
// element (x y z, nx ny nz, red green blue [alpha]) and, when present, the face element
// (vertex_indices / vertex_index lists; polygons are split into triangle fans). Any other element or
// property is skipped. Coordinates are returned as stored; the caller knows the unit.
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "viewpose/core/mesh.hpp"
#include "viewpose/core/point_cloud.hpp"

namespace viewpose {

enum class PlyEncoding { Ascii, BinaryLittleEndian, BinaryBigEndian };
std::string_view to_string(PlyEncoding encoding);
/// "ascii", "binary_little_endian" or "binary_big_endian"; throws viewpose::Error otherwise.
PlyEncoding parse_ply_encoding(std::string_view text);

struct PlyElementInfo {
  std::string name;
  std::size_t count = 0;
  std::vector<std::string> properties;
};

struct PlyFile {
  PlyEncoding encoding = PlyEncoding::Ascii;
  std::vector<PlyElementInfo> elements;
  PointCloud cloud;   ///< the vertices, with normals and colours when the file has them
  TriangleMesh mesh;  ///< the same vertices and normals, plus the triangles (none for a point cloud)
  bool has_faces() const { return !mesh.triangles.empty(); }
};

inline constexpr std::size_t kMaxPlyHeaderBytes = 64 * 1024;

PlyFile read_ply(const std::filesystem::path& path);
PlyFile parse_ply(std::span<const std::uint8_t> bytes, std::string_view name);

/// Writes the points (and normals and colours when present). Atomic.
void write_ply(const std::filesystem::path& path, const PointCloud& cloud, PlyEncoding encoding);
/// Writes vertices (and normals when present) and triangles. Atomic.
void write_ply(const std::filesystem::path& path, const TriangleMesh& mesh, PlyEncoding encoding);
std::vector<std::uint8_t> encode_ply(const PointCloud& cloud, PlyEncoding encoding);
std::vector<std::uint8_t> encode_ply(const TriangleMesh& mesh, PlyEncoding encoding);

}  // namespace viewpose
