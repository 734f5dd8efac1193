#include "viewpose/io/ply.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>

#include <fmt/format.h>

#include "text.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/core/file.hpp"

namespace viewpose {

namespace {

constexpr std::size_t kMaxListLength = 1 << 16;  // vertices of one polygon

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

std::optional<PlyType> type_named(std::string_view s) {
  if (s == "char" || s == "int8") return PlyType::Int8;
  if (s == "uchar" || s == "uint8") return PlyType::UInt8;
  if (s == "short" || s == "int16") return PlyType::Int16;
  if (s == "ushort" || s == "uint16") return PlyType::UInt16;
  if (s == "int" || s == "int32") return PlyType::Int32;
  if (s == "uint" || s == "uint32") return PlyType::UInt32;
  if (s == "float" || s == "float32") return PlyType::Float32;
  if (s == "double" || s == "float64") return PlyType::Float64;
  return std::nullopt;
}

std::size_t type_size(PlyType t) {
  switch (t) {
    case PlyType::Int8: case PlyType::UInt8: return 1;
    case PlyType::Int16: case PlyType::UInt16: return 2;
    case PlyType::Int32: case PlyType::UInt32: case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
  }
  return 1;
}

bool is_float(PlyType t) { return t == PlyType::Float32 || t == PlyType::Float64; }

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Float32;
  bool is_list = false;
  PlyType count_type = PlyType::UInt8;
};

struct PlyElement {
  std::string name;
  std::size_t count = 0;
  std::vector<PlyProperty> properties;
};

// Reads values one at a time from the body, in any of the three encodings.
class BodyReader {
 public:
  BodyReader(std::span<const std::uint8_t> data, PlyEncoding encoding, std::string_view name)
      : data_(data), encoding_(encoding), name_(name) {}

  double read(PlyType t) { return encoding_ == PlyEncoding::Ascii ? read_ascii(t) : read_binary(t); }
  std::size_t remaining() const { return data_.size() - pos_; }

