#include "viewpose/database/view_database.hpp"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "viewpose/core/threads.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/core/file.hpp"
#include "viewpose/core/kdtree.hpp"
#include "viewpose/core/nearest_grid.hpp"
#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/simplify.hpp"
#include "viewpose/render/view_sphere.hpp"
#include "viewpose/segment/voxel_grid.hpp"

namespace viewpose {

namespace {

// File layout: an 32-byte header, then the payload it describes.
constexpr char kMagic[8] = {'V', 'P', 'D', 'B', '\r', '\n', '\x1a', '\n'};  // catches text-mode copies too
constexpr std::uint32_t kByteOrderMark = 0x01020304;
constexpr std::size_t kHeaderBytes = 32;
constexpr std::size_t kTablesHeaderBytes = 16;  // after the payload: the pair tables' size and CRC-32

class Writer {
 public:
  template <typename T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  void put_floats(const float* data, std::size_t n) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(data);
    bytes.insert(bytes.end(), p, p + n * sizeof(float));
  }
  void put_string(const std::string& s) {
    put(static_cast<std::uint32_t>(s.size()));
    bytes.insert(bytes.end(), s.begin(), s.end());
  }
  void put_points(const std::vector<Eigen::Vector3f>& pts) {
    put(static_cast<std::uint32_t>(pts.size()));
    for (const auto& p : pts) put_floats(p.data(), 3);
  }
  void put_mesh(const TriangleMesh& mesh) {
    put_points(mesh.vertices);
    put(static_cast<std::uint32_t>(mesh.triangles.size()));
    for (const auto& t : mesh.triangles)
      for (std::uint32_t i : t) put(i);
  }
  void put_cells(const std::vector<std::uint32_t>& cells) {
    put(static_cast<std::uint64_t>(cells.size()));
    const auto* p = reinterpret_cast<const std::uint8_t*>(cells.data());
    bytes.insert(bytes.end(), p, p + cells.size() * sizeof(std::uint32_t));
  }
  void put_pair_table(const PpfTable* t) {
    put(static_cast<std::uint8_t>(t ? 1 : 0));
    if (!t) return;
    put(t->diameter_m);
    put(t->sample_fraction);
    put(static_cast<std::int32_t>(t->angle_bins));
    put(t->normal_split_deg);
    put_points(t->sampled.points);
    put_points(t->sampled.normals);
    put_cells(t->key_start);
    put_cells(t->entries);
  }
  std::vector<std::uint8_t> bytes;
};

class Reader {
 public:
  Reader(std::span<const std::uint8_t> bytes, std::string_view name) : bytes_(bytes), name_(name) {}
  template <typename T>
  T get() {
    T v;
    need(sizeof(T));
    std::memcpy(&v, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  void get_floats(float* out, std::size_t n) {
    need(n * sizeof(float));
    if (n > 0) std::memcpy(out, bytes_.data() + pos_, n * sizeof(float));
    pos_ += n * sizeof(float);
  }
  std::string get_string() {
    const auto n = get<std::uint32_t>();
    need(n);
    std::string s(reinterpret_cast<const char*>(bytes_.data() + pos_), n);
    pos_ += n;
    return s;
  }
  std::vector<Eigen::Vector3f> get_points() {
    const auto n = get<std::uint32_t>();
    need(std::size_t{n} * 12);  // before allocating
    std::vector<Eigen::Vector3f> pts(n);
    static_assert(sizeof(Eigen::Vector3f) == 12);
    get_floats(pts.empty() ? nullptr : pts.front().data(), 3 * std::size_t{n});
    // x * 0 is 0 for every finite x and NaN for an infinite or NaN one: one pass without a branch
    // per value, which vectorizes.
    float zero = 0;
    for (const Eigen::Vector3f& p : pts) zero += (p * 0.0f).sum();
    if (!(zero == 0)) fail("a point or normal is not a finite number");
    return pts;
  }
  TriangleMesh get_mesh() {
    TriangleMesh mesh;
    mesh.vertices = get_points();
    const auto n_triangles = get<std::uint32_t>();
    need_records(n_triangles, 12);
    mesh.triangles.resize(n_triangles);
    std::uint32_t largest = 0;
    for (auto& t : mesh.triangles) {
      for (auto& vertex : t) largest = std::max(largest, vertex = get<std::uint32_t>());
    }
    if (!mesh.triangles.empty() && largest >= mesh.vertices.size()) fail("a triangle names a vertex that does not exist");
    return mesh;
  }
  std::vector<std::uint32_t> get_cells() {
    const auto n = get<std::uint64_t>();
    need_records(n, sizeof(std::uint32_t));
    std::vector<std::uint32_t> cells(static_cast<std::size_t>(n));
    if (n > 0) std::memcpy(cells.data(), bytes_.data() + pos_, cells.size() * sizeof(std::uint32_t));
    pos_ += cells.size() * sizeof(std::uint32_t);
    return cells;
  }
  std::shared_ptr<const PpfTable> get_pair_table() {
    const auto present = get<std::uint8_t>();
    if (present == 0) return nullptr;
    if (present != 1) fail("an object's pair table flag is neither 0 nor 1");
    auto t = std::make_shared<PpfTable>();
    t->diameter_m = get<double>();
    t->sample_fraction = get<double>();
    t->angle_bins = get<std::int32_t>();
    t->normal_split_deg = get<double>();
    t->sampled.points = get_points();
    t->sampled.normals = get_points();
    t->key_start = get_cells();
    t->entries = get_cells();
    try {
      check_ppf_table(*t);
    } catch (const Error& e) {
      fail(e.what());
    }
    return t;
  }
  /// Fails unless `count` records of at least `min_bytes` each can still follow.
  void need_records(std::size_t count, std::size_t min_bytes) const {
    if (count > (bytes_.size() - pos_) / min_bytes) fail(fmt::format("says {} records but is too short for them", count));
  }
  bool at_end() const { return pos_ == bytes_.size(); }
  [[noreturn]] void fail(const std::string& why) const { throw Error(fmt::format("{}: {}", name_, why)); }

 private:
  void need(std::size_t n) const {
    if (n > bytes_.size() - pos_) fail("database ends early (truncated)");
  }
  std::span<const std::uint8_t> bytes_;
  std::size_t pos_ = 0;
  std::string_view name_;
};

nlohmann::json params_json(const DatabaseParams& p) {
  const auto& K = p.camera;
  return {{"camera", {{"fx", K.fx}, {"fy", K.fy}, {"cx", K.cx}, {"cy", K.cy}, {"width", K.width}, {"height", K.height}}},
          {"subdivisions", p.subdivisions},
          {"distance_m", p.distance_m},
          {"voxel_m", p.voxel_m},
          {"icp_voxel_m", p.icp_voxel_m},
          {"normal_radius_m", p.describe.normals.radius_m},
          {"drawn_mesh_error_m", p.drawn_mesh_error_m},
          {"grid_cell_m", p.grid_cell_m},
          {"grid_margin_m", p.grid_margin_m},
          {"max_grid_bytes", p.max_grid_bytes},
          {"ppf", {{"sample_fraction", p.ppf.sample_fraction}, {"angle_bins", p.ppf.angle_bins}, {"normal_split_deg", p.ppf.normal_split_deg}}},
          {"max_pair_table_bytes", p.max_pair_table_bytes},
          {"vfh", {{"normalize_bins", p.describe.vfh.normalize_bins},
                   {"normalize_distances", p.describe.vfh.normalize_distances},
                   {"size_component", p.describe.vfh.size_component},
                   {"pcl_compatible", p.describe.vfh.pcl_compatible}}}};
}

DatabaseParams params_from_json(const std::string& text, const Reader& r) {
  try {
    const auto j = nlohmann::json::parse(text);
    DatabaseParams p;
    // Every number is read as a double and checked before it is narrowed: json's own get<int> or
    // get<float> of 5e51 is a conversion C++ leaves undefined (the fuzzer found one).
    const auto whole = [&](const nlohmann::json& x, int most) {
      const double d = x.get<double>();
      if (!(d >= 0 && d <= most) || d != std::floor(d)) r.fail("build parameters are out of range (camera size or view sphere)");
      return static_cast<int>(d);
    };
    const auto length = [&](const nlohmann::json& x) {
      const double d = x.get<double>();
      if (!(std::isfinite(d) && d > 0 && d <= 1.0)) {
        r.fail("build parameters are out of range (a voxel, normal radius, drawing error or grid size is not in (0, 1] m)");
      }
      return static_cast<float>(d);
    };
    const auto& c = j.at("camera");
    p.camera = {c.at("fx").get<double>(), c.at("fy").get<double>(), c.at("cx").get<double>(), c.at("cy").get<double>(),
                whole(c.at("width"), 16384), whole(c.at("height"), 16384)};
    p.subdivisions = whole(j.at("subdivisions"), 6);
    p.distance_m = j.at("distance_m").get<double>();
    p.voxel_m = length(j.at("voxel_m"));
    p.icp_voxel_m = length(j.at("icp_voxel_m"));
    p.describe.normals.radius_m = length(j.at("normal_radius_m"));
    p.drawn_mesh_error_m = length(j.at("drawn_mesh_error_m"));
    p.grid_cell_m = length(j.at("grid_cell_m"));
    p.grid_margin_m = length(j.at("grid_margin_m"));
    const double max_grid_bytes = j.at("max_grid_bytes").get<double>();
    if (!(max_grid_bytes >= 0 && max_grid_bytes <= 1e15) || max_grid_bytes != std::floor(max_grid_bytes)) {
      r.fail("build parameters are out of range (max_grid_bytes)");
    }
    p.max_grid_bytes = static_cast<std::size_t>(max_grid_bytes);
    const double max_pair_table_bytes = j.at("max_pair_table_bytes").get<double>();
    if (!(max_pair_table_bytes >= 0 && max_pair_table_bytes <= 1e15) || max_pair_table_bytes != std::floor(max_pair_table_bytes)) {
      r.fail("build parameters are out of range (max_pair_table_bytes)");
    }
    p.max_pair_table_bytes = static_cast<std::size_t>(max_pair_table_bytes);
    const auto& ppf = j.at("ppf");
    p.ppf.sample_fraction = ppf.at("sample_fraction").get<double>();
    p.ppf.angle_bins = whole(ppf.at("angle_bins"), 13440);
    p.ppf.normal_split_deg = ppf.at("normal_split_deg").get<double>();
    try {
      check_ppf_options(p.ppf);
    } catch (const Error& e) {
      r.fail(fmt::format("build parameters are out of range ({})", e.what()));
    }
    const auto& v = j.at("vfh");
    p.describe.vfh.normalize_bins = v.at("normalize_bins").get<bool>();
    p.describe.vfh.normalize_distances = v.at("normalize_distances").get<bool>();
    p.describe.vfh.size_component = v.at("size_component").get<bool>();
    p.describe.vfh.pcl_compatible = v.at("pcl_compatible").get<bool>();
    // Values a damaged or hand-made file could hold that would make every later stage misbehave.
    const auto positive = [](double x, double most) { return std::isfinite(x) && x > 0 && x <= most; };
    if (!positive(p.camera.fx, 1e5) || !positive(p.camera.fy, 1e5) || !std::isfinite(p.camera.cx) || !std::isfinite(p.camera.cy) ||
        p.camera.width <= 0 || p.camera.height <= 0 || p.camera.width > 16384 || p.camera.height > 16384 ||
        p.subdivisions < 0 || p.subdivisions > 6 || !positive(p.distance_m, 1e3) || !positive(p.voxel_m, 1.0) ||
        !positive(p.icp_voxel_m, 1.0) || !positive(p.describe.normals.radius_m, 1.0)) {
      r.fail("build parameters are out of range (camera, view sphere, voxel or normal radius)");
    }
    return p;
  } catch (const nlohmann::json::exception& e) {
    r.fail(fmt::format("build parameters are unreadable: {}", e.what()));
  }
}

}  // namespace

std::vector<std::uint8_t> ViewDatabase::serialize() const {
  Writer w;
  w.put_string(params_json(params).dump());
  w.put(static_cast<std::uint32_t>(objects.size()));
  for (const auto& o : objects) {
    w.put(static_cast<std::int32_t>(o.id));
    w.put_string(o.name);
    w.put(o.diameter_m);
    w.put_mesh(o.mesh);
    w.put_points(o.model_points);
    w.put_points(o.model_normals);
    w.put(static_cast<std::uint32_t>(o.symmetries.discrete.size()));
    for (const Transform& S : o.symmetries.discrete)
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) w.put(S(r, c));
    w.put(static_cast<std::uint32_t>(o.symmetries.continuous.size()));
    for (const ContinuousSymmetry& c : o.symmetries.continuous)
      for (int k = 0; k < 3; ++k) {
        w.put(c.axis[k]);
        w.put(c.offset_m[k]);
      }
    w.put_mesh(o.drawn_mesh);
    w.put_cells(o.nearest_cells);
  }
  w.put(static_cast<std::uint32_t>(views.size()));
  for (const auto& v : views) {
    w.put(v.object);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) w.put(v.T_view_object(r, c));
    w.put_floats(v.vfh.data(), v.vfh.size());
    w.put_floats(v.crh.data(), v.crh.size());
    w.put_floats(v.centroid.data(), 3);
    w.put(v.described_points);
    w.put_points(v.icp_points);
  }
  Writer tables;
  if (stored_pair_table_bytes(*this) > 0) {
    for (const auto& o : objects) tables.put_pair_table(o.pair_table.get());
  }
  return file_from_payload(w.bytes, tables.bytes);
}

