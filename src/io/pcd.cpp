#include "viewpose/io/pcd.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>

#include <fmt/format.h>
#include <lzf.h>

#include "text.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/core/file.hpp"

namespace viewpose {

namespace {

// LZF encodes at best 264 bytes in a 3-byte back reference, so no real stream expands more than
// about 88 times; a header claiming more is refused before anything is allocated.
constexpr std::size_t kLzfMaxRatio = 100;

// Where each field we use sits in a point record, or -1 when the file lacks it.
struct FieldSlots {
  int x = -1, y = -1, z = -1, nx = -1, ny = -1, nz = -1, curvature = -1, rgba = -1, label = -1;
};

struct Layout {
  std::vector<std::size_t> offset;  // byte offset of each field in a binary (point-major) record
  std::size_t point_step = 0;
  std::size_t values_per_point = 0;
  FieldSlots slots;
};

std::optional<PcdEncoding> encoding_named(std::string_view text) {
  if (text == "ascii") return PcdEncoding::Ascii;
  if (text == "binary") return PcdEncoding::Binary;
  if (text == "binary_compressed") return PcdEncoding::BinaryCompressed;
  return std::nullopt;
}

double read_scalar(const std::uint8_t* p, const PcdField& f) {
  switch (f.type) {
    case 'F':
      if (f.size == 4) { float v; std::memcpy(&v, p, 4); return v; }
      { double v; std::memcpy(&v, p, 8); return v; }
    case 'U':
      switch (f.size) {
        case 1: return *p;
        case 2: { std::uint16_t v; std::memcpy(&v, p, 2); return v; }
        case 4: { std::uint32_t v; std::memcpy(&v, p, 4); return v; }
        default: { std::uint64_t v; std::memcpy(&v, p, 8); return static_cast<double>(v); }
      }
    default:
      switch (f.size) {
        case 1: { std::int8_t v; std::memcpy(&v, p, 1); return v; }
        case 2: { std::int16_t v; std::memcpy(&v, p, 2); return v; }
        case 4: { std::int32_t v; std::memcpy(&v, p, 4); return v; }
        default: { std::int64_t v; std::memcpy(&v, p, 8); return static_cast<double>(v); }
      }
  }
}

// Packed colour: PCL stores rgb as the bits of a float, rgba as an unsigned int; both are the same
// 32 bits.
std::uint32_t to_u32(double v) {
  return (std::isfinite(v) && v >= 0 && v <= 4294967295.0) ? static_cast<std::uint32_t>(v) : 0u;
}

// (A colour field of another size is read as a number; one past 32 bits, as the fuzzer once gave, is 0.)
std::uint32_t read_bits32(const std::uint8_t* p, const PcdField& f) {
  if (f.size == 4) { std::uint32_t v; std::memcpy(&v, p, 4); return v; }
  return to_u32(read_scalar(p, f));
}

Layout make_layout(const PcdHeader& h, std::string_view name) {
  Layout layout;
  for (std::size_t i = 0; i < h.fields.size(); ++i) {
    const PcdField& f = h.fields[i];
    layout.offset.push_back(layout.point_step);
    layout.point_step += static_cast<std::size_t>(f.size) * static_cast<std::size_t>(f.count);
    layout.values_per_point += static_cast<std::size_t>(f.count);
    int* slot = nullptr;
    FieldSlots& s = layout.slots;
    if (f.name == "x") slot = &s.x;
    else if (f.name == "y") slot = &s.y;
    else if (f.name == "z") slot = &s.z;
    else if (f.name == "normal_x") slot = &s.nx;
    else if (f.name == "normal_y") slot = &s.ny;
    else if (f.name == "normal_z") slot = &s.nz;
    else if (f.name == "curvature") slot = &s.curvature;
    else if (f.name == "rgb" || f.name == "rgba") slot = &s.rgba;
    else if (f.name == "label") slot = &s.label;
    if (slot == nullptr) continue;  // a field we do not use: skipped
    if (*slot >= 0) throw Error(fmt::format("{}: field '{}' appears twice", name, f.name));
    if (f.count != 1) throw Error(fmt::format("{}: field '{}' has COUNT {}, expected 1", name, f.name, f.count));
    *slot = static_cast<int>(i);
  }
  const FieldSlots& s = layout.slots;
  if (s.x < 0 || s.y < 0 || s.z < 0) throw Error(fmt::format("{}: no x y z fields", name));
  for (int xyz : {s.x, s.y, s.z}) {
    if (h.fields[static_cast<std::size_t>(xyz)].type != 'F') {
      throw Error(fmt::format("{}: x, y and z must be floating point (TYPE F)", name));
    }
  }
  const int normal_fields = (s.nx >= 0) + (s.ny >= 0) + (s.nz >= 0);
  if (normal_fields != 0 && normal_fields != 3) {
    throw Error(fmt::format("{}: has only some of normal_x, normal_y, normal_z", name));
  }
  return layout;
}

template <typename T>
T parse_header_int(std::string_view token, std::string_view key, std::string_view name, long long max_value) {
  long long v = 0;
  if (!text::parse_number(token, v) || v < 0 || v > max_value) {
    throw Error(fmt::format("{}: {} '{}' is not a whole number from 0 to {}", name, key, text::excerpt(token), max_value));
  }
  return static_cast<T>(v);
}

// Parses the header; returns it with the offset of the first data byte.
PcdHeader parse_header(std::span<const std::uint8_t> bytes, std::string_view name, std::size_t& data_offset) {
  PcdHeader h;
  text::LineReader lines(bytes.first(std::min(bytes.size(), kMaxPcdHeaderBytes)));
  std::vector<std::string_view> sizes, types, counts;
  std::optional<std::size_t> points;
  bool have_width = false, have_height = false, first = true, found_data = false;
  std::string_view line;
  while (lines.next(line)) {
    if (line.size() >= 1 && line.find('\0') != std::string_view::npos) {
      throw Error(fmt::format("{}: not a PCD file (binary bytes in the header)", name));
    }
    const auto tokens = text::split_whitespace(line);
    if (tokens.empty()) continue;
    if (tokens[0].front() == '#') { first = false; continue; }
    const std::string_view key = tokens[0];
    const std::span<const std::string_view> args(tokens.data() + 1, tokens.size() - 1);
    auto need_args = [&](std::size_t n) {
      if (args.size() != n) throw Error(fmt::format("{}: {} needs {} value(s), got {}", name, key, n, args.size()));
    };
    if (key == "VERSION") {
      need_args(1);
      h.version = std::string(args[0]);
      if (h.version != "0.7" && h.version != ".7" && h.version != "0.6" && h.version != ".6") {
        throw Error(fmt::format("{}: unsupported PCD version '{}' (0.6 and 0.7 are read)", name, text::excerpt(args[0])));
      }
      if (h.version.front() == '.') h.version.insert(h.version.begin(), '0');
    } else if (key == "FIELDS" || key == "COLUMNS") {
      if (args.empty() || args.size() > 256) throw Error(fmt::format("{}: FIELDS must list 1 to 256 fields", name));
      for (auto a : args) h.fields.push_back(PcdField{std::string(a), 4, 'F', 1});
    } else if (key == "SIZE") {
      sizes.assign(args.begin(), args.end());
    } else if (key == "TYPE") {
      types.assign(args.begin(), args.end());
    } else if (key == "COUNT") {
      counts.assign(args.begin(), args.end());
    } else if (key == "WIDTH") {
      need_args(1);
      h.width = parse_header_int<int>(args[0], key, name, std::numeric_limits<int>::max());
      have_width = true;
    } else if (key == "HEIGHT") {
      need_args(1);
      h.height = parse_header_int<int>(args[0], key, name, std::numeric_limits<int>::max());
      have_height = true;
    } else if (key == "VIEWPOINT") {
      need_args(7);
      for (auto a : args) {
        double v;
        if (!text::parse_number(a, v)) throw Error(fmt::format("{}: VIEWPOINT value '{}' is not a number", name, text::excerpt(a)));
      }
    } else if (key == "POINTS") {
      need_args(1);
      points = parse_header_int<std::size_t>(args[0], key, name, std::numeric_limits<long long>::max());
    } else if (key == "DATA") {
      need_args(1);
      const auto encoding = encoding_named(args[0]);
      if (!encoding) {
        throw Error(fmt::format("{}: unknown DATA encoding '{}' (ascii, binary or binary_compressed)", name,
                                text::excerpt(args[0])));
      }
      h.encoding = *encoding;
      data_offset = lines.offset();
      found_data = true;
      break;
    } else {
      if (first) throw Error(fmt::format("{}: not a PCD file (starts with '{}')", name, text::excerpt(line)));
      throw Error(fmt::format("{}: unknown header line '{}'", name, text::excerpt(line)));
    }
    first = false;
  }
  if (!found_data) {
    if (bytes.size() >= kMaxPcdHeaderBytes) {
      throw Error(fmt::format("{}: no DATA line in the first {} bytes (not a PCD file, or a huge header)", name,
                              kMaxPcdHeaderBytes));
    }
    throw Error(fmt::format("{}: header ends without a DATA line (truncated or not a PCD file)", name));
  }
  if (h.fields.empty()) throw Error(fmt::format("{}: no FIELDS line", name));
  if (!have_width || !have_height) throw Error(fmt::format("{}: WIDTH or HEIGHT missing", name));
  if (sizes.size() != h.fields.size() || types.size() != h.fields.size()) {
    throw Error(fmt::format("{}: FIELDS lists {} fields but SIZE has {} and TYPE {}", name, h.fields.size(),
                            sizes.size(), types.size()));
  }
  if (!counts.empty() && counts.size() != h.fields.size()) {
    throw Error(fmt::format("{}: FIELDS lists {} fields but COUNT has {}", name, h.fields.size(), counts.size()));
  }
  for (std::size_t i = 0; i < h.fields.size(); ++i) {
    PcdField& f = h.fields[i];
    f.size = parse_header_int<int>(sizes[i], "SIZE", name, 8);
    if (types[i].size() != 1 || (types[i][0] != 'F' && types[i][0] != 'U' && types[i][0] != 'I')) {
      throw Error(fmt::format("{}: TYPE of field '{}' is '{}', expected F, U or I", name, f.name, text::excerpt(types[i])));
    }
    f.type = types[i][0];
    if (f.size != 1 && f.size != 2 && f.size != 4 && f.size != 8) {
      throw Error(fmt::format("{}: SIZE of field '{}' is {}, expected 1, 2, 4 or 8", name, f.name, f.size));
    }
    if (f.type == 'F' && f.size != 4 && f.size != 8) {
      throw Error(fmt::format("{}: floating-point field '{}' has SIZE {}", name, f.name, f.size));
    }
    f.count = counts.empty() ? 1 : parse_header_int<int>(counts[i], "COUNT", name, 1 << 20);
    if (f.count < 1) throw Error(fmt::format("{}: COUNT of field '{}' is 0", name, f.name));
  }
  const std::size_t grid = static_cast<std::size_t>(h.width) * static_cast<std::size_t>(h.height);
  h.points = points.value_or(grid);
  if (h.points != grid) {
    throw Error(fmt::format("{}: POINTS {} is not WIDTH x HEIGHT = {} x {}", name, h.points, h.width, h.height));
  }
  if (h.points > kMaxCloudPoints) {
    throw Error(fmt::format("{}: {} points is more than the limit of {}", name, h.points, kMaxCloudPoints));
  }
  return h;
}

// Sizes the cloud's points and the attributes the file has, for n points.
void allocate(PointCloud& cloud, const FieldSlots& s, std::size_t n) {
  cloud.points.resize(n);
  if (s.nx >= 0) cloud.normals.resize(n);
  if (s.curvature >= 0) cloud.curvature.resize(n);
  if (s.rgba >= 0) cloud.rgba.resize(n);
  if (s.label >= 0) cloud.labels.resize(n);
}

// Fills the cloud from the binary data; value_ptr(i, slot) points at point i's value of a field, so
// the point-major (binary) and field-major (binary_compressed) layouts share this code.
template <typename ValuePtr>
void fill_cloud(PointCloud& cloud, const PcdHeader& h, const Layout& L, ValuePtr value_ptr) {
  const FieldSlots& s = L.slots;
  const auto field = [&](int slot) -> const PcdField& { return h.fields[static_cast<std::size_t>(slot)]; };
  const std::size_t n = h.points;
  allocate(cloud, s, n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto get = [&](int slot) { return static_cast<float>(read_scalar(value_ptr(i, slot), field(slot))); };
    cloud.points[i] = {get(s.x), get(s.y), get(s.z)};
    if (s.nx >= 0) cloud.normals[i] = {get(s.nx), get(s.ny), get(s.nz)};
    if (s.curvature >= 0) cloud.curvature[i] = get(s.curvature);
    if (s.rgba >= 0) cloud.rgba[i] = read_bits32(value_ptr(i, s.rgba), field(s.rgba));
    if (s.label >= 0) cloud.labels[i] = to_u32(read_scalar(value_ptr(i, s.label), field(s.label)));
  }
}

void read_ascii(PointCloud& cloud, const PcdHeader& h, const Layout& L, std::span<const std::uint8_t> data,
                std::string_view name) {
  // Every value takes at least one character and one separator: refuse counts the data cannot hold.
  if (h.points > 0 && h.points * L.values_per_point * 2 > data.size() + 1) {
    throw Error(fmt::format("{}: header says {} points but the data holds at most {}", name, h.points,
                            (data.size() + 1) / (2 * L.values_per_point)));
  }
  // Column index of the first value of each field on a line.
  std::vector<std::size_t> column(h.fields.size());
  for (std::size_t i = 0, c = 0; i < h.fields.size(); ++i) {
    column[i] = c;
    c += static_cast<std::size_t>(h.fields[i].count);
  }
  const FieldSlots& s = L.slots;
  const std::size_t n = h.points;
  allocate(cloud, s, n);
  text::LineReader lines(data);
  std::string_view line;
  std::vector<std::string_view> tokens;
  for (std::size_t i = 0; i < n; ++i) {
    do {
      if (!lines.next(line)) {
        throw Error(fmt::format("{}: header says {} points but the data ends after {}", name, n, i));
      }
      tokens = text::split_whitespace(line);
    } while (tokens.empty());
    if (tokens.size() != L.values_per_point) {
      throw Error(fmt::format("{}: point {} has {} values, expected {}", name, i, tokens.size(), L.values_per_point));
    }
    const auto token = [&](int slot) { return tokens[column[static_cast<std::size_t>(slot)]]; };
    const auto get_float = [&](int slot) {
      float v;
      if (!text::parse_number(token(slot), v)) {
        throw Error(fmt::format("{}: point {}: '{}' is not a number", name, i, text::excerpt(token(slot))));
      }
      return v;
    };
    const auto get_uint = [&](int slot) -> std::uint32_t {
      const PcdField& f = h.fields[static_cast<std::size_t>(slot)];
      if (f.type == 'F') {
        // PCL writes a packed rgb float as its value; its bits are the colour.
        const float v = get_float(slot);
        return f.name == "rgb" || f.name == "rgba" ? std::bit_cast<std::uint32_t>(v) : to_u32(v);
      }
      std::uint64_t v;
      if (!text::parse_number(token(slot), v) || v > 0xffffffffu) {
        throw Error(fmt::format("{}: point {}: '{}' is not a 32-bit unsigned number", name, i, text::excerpt(token(slot))));
      }
      return static_cast<std::uint32_t>(v);
    };
    cloud.points[i] = {get_float(s.x), get_float(s.y), get_float(s.z)};
    if (s.nx >= 0) cloud.normals[i] = {get_float(s.nx), get_float(s.ny), get_float(s.nz)};
    if (s.curvature >= 0) cloud.curvature[i] = get_float(s.curvature);
    if (s.rgba >= 0) cloud.rgba[i] = get_uint(s.rgba);
    if (s.label >= 0) cloud.labels[i] = get_uint(s.label);
  }
  while (lines.next(line)) {
    if (!text::trim(line).empty()) throw Error(fmt::format("{}: more data than the {} points the header says", name, n));
  }
}

}  // namespace

std::string_view to_string(PcdEncoding encoding) {
  switch (encoding) {
    case PcdEncoding::Ascii: return "ascii";
    case PcdEncoding::Binary: return "binary";
    case PcdEncoding::BinaryCompressed: return "binary_compressed";
  }
  return "?";
}

PcdEncoding parse_pcd_encoding(std::string_view text) {
  if (const auto encoding = encoding_named(text)) return *encoding;
  throw Error(fmt::format("unknown PCD encoding '{}' (ascii, binary or binary_compressed)", text::excerpt(text)));
}

PcdFile parse_pcd(std::span<const std::uint8_t> bytes, std::string_view name) {
  if (bytes.empty()) throw Error(fmt::format("{}: empty file", name));
  PcdFile file;
  std::size_t data_offset = 0;
  file.header = parse_header(bytes, name, data_offset);
  const PcdHeader& h = file.header;
  const Layout L = make_layout(h, name);
  PointCloud& cloud = file.cloud;
  cloud.width = h.height > 1 ? h.width : static_cast<int>(h.points);
  cloud.height = h.height > 1 ? h.height : 1;
  const std::span<const std::uint8_t> data = bytes.subspan(data_offset);

  switch (h.encoding) {
    case PcdEncoding::Ascii:
      read_ascii(cloud, h, L, data, name);
      break;
    case PcdEncoding::Binary: {
      if (data.size() / L.point_step < h.points) {
        throw Error(fmt::format("{}: header says {} points but the binary data holds {}", name, h.points,
                                data.size() / L.point_step));
      }
      fill_cloud(cloud, h, L, [&](std::size_t i, int slot) {
        return data.data() + i * L.point_step + L.offset[static_cast<std::size_t>(slot)];
      });
      break;
    }
    case PcdEncoding::BinaryCompressed: {
      if (data.size() < 8) throw Error(fmt::format("{}: compressed data ends before its size fields", name));
      std::uint32_t compressed = 0, raw = 0;
      std::memcpy(&compressed, data.data(), 4);
      std::memcpy(&raw, data.data() + 4, 4);
      const std::size_t expected = h.points * L.point_step;
      if (raw != expected) {
        throw Error(fmt::format("{}: compressed block unpacks to {} bytes but {} points need {}", name, raw, h.points,
                                expected));
      }
      if (compressed > data.size() - 8) {
        throw Error(fmt::format("{}: compressed block of {} bytes but only {} follow (truncated)", name, compressed,
                                data.size() - 8));
      }
      if (raw > std::size_t{compressed} * kLzfMaxRatio + 64) {
        throw Error(fmt::format("{}: {} compressed bytes cannot unpack to {} bytes", name, compressed, raw));
      }
      std::vector<std::uint8_t> unpacked(raw);
      if (raw > 0) {
        const unsigned got = lzf_decompress(data.data() + 8, compressed, unpacked.data(), raw);
        if (got != raw) throw Error(fmt::format("{}: compressed data is corrupt (unpacked {} of {} bytes)", name, got, raw));
      }
      // Unpacked data is field-major: all points' values of field 0, then of field 1, ...
      std::vector<std::size_t> field_start(h.fields.size());
      for (std::size_t f = 0; f < h.fields.size(); ++f) field_start[f] = L.offset[f] * h.points;
      fill_cloud(cloud, h, L, [&](std::size_t i, int slot) {
        const auto f = static_cast<std::size_t>(slot);
        return unpacked.data() + field_start[f] + i * static_cast<std::size_t>(h.fields[f].size);
      });
      break;
    }
  }
  return file;
}

PcdFile read_pcd(const std::filesystem::path& path) { return parse_pcd(read_file_bytes(path), path.string()); }

std::vector<std::uint8_t> encode_pcd(const PointCloud& cloud, PcdEncoding encoding) {
  cloud.check_consistent();
  // Every field we write is 4 bytes a point: keep each as a column of raw 32-bit words.
  struct Column {
    const char* name;
    char type;
    std::vector<std::uint32_t> words;
  };
  const std::size_t n = cloud.size();
  std::vector<Column> columns;
  const auto add_float = [&](const char* name, auto&& value) {
    Column c{name, 'F', std::vector<std::uint32_t>(n)};
    for (std::size_t i = 0; i < n; ++i) c.words[i] = std::bit_cast<std::uint32_t>(static_cast<float>(value(i)));
    columns.push_back(std::move(c));
  };
  for (int k = 0; k < 3; ++k) {
    static const char* names[] = {"x", "y", "z"};
    add_float(names[k], [&](std::size_t i) { return cloud.points[i][k]; });
  }
  if (cloud.has_normals()) {
    for (int k = 0; k < 3; ++k) {
      static const char* names[] = {"normal_x", "normal_y", "normal_z"};
      add_float(names[k], [&](std::size_t i) { return cloud.normals[i][k]; });
    }
  }
  if (!cloud.curvature.empty()) add_float("curvature", [&](std::size_t i) { return cloud.curvature[i]; });
  if (!cloud.rgba.empty()) columns.push_back({"rgba", 'U', cloud.rgba});
  if (!cloud.labels.empty()) columns.push_back({"label", 'U', cloud.labels});

  std::string header = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS";
  std::string size_line = "SIZE", type_line = "TYPE", count_line = "COUNT";
  for (const Column& c : columns) {
    header += fmt::format(" {}", c.name);
    size_line += " 4";
    type_line += fmt::format(" {}", c.type);
    count_line += " 1";
  }
  header += fmt::format("\n{}\n{}\n{}\nWIDTH {}\nHEIGHT {}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {}\nDATA {}\n", size_line,
                        type_line, count_line, cloud.width, cloud.height, n, to_string(encoding));
  std::vector<std::uint8_t> out(header.begin(), header.end());
  const auto append = [&out](const void* data, std::size_t bytes) {
    const auto* p = static_cast<const std::uint8_t*>(data);
    out.insert(out.end(), p, p + bytes);
  };
  switch (encoding) {
    case PcdEncoding::Ascii: {
      std::string body;
      for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t f = 0; f < columns.size(); ++f) {
          if (f) body += ' ';
          const std::uint32_t w = columns[f].words[i];
          const float v = std::bit_cast<float>(w);
          body += columns[f].type == 'U' ? fmt::format("{}", w) : std::isnan(v) ? std::string("nan") : fmt::format("{}", v);
        }
        body += '\n';
      }
      append(body.data(), body.size());
      break;
    }
    case PcdEncoding::Binary: {
      std::vector<std::uint32_t> records;
      records.reserve(n * columns.size());
      for (std::size_t i = 0; i < n; ++i) {
        for (const Column& c : columns) records.push_back(c.words[i]);
      }
      append(records.data(), records.size() * 4);
      break;
    }
    case PcdEncoding::BinaryCompressed: {
      std::vector<std::uint32_t> raw;  // field-major, as PCL lays it out
      raw.reserve(n * columns.size());
      for (const Column& c : columns) raw.insert(raw.end(), c.words.begin(), c.words.end());
      const std::size_t raw_bytes = raw.size() * 4;
      if (raw_bytes > 0xffffffffu) throw Error("PCD: cloud too large for binary_compressed (over 4 GiB)");
      std::vector<std::uint8_t> packed(raw_bytes + raw_bytes / 16 + 64);
      unsigned packed_size = 0;
      if (raw_bytes > 0) {
        packed_size = lzf_compress(raw.data(), static_cast<unsigned>(raw_bytes), packed.data(),
                                   static_cast<unsigned>(packed.size()));
        if (packed_size == 0) throw Error("PCD: LZF compression failed");
      }
      const std::uint32_t sizes[2] = {packed_size, static_cast<std::uint32_t>(raw_bytes)};
      append(sizes, 8);
      append(packed.data(), packed_size);
      break;
    }
  }
  return out;
}

void write_pcd(const std::filesystem::path& path, const PointCloud& cloud, PcdEncoding encoding) {
  write_file_atomic(path, encode_pcd(cloud, encoding));
}

}  // namespace viewpose