 private:
  double read_binary(PlyType t) {
    const std::size_t n = type_size(t);
    if (remaining() < n) throw Error(fmt::format("{}: binary data ends early (truncated file)", name_));
    std::uint8_t b[8];
    std::memcpy(b, data_.data() + pos_, n);
    pos_ += n;
    if (encoding_ == PlyEncoding::BinaryBigEndian) {
      for (std::size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
    }
    switch (t) {
      case PlyType::Int8: { std::int8_t v; std::memcpy(&v, b, 1); return v; }
      case PlyType::UInt8: return b[0];
      case PlyType::Int16: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::UInt16: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::Int32: { std::int32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::UInt32: { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::Float32: { float v; std::memcpy(&v, b, 4); return v; }
      case PlyType::Float64: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0;
  }

  double read_ascii(PlyType t) {
    const char* d = reinterpret_cast<const char*>(data_.data());
    const auto space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
    while (pos_ < data_.size() && space(d[pos_])) ++pos_;
    const std::size_t start = pos_;
    while (pos_ < data_.size() && !space(d[pos_])) ++pos_;
    const std::string_view token(d + start, pos_ - start);
    if (token.empty()) throw Error(fmt::format("{}: ascii data ends early (truncated file)", name_));
    if (is_float(t)) {
      double v;
      if (text::parse_number(token, v)) return v;
    } else {
      long long v;
      if (text::parse_number(token, v)) return static_cast<double>(v);
    }
    throw Error(fmt::format("{}: '{}' is not a valid {} value", name_, text::excerpt(token),
                            is_float(t) ? "floating-point" : "integer"));
  }

  std::span<const std::uint8_t> data_;
  std::size_t pos_ = 0;
  PlyEncoding encoding_;
  std::string_view name_;
};

std::vector<PlyElement> parse_header(std::span<const std::uint8_t> bytes, std::string_view name, PlyEncoding& encoding,
                                     std::size_t& body_offset) {
  text::LineReader lines(bytes.first(std::min(bytes.size(), kMaxPlyHeaderBytes)));
  std::string_view line;
  if (!lines.next(line) || text::trim(line) != "ply") {
    throw Error(fmt::format("{}: not a PLY file (starts with '{}')", name, text::excerpt(line)));
  }
  std::vector<PlyElement> elements;
  bool have_format = false;
  while (lines.next(line)) {
    const auto t = text::split_whitespace(line);
    if (t.empty() || t[0] == "comment" || t[0] == "obj_info") continue;
    if (t[0] == "end_header") {
      if (!have_format) throw Error(fmt::format("{}: no format line in the header", name));
      body_offset = lines.offset();
      return elements;
    }
    if (t[0] == "format") {
      if (t.size() != 3) throw Error(fmt::format("{}: malformed format line '{}'", name, text::excerpt(line, 60)));
      if (t[1] == "ascii") encoding = PlyEncoding::Ascii;
      else if (t[1] == "binary_little_endian") encoding = PlyEncoding::BinaryLittleEndian;
      else if (t[1] == "binary_big_endian") encoding = PlyEncoding::BinaryBigEndian;
      else throw Error(fmt::format("{}: unknown PLY format '{}'", name, text::excerpt(t[1])));
      have_format = true;
    } else if (t[0] == "element") {
      long long count = 0;
      if (t.size() != 3 || !text::parse_number(t[2], count) || count < 0) {
        throw Error(fmt::format("{}: malformed element line '{}'", name, text::excerpt(line, 60)));
      }
      elements.push_back({std::string(t[1]), static_cast<std::size_t>(count), {}});
    } else if (t[0] == "property") {
      if (elements.empty()) throw Error(fmt::format("{}: property before any element", name));
      PlyProperty p;
      if (t.size() == 5 && t[1] == "list") {
        const auto count_type = type_named(t[2]);
        const auto value_type = type_named(t[3]);
        if (!count_type || !value_type || is_float(*count_type)) {
          throw Error(fmt::format("{}: malformed list property '{}'", name, text::excerpt(line, 60)));
        }
        p = {std::string(t[4]), *value_type, true, *count_type};
      } else if (t.size() == 3 && type_named(t[1])) {
        p = {std::string(t[2]), *type_named(t[1]), false, PlyType::UInt8};
      } else {
        throw Error(fmt::format("{}: malformed property line '{}'", name, text::excerpt(line, 60)));
      }
      elements.back().properties.push_back(std::move(p));
    } else {
      throw Error(fmt::format("{}: unknown header line '{}'", name, text::excerpt(line, 60)));
    }
  }
  if (bytes.size() >= kMaxPlyHeaderBytes) {
    throw Error(fmt::format("{}: no end_header in the first {} bytes (a huge header?)", name, kMaxPlyHeaderBytes));
  }
  throw Error(fmt::format("{}: header ends without end_header (truncated file)", name));
}

// Refuses element counts the body cannot hold, before anything is allocated for them.
void check_counts_fit(const std::vector<PlyElement>& elements, PlyEncoding encoding, std::size_t body_bytes,
                      std::string_view name) {
  std::size_t needed = 0;
  for (const PlyElement& e : elements) {
    std::size_t min_item = 0;
    for (const PlyProperty& p : e.properties) {
      // An ascii value takes at least a character and a separator; a list at least its count.
      min_item += encoding == PlyEncoding::Ascii ? 2 : type_size(p.is_list ? p.count_type : p.type);
    }
    if (min_item == 0) {
      if (e.count > 0) throw Error(fmt::format("{}: element '{}' has no properties", name, e.name));
      continue;
    }
    if (e.count > (body_bytes + 1) / min_item || needed + e.count * min_item > body_bytes + 1) {
      throw Error(fmt::format("{}: header says {} {} elements but the file is too short for them (truncated?)", name,
                              e.count, e.name));
    }
    needed += e.count * min_item;
  }
}

std::uint8_t colour_byte(double v, PlyType t) {
  if (is_float(t)) v *= 255.0;  // float colours are 0..1
  if (!(v >= 0)) return 0;
  return v >= 255 ? 255 : static_cast<std::uint8_t>(std::lround(v));
}

}  // namespace

std::string_view to_string(PlyEncoding encoding) {
  switch (encoding) {
    case PlyEncoding::Ascii: return "ascii";
    case PlyEncoding::BinaryLittleEndian: return "binary_little_endian";
    case PlyEncoding::BinaryBigEndian: return "binary_big_endian";
  }
  return "?";
}

PlyEncoding parse_ply_encoding(std::string_view text) {
  if (text == "ascii") return PlyEncoding::Ascii;
  if (text == "binary_little_endian") return PlyEncoding::BinaryLittleEndian;
  if (text == "binary_big_endian") return PlyEncoding::BinaryBigEndian;
  throw Error(fmt::format("unknown PLY encoding '{}' (ascii, binary_little_endian or binary_big_endian)",
                          text::excerpt(text)));
}

PlyFile parse_ply(std::span<const std::uint8_t> bytes, std::string_view name) {
  if (bytes.empty()) throw Error(fmt::format("{}: empty file", name));
  PlyFile file;
  std::size_t body_offset = 0;
  const std::vector<PlyElement> elements = parse_header(bytes, name, file.encoding, body_offset);
  const std::span<const std::uint8_t> body = bytes.subspan(body_offset);
  check_counts_fit(elements, file.encoding, body.size(), name);

  const PlyElement* vertex_element = nullptr;
  for (const PlyElement& e : elements) {
    PlyElementInfo info{e.name, e.count, {}};
    for (const auto& p : e.properties) info.properties.push_back(p.name);
    file.elements.push_back(std::move(info));
    if (e.name == "vertex") vertex_element = &e;
  }
  if (vertex_element == nullptr) throw Error(fmt::format("{}: no vertex element", name));

  PointCloud& cloud = file.cloud;
  TriangleMesh& mesh = file.mesh;
  BodyReader reader(body, file.encoding, name);
  for (const PlyElement& e : elements) {
    // Which vertex attribute each property fills: 0-2 position, 3-5 normal, 6-9 colour, -1 none.
    std::vector<int> slot(e.properties.size(), -1);
    bool has_normal[3] = {}, has_colour = false;
    int face_list = -1;
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
      const PlyProperty& p = e.properties[i];
      if (e.name == "vertex" && !p.is_list) {
        static const char* names[][2] = {{"x", "x"}, {"y", "y"}, {"z", "z"}, {"nx", "normal_x"}, {"ny", "normal_y"},
                                          {"nz", "normal_z"}, {"red", "r"}, {"green", "g"}, {"blue", "b"}, {"alpha", "a"}};
        for (int k = 0; k < 10; ++k) {
          if (p.name == names[k][0] || (k >= 3 && k < 6 && p.name == names[k][1])) slot[i] = k;
        }
        if (slot[i] >= 3 && slot[i] < 6) has_normal[slot[i] - 3] = true;
        if (slot[i] >= 6) has_colour = true;
      }
      if (e.name == "face" && p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index")) {
        face_list = static_cast<int>(i);
      }
    }
    if (&e == vertex_element) {
      int xyz = 0;
      for (int s : slot) xyz += (s >= 0 && s < 3) ? 1 : 0;
      if (xyz != 3) throw Error(fmt::format("{}: vertex element lacks x, y or z", name));
      cloud.points.resize(e.count);
      if (has_normal[0] && has_normal[1] && has_normal[2]) cloud.normals.resize(e.count);
      if (has_colour) cloud.rgba.assign(e.count, 0xff000000u);
    }
    for (std::size_t item = 0; item < e.count; ++item) {
      for (std::size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& p = e.properties[i];
        if (p.is_list) {
          const double count = reader.read(p.count_type);
          if (!(count >= 0 && count <= kMaxListLength)) {
            throw Error(fmt::format("{}: {} {} has a list of {} values", name, e.name, item, count));
          }
          const auto n = static_cast<std::size_t>(count);
          if (static_cast<int>(i) != face_list) {
            for (std::size_t k = 0; k < n; ++k) reader.read(p.type);
            continue;
          }
          if (n < 3) throw Error(fmt::format("{}: face {} has {} vertices", name, item, n));
          std::uint32_t first = 0, prev = 0;
          for (std::size_t k = 0; k < n; ++k) {
            const double v = reader.read(p.type);
            if (!(v >= 0 && v < static_cast<double>(cloud.points.size()))) {
              throw Error(fmt::format("{}: face {} names vertex {} of {}", name, item, v, cloud.points.size()));
            }
            const auto idx = static_cast<std::uint32_t>(v);
            if (k == 0) first = idx;
            else if (k >= 2) mesh.triangles.push_back({first, prev, idx});  // fan
            prev = idx;
          }
          continue;
        }
        const double v = reader.read(p.type);
        if (&e != vertex_element || slot[i] < 0) continue;
        const int s = slot[i];
        if (s < 3) cloud.points[item][s] = static_cast<float>(v);
        else if (s < 6) { if (!cloud.normals.empty()) cloud.normals[item][s - 3] = static_cast<float>(v); }
        else {
          const int shift = s == 9 ? 24 : 8 * (8 - s);  // red 16, green 8, blue 0, alpha 24
          std::uint32_t& c = cloud.rgba[item];
          c = (c & ~(0xffu << shift)) | (std::uint32_t{colour_byte(v, p.type)} << shift);
        }
      }
    }
  }
  cloud.width = static_cast<int>(cloud.points.size());
  cloud.height = 1;
  mesh.vertices = cloud.points;
  mesh.normals = cloud.normals;
  return file;
}

PlyFile read_ply(const std::filesystem::path& path) { return parse_ply(read_file_bytes(path), path.string()); }

namespace {

// Appends header text and body values in one of the three encodings.
class PlyWriter {
 public:
  explicit PlyWriter(PlyEncoding encoding) : encoding_(encoding) {}
  void header(const std::string& h) { out_.insert(out_.end(), h.begin(), h.end()); }
  template <typename T>
  void value(T v) {
    if (encoding_ == PlyEncoding::Ascii) {
      if (!first_in_line_) out_.push_back(' ');
      first_in_line_ = false;
      const std::string s = fmt::format("{}", +v);
      out_.insert(out_.end(), s.begin(), s.end());
      return;
    }
    std::uint8_t b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (encoding_ == PlyEncoding::BinaryBigEndian) {
      for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    }
    out_.insert(out_.end(), b, b + sizeof(T));
  }
  void end_item() {
    if (encoding_ == PlyEncoding::Ascii) out_.push_back('\n');
    first_in_line_ = true;
  }
  std::vector<std::uint8_t> take() { return std::move(out_); }

 private:
  PlyEncoding encoding_;
  std::vector<std::uint8_t> out_;
  bool first_in_line_ = true;
};

std::vector<std::uint8_t> encode(const std::vector<Eigen::Vector3f>& points, const std::vector<Eigen::Vector3f>& normals,
                                 const std::vector<std::uint32_t>& rgba,
                                 const std::vector<std::array<std::uint32_t, 3>>& triangles, PlyEncoding encoding) {
  std::string h = fmt::format("ply\nformat {} 1.0\ncomment written by viewpose\nelement vertex {}\n", to_string(encoding),
                              points.size());
  h += "property float x\nproperty float y\nproperty float z\n";
  if (!normals.empty()) h += "property float nx\nproperty float ny\nproperty float nz\n";
  if (!rgba.empty()) h += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
  if (!triangles.empty()) h += fmt::format("element face {}\nproperty list uchar int vertex_indices\n", triangles.size());
  h += "end_header\n";
  PlyWriter w(encoding);
  w.header(h);
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (int k = 0; k < 3; ++k) w.value(points[i][k]);
    if (!normals.empty()) for (int k = 0; k < 3; ++k) w.value(normals[i][k]);
    if (!rgba.empty()) {
      for (int shift : {16, 8, 0, 24}) w.value(static_cast<std::uint8_t>(rgba[i] >> shift));
    }
    w.end_item();
  }
  for (const auto& t : triangles) {
    w.value(std::uint8_t{3});
    for (std::uint32_t idx : t) w.value(static_cast<std::int32_t>(idx));
    w.end_item();
  }
  return w.take();
}

}  // namespace

std::vector<std::uint8_t> encode_ply(const PointCloud& cloud, PlyEncoding encoding) {
  cloud.check_consistent();
  return encode(cloud.points, cloud.normals, cloud.rgba, {}, encoding);
}

std::vector<std::uint8_t> encode_ply(const TriangleMesh& mesh, PlyEncoding encoding) {
  mesh.check_consistent();
  if (mesh.vertices.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
    throw Error("PLY: too many vertices for 32-bit face indices");
  }
  return encode(mesh.vertices, mesh.normals, {}, mesh.triangles, encoding);
}

void write_ply(const std::filesystem::path& path, const PointCloud& cloud, PlyEncoding encoding) {
  write_file_atomic(path, encode_ply(cloud, encoding));
}

void write_ply(const std::filesystem::path& path, const TriangleMesh& mesh, PlyEncoding encoding) {
  write_file_atomic(path, encode_ply(mesh, encoding));
}

}  // namespace viewpose