namespace {
// crc32_z takes a size_t length: a payload over 4 GiB is checked whole, not modulo 2^32.
std::uint32_t payload_crc(std::span<const std::uint8_t> payload) {
  return static_cast<std::uint32_t>(crc32_z(0, payload.data(), payload.size()));
}
}  // namespace

std::vector<std::uint8_t> ViewDatabase::file_from_payload(std::span<const std::uint8_t> payload,
                                                          std::span<const std::uint8_t> pair_tables) {
  Writer file;
  file.bytes.reserve(kHeaderBytes + payload.size() + kTablesHeaderBytes + pair_tables.size());
  for (char c : kMagic) file.put(c);
  file.put(kFormatVersion);
  file.put(kByteOrderMark);
  file.put(static_cast<std::uint64_t>(payload.size()));
  file.put(payload_crc(payload));
  file.put(std::uint32_t{0});  // reserved
  file.bytes.insert(file.bytes.end(), payload.begin(), payload.end());
  file.put(static_cast<std::uint64_t>(pair_tables.size()));
  file.put(payload_crc(pair_tables));
  file.put(std::uint32_t{0});  // reserved
  file.bytes.insert(file.bytes.end(), pair_tables.begin(), pair_tables.end());
  return file.bytes;
}

namespace {

// The pair tables' own 16-byte header, at the start of `at` (which holds at least that): their
// size and CRC-32.
struct TablesHeader {
  std::uint64_t size = 0;
  std::uint32_t crc = 0;
};

TablesHeader tables_header(std::span<const std::uint8_t> at) {
  TablesHeader h;
  std::memcpy(&h.size, at.data(), 8);
  std::memcpy(&h.crc, at.data() + 8, 4);
  return h;
}

// Where a file's parts lie, from its first kHeaderBytes + payload + kTablesHeaderBytes bytes (all
// of `bytes` may be longer) and its whole size; the payload's checksum checked.
struct FileParts {
  std::span<const std::uint8_t> payload;
  TablesHeader tables;
};

// The header's payload size, or throws; `bytes` holds at least the header.
std::uint64_t payload_size(std::span<const std::uint8_t> bytes, const Reader& header) {
  if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0) {
    header.fail("not a viewpose view database (no VPDB header)");
  }
  std::uint32_t version, bom;
  std::uint64_t size;
  std::memcpy(&version, bytes.data() + 8, 4);
  std::memcpy(&bom, bytes.data() + 12, 4);
  std::memcpy(&size, bytes.data() + 16, 8);
  if (bom != kByteOrderMark) header.fail("written on a machine of the other byte order; rebuild it here with `viewpose db build`");
  if (version != ViewDatabase::kFormatVersion) {
    header.fail(fmt::format("database format version {}, this viewpose reads version {}; rebuild it with `viewpose db build`",
                            version, ViewDatabase::kFormatVersion));
  }
  return size;
}

FileParts file_parts(std::span<const std::uint8_t> bytes, std::uint64_t file_size, const Reader& header) {
  const std::uint64_t size = payload_size(bytes, header);
  const std::uint64_t after_header = file_size - kHeaderBytes;
  if (size > after_header || after_header - size < kTablesHeaderBytes) {
    header.fail(fmt::format("header says {} bytes of data but the file holds {} (truncated or padded)", size, after_header));
  }
  // (Less than that read: the file was replaced between two reads of it.)
  if (bytes.size() < kHeaderBytes + size + kTablesHeaderBytes) header.fail("the file changed while it was read");
  FileParts parts;
  parts.tables = tables_header(bytes.subspan(static_cast<std::size_t>(kHeaderBytes + size)));
  if (parts.tables.size != after_header - size - kTablesHeaderBytes) {
    header.fail(fmt::format("the pair tables' header says {} bytes but the file holds {} after the views (truncated or padded)",
                            parts.tables.size, after_header - size - kTablesHeaderBytes));
  }
  std::uint32_t crc;
  std::memcpy(&crc, bytes.data() + 24, 4);
  parts.payload = bytes.subspan(kHeaderBytes, static_cast<std::size_t>(size));
  if (payload_crc(parts.payload) != crc) header.fail("checksum mismatch: the file is corrupted");
  return parts;
}

ViewDatabase read_payload(std::span<const std::uint8_t> payload, std::string_view name);
// The pair tables (`tables` after their header), one per object of `objects` in order (null where
// none is stored; all null when the file stores none); each checked to be made for its object's size.
std::vector<std::shared_ptr<const PpfTable>> read_pair_tables(std::span<const std::uint8_t> tables, std::uint32_t crc,
                                                              std::span<const DatabaseObject> objects, std::string_view name);

}  // namespace

ViewDatabase ViewDatabase::deserialize(std::span<const std::uint8_t> bytes, std::string_view name, DatabaseLoadOptions options) {
  const Reader header(bytes, name);
  const FileParts parts = file_parts(bytes, bytes.size(), header);
  ViewDatabase db = read_payload(parts.payload, name);
  if (options.pair_tables) {
    std::vector<std::shared_ptr<const PpfTable>> tables =
        read_pair_tables(bytes.subspan(bytes.size() - static_cast<std::size_t>(parts.tables.size)), parts.tables.crc, db.objects, name);
    for (std::size_t i = 0; i < db.objects.size(); ++i) db.objects[i].pair_table = std::move(tables[i]);
  }
  return db;
}

ViewDatabase ViewDatabase::load(const std::filesystem::path& path, DatabaseLoadOptions options) {
  if (options.pair_tables) return deserialize(read_file_bytes(path, kMaxFileBytes), path.string(), options);
  // The header, then the payload and the tables' header: the tables are neither read nor unpacked.
  const std::string name = path.string();
  const Reader header({}, name);
  std::uint64_t file_size = 0;
  std::vector<std::uint8_t> bytes = read_file_prefix(path, kHeaderBytes, kMaxFileBytes, file_size);
  const std::uint64_t size = payload_size(bytes, header);
  if (size <= file_size - kHeaderBytes) {
    const std::uint64_t first_size = file_size;
    bytes = read_file_prefix(path, static_cast<std::size_t>(std::min(file_size, kHeaderBytes + size + kTablesHeaderBytes)), kMaxFileBytes,
                             file_size);
    // A file replaced between the two reads (a `db build` renaming over it) is not mixed with the first.
    if (file_size != first_size || payload_size(bytes, header) != size) header.fail("the file changed while it was read");
  }
  const FileParts parts = file_parts(bytes, file_size, header);
  ViewDatabase db = read_payload(parts.payload, name);
  if (parts.tables.size > 0) {
    PairTablesOnDisk& on_disk = db.pair_tables_on_disk.emplace();
    // Read later, when the working directory may have changed.
    std::error_code ec;
    on_disk.path = std::filesystem::absolute(path, ec);
    if (ec) on_disk.path = path;
    on_disk.file_size = file_size;
    std::copy_n(bytes.begin(), kHeaderBytes, on_disk.header.begin());
    on_disk.offset = kHeaderBytes + parts.payload.size();
  }
  return db;
}

std::vector<std::shared_ptr<const PpfTable>> read_stored_pair_tables(const ViewDatabase& db) {
  if (!db.pair_tables_on_disk) return {};
  const PairTablesOnDisk& on_disk = *db.pair_tables_on_disk;
  const std::string name = on_disk.path.string();
  const Reader header({}, name);
  std::uint64_t file_size = 0;
  const std::vector<std::uint8_t> first = read_file_prefix(on_disk.path, kHeaderBytes, ViewDatabase::kMaxFileBytes, file_size);
  if (file_size != on_disk.file_size || first.size() != kHeaderBytes || !std::equal(first.begin(), first.end(), on_disk.header.begin())) {
    header.fail("the file changed since it was loaded; load it again");
  }
  std::vector<std::uint8_t> tail = read_file_range(on_disk.path, on_disk.offset, std::numeric_limits<std::size_t>::max(),
                                                   ViewDatabase::kMaxFileBytes, file_size);
  if (file_size != on_disk.file_size || tail.size() < kTablesHeaderBytes) header.fail("the file changed since it was loaded; load it again");
  const TablesHeader tables = tables_header(tail);
  if (tables.size != tail.size() - kTablesHeaderBytes) header.fail("the file changed since it was loaded; load it again");
  return read_pair_tables(std::span<const std::uint8_t>(tail).subspan(kTablesHeaderBytes), tables.crc, db.objects, name);
}

namespace {

ViewDatabase read_payload(std::span<const std::uint8_t> payload, std::string_view name) {
  Reader r(payload, name);
  ViewDatabase db;
  db.params = params_from_json(r.get_string(), r);
  const auto n_objects = r.get<std::uint32_t>();
  r.need_records(n_objects, 16);
  for (std::uint32_t i = 0; i < n_objects; ++i) {
    DatabaseObject o;
    o.id = r.get<std::int32_t>();
    o.name = r.get_string();
    o.diameter_m = r.get<double>();
    if (!(std::isfinite(o.diameter_m) && o.diameter_m > 0 && o.diameter_m < 1e3)) r.fail("an object's diameter is out of range");
    o.mesh = r.get_mesh();
    o.model_points = r.get_points();
    o.model_normals = r.get_points();
    if (o.model_normals.size() != o.model_points.size()) r.fail("an object's model normals do not match its points");
    const auto n_discrete = r.get<std::uint32_t>();
    r.need_records(n_discrete, 96);
    for (std::uint32_t k = 0; k < n_discrete; ++k) {
      Transform S = Transform::Identity();
      for (int row = 0; row < 3; ++row)
        for (int c = 0; c < 4; ++c) S(row, c) = r.get<double>();
      if (!S.matrix().allFinite() || (S.linear().transpose() * S.linear() - Eigen::Matrix3d::Identity()).norm() > 1e-6) {
        r.fail("an object's symmetry is not a rigid motion");
      }
      o.symmetries.discrete.push_back(S);
    }
    const auto n_continuous = r.get<std::uint32_t>();
    r.need_records(n_continuous, 48);
    for (std::uint32_t k = 0; k < n_continuous; ++k) {
      ContinuousSymmetry c;
      for (int axis = 0; axis < 3; ++axis) {
        c.axis[axis] = r.get<double>();
        c.offset_m[axis] = r.get<double>();
      }
      if (!c.axis.allFinite() || !c.offset_m.allFinite() || std::abs(c.axis.norm() - 1.0) > 1e-6) {
        r.fail("an object's symmetry axis is not a unit vector");
      }
      o.symmetries.continuous.push_back(c);
    }
    o.drawn_mesh = r.get_mesh();
    o.nearest_cells = r.get_cells();
    // As NearestGrid would refuse them, but here, so that a damaged file is refused when it is read.
    if (!o.nearest_cells.empty() && !NearestGrid::fits(o.model_points, db.params.grid_cell_m, db.params.grid_margin_m, o.nearest_cells)) {
      r.fail("an object's nearest-point grid does not fit its model points");
    }
    db.objects.push_back(std::move(o));
  }
  const auto n_views = r.get<std::uint32_t>();
  r.need_records(n_views, 4 + 96 + 4 * (308 + 90 + 3) + 4 + 4);
  db.views.resize(n_views);
  for (auto& v : db.views) {
    v.object = r.get<std::uint32_t>();
    if (v.object >= db.objects.size()) r.fail("a view names an object that does not exist");
    for (int row = 0; row < 3; ++row)
      for (int c = 0; c < 4; ++c) v.T_view_object(row, c) = r.get<double>();
    if (!v.T_view_object.matrix().allFinite() ||
        (v.T_view_object.linear().transpose() * v.T_view_object.linear() - Eigen::Matrix3d::Identity()).norm() > 1e-6) {
      r.fail("a view's pose is not a rigid motion");
    }
    r.get_floats(v.vfh.data(), v.vfh.size());
    r.get_floats(v.crh.data(), v.crh.size());
    r.get_floats(v.centroid.data(), 3);
    const auto finite = [](const auto& values) {
      return std::all_of(values.begin(), values.end(), [](float x) { return std::isfinite(x); });
    };
    if (!finite(v.vfh) || !finite(v.crh) || !v.centroid.allFinite()) r.fail("a view's descriptor is not finite");
    v.described_points = r.get<std::uint32_t>();
    v.icp_points = r.get_points();
  }
  if (!r.at_end()) r.fail("unexpected data after the last view");
  return db;
}

std::vector<std::shared_ptr<const PpfTable>> read_pair_tables(std::span<const std::uint8_t> tables, std::uint32_t crc,
                                                              std::span<const DatabaseObject> objects, std::string_view name) {
  Reader r(tables, name);
  if (payload_crc(tables) != crc) r.fail("checksum mismatch in the pair tables: the file is corrupted");
  std::vector<std::shared_ptr<const PpfTable>> out(objects.size());
  if (tables.empty()) return out;  // none stored
  r.need_records(objects.size(), 1);
  for (std::size_t i = 0; i < objects.size(); ++i) {
    out[i] = r.get_pair_table();
    if (out[i] && out[i]->diameter_m != objects[i].diameter_m) r.fail("an object's pair table was made for another size");
  }
  if (!r.at_end()) r.fail("unexpected data after the last pair table");
  return out;
}

}  // namespace

void ViewDatabase::save(const std::filesystem::path& path) const { write_file_atomic(path, serialize()); }


int add_captured_view(ViewDatabase& db, const PointCloud& cloud, const std::string& name) {
  if (name.empty()) throw Error("add-view: the object needs a name");
  PointCloud points = voxel_downsample(cloud, db.params.voxel_m);
  if (points.size() < 50) throw Error(fmt::format("add-view: only {} points after the voxel grid; is the cloud the object?", points.size()));
  Description d = describe(std::move(points), db.params.describe);
  std::uint32_t index = 0;
  while (index < db.objects.size() && db.objects[index].name != name) ++index;
  if (index == db.objects.size()) {
    DatabaseObject o;
    o.name = name;
    for (const auto& existing : db.objects) o.id = std::max(o.id, existing.id);
    ++o.id;
    db.objects.push_back(std::move(o));
  } else if (!db.objects[index].mesh.triangles.empty()) {
    throw Error(fmt::format("add-view: object '{}' comes from a mesh; captured views are for scanned objects", name));
  }
  DatabaseObject& object = db.objects[index];
  ViewEntry v;
  v.object = index;
  v.T_view_object = Transform::Identity();  // the capture's frame is the object's
  v.vfh = d.vfh;
  v.crh = d.crh;
  v.centroid = d.centroid;
  v.icp_points = voxel_downsample(d.cloud, db.params.icp_voxel_m).points;
  v.described_points = static_cast<std::uint32_t>(d.cloud.points.size());
  db.views.push_back(std::move(v));
  // The model cloud grows with every view; the diameter follows it.
  PointCloud model;
  model.points = object.model_points;
  model.normals = object.model_normals;
  model.points.insert(model.points.end(), d.cloud.points.begin(), d.cloud.points.end());
  model.normals.insert(model.normals.end(), d.cloud.normals.begin(), d.cloud.normals.end());
  model.width = static_cast<int>(model.points.size());
  PointCloud grid = voxel_downsample(model, db.params.voxel_m);
  object.model_points = std::move(grid.points);
  object.model_normals = std::move(grid.normals);
  TriangleMesh hull;
  hull.vertices = object.model_points;
  object.diameter_m = mesh_diameter(hull);
  // Its grid made again for the grown model, within what the database's other grids leave.
  object.nearest_cells = std::vector<std::uint32_t>();
  object.pair_table.reset();
  const auto less = [](std::size_t most, std::size_t taken) { return most > taken ? most - taken : 0; };
  PreparedBytesLeft left{less(db.params.max_grid_bytes, stored_grid_bytes(db)),
                         less(db.params.max_pair_table_bytes, stored_pair_table_bytes(db))};
  prepare_object(object, db.params, left);
  return object.id;
}

PointCloud view_points(const DepthImage& depth, const CameraIntrinsics& K, float voxel_m) {
  return voxel_downsample(depth_to_cloud(depth, K), voxel_m);
}

ViewEntry describe_view(const DepthImage& depth, const Transform& T_view_object, std::uint32_t object,
                        const DatabaseParams& params, PointCloud* described) {
  Description d = describe(view_points(depth, params.camera, params.voxel_m), params.describe);
  ViewEntry v;
  v.object = object;
  v.T_view_object = T_view_object;
  v.vfh = d.vfh;
  v.crh = d.crh;
  v.centroid = d.centroid;
  v.icp_points = voxel_downsample(d.cloud, params.icp_voxel_m).points;
  v.described_points = static_cast<std::uint32_t>(d.cloud.points.size());
  if (described) *described = std::move(d.cloud);
  return v;
}

namespace {

// The view sphere's camera must see the whole object (else every view is a cut-out, or the camera
// sits inside it), and the object must cover a few voxels. Both fail at once for a mesh read in the
// wrong unit: a 17 cm bottle in millimetres is 170 m across as metres.
void check_viewable(const std::string& name, const BoundingBox& box, const DatabaseParams& params) {
  const CameraIntrinsics& K = params.camera;
  const double half_px = std::min({K.cx, K.width - K.cx, K.cy, K.height - K.cy});
  const double seen_m = 2.0 * params.distance_m * half_px / std::max(K.fx, K.fy);
  const double d = box.diagonal();
  if (d > seen_m) {
    throw Error(fmt::format(
        "db build: '{}' is {:.4g} m across, more than the view camera {:.2f} m away sees whole ({:.2f} m): a mesh in "
        "millimetres or centimetres needs --unit mm or --unit cm; a large object, a larger --distance",
        name, d, params.distance_m, seen_m));
  }
  if (d < 4.0 * params.voxel_m) {
    throw Error(fmt::format(
        "db build: '{}' is {:.3g} mm across, less than four {:.0f} mm voxels: a mesh in metres read as millimetres needs "
        "--unit m",
        name, d * 1000.0, params.voxel_m * 1000.0));
  }
}

}  // namespace

void prepare_object(DatabaseObject& object, const DatabaseParams& params, PreparedBytesLeft& left) {
  object.drawn_mesh = object.mesh.triangles.empty() ? TriangleMesh{} : simplify_for_drawing(object.mesh, params.drawn_mesh_error_m);
  object.nearest_cells = std::vector<std::uint32_t>();
  const std::size_t cells = NearestGrid::cell_count(object.model_points, params.grid_cell_m, params.grid_margin_m);
  if (cells > 0 && cells <= left.grids / sizeof(std::uint32_t)) {  // (a scan of a whole room: too many)
    left.grids -= cells * sizeof(std::uint32_t);
    object.nearest_cells = filled_nearest_cells(object.model_points, params.grid_cell_m, params.grid_margin_m);
  }
  object.pair_table.reset();
  if (left.pair_tables == 0) return;
  try {
    auto table = std::make_shared<const PpfTable>(make_ppf_table(object.model_points, object.model_normals, object.diameter_m, params.ppf));
    if (table->bytes() > left.pair_tables) return;
    left.pair_tables -= table->bytes();
    object.pair_table = std::move(table);
  } catch (const Error&) {
    // A model of fewer than two oriented points gives no votes; the recognizer finds that again.
  }
}

std::size_t stored_pair_table_bytes(const ViewDatabase& db) {
  std::size_t bytes = 0;
  for (const DatabaseObject& o : db.objects) bytes += o.pair_table ? o.pair_table->bytes() : 0;
  return bytes;
}

std::size_t stored_grid_bytes(const ViewDatabase& db) {
  std::size_t bytes = 0;
  for (const DatabaseObject& o : db.objects) bytes += o.nearest_cells.size() * sizeof(std::uint32_t);
  return bytes;
}

ViewDatabase build_view_database(std::span<const ObjectModel> objects, const DatabaseParams& params,
                                 const std::function<void(std::size_t, std::size_t)>& progress) {
  params.camera.validate();
  // What the file will hold must be readable back: lengths in (0, 1] m, as the reader asks.
  for (const auto& [name, value] : {std::pair{"voxel_m", params.voxel_m}, {"icp_voxel_m", params.icp_voxel_m},
                                    {"drawn_mesh_error_m", params.drawn_mesh_error_m}, {"grid_cell_m", params.grid_cell_m},
                                    {"grid_margin_m", params.grid_margin_m}}) {
    if (!(value > 0 && value <= 1.0f)) throw Error(fmt::format("db build: {} is {}; it must be in (0, 1] m", name, value));
  }
  ViewDatabase db;
  db.params = params;
  check_ppf_options(params.ppf);
  PreparedBytesLeft left{params.max_grid_bytes, params.max_pair_table_bytes};
  for (std::size_t o = 0; o < objects.size(); ++o) {
    const TriangleMesh& mesh = objects[o].mesh;
    if (mesh.triangles.empty()) throw Error(fmt::format("db build: object '{}' has no triangles", objects[o].name));
    DatabaseObject object;
    object.id = objects[o].id;
    object.name = objects[o].name;
    object.diameter_m = mesh_diameter(mesh);
    object.mesh.vertices = mesh.vertices;
    object.mesh.triangles = mesh.triangles;
    object.symmetries = find_symmetries(mesh);
    db.objects.push_back(std::move(object));
    const BoundingBox box = bounding_box(mesh);
    check_viewable(objects[o].name, box, params);
    const Eigen::Vector3d centre = (0.5f * (box.min + box.max)).cast<double>();
    const std::vector<Transform> poses = view_sphere_poses(centre, params.distance_m, params.subdivisions);
    RenderOptions render_options;
    render_options.closed_winding = closed_mesh_winding(mesh);  // the same pictures, sooner
    const std::vector<RenderedFrame> frames = render_views(mesh, poses, params.camera, render_options);
    std::vector<ViewEntry> entries(poses.size());
    std::vector<PointCloud> described(poses.size());
    FirstException failed;
#pragma omp parallel for schedule(dynamic)
    for (std::size_t i = 0; i < poses.size(); ++i) {
      failed.run(static_cast<std::ptrdiff_t>(i), [&] {
        entries[i] = describe_view(frames[i].depth, poses[i], static_cast<std::uint32_t>(o), params, &described[i]);
      });
    }
    failed.rethrow();
    // The model cloud: every view's points carried into the object frame, on one voxel grid. It is
    // the surface a sensor can see, with outward normals, and ICP aligns scene points to it.
    PointCloud model;
    for (std::size_t v = 0; v < entries.size(); ++v) {
      const Transform T_object_view = entries[v].T_view_object.inverse();
      const Eigen::Matrix3f R = T_object_view.linear().cast<float>();
      const Eigen::Vector3f t = T_object_view.translation().cast<float>();
      for (std::size_t i = 0; i < described[v].points.size(); ++i) {
        model.points.push_back(R * described[v].points[i] + t);
        model.normals.push_back(R * described[v].normals[i]);
      }
    }
    model.width = static_cast<int>(model.points.size());
    PointCloud model_grid = voxel_downsample(model, params.voxel_m);
    db.objects.back().model_points = std::move(model_grid.points);
    db.objects.back().model_normals = std::move(model_grid.normals);
    prepare_object(db.objects.back(), params, left);
    std::size_t usable = 0;
    for (auto& e : entries) {
      if (e.described_points < 3) continue;  // a view that sees nothing is no use
      db.views.push_back(std::move(e));
      ++usable;
    }
    // An object that no view sees would never be found: a database without it is not what was asked for.
    if (usable == 0) {
      throw Error(fmt::format("db build: '{}': no view sees it ({:.3g} m across, {:.3g} m voxels); is its unit right?",
                              objects[o].name, box.diagonal(), params.voxel_m));
    }
    if (progress) progress(o + 1, objects.size());
  }
  return db;
}

}  // namespace viewpose
