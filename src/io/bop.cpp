#include "viewpose/io/bop.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <tuple>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "viewpose/core/error.hpp"
#include "viewpose/io/depth_png.hpp"
#include "viewpose/core/file.hpp"

namespace viewpose {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr std::size_t kMaxJsonBytes = std::size_t{1} << 30;

json parse_json(std::string_view text, std::string_view name) {
  try {
    return json::parse(text);
  } catch (const json::exception& e) {
    throw Error(fmt::format("{}: invalid JSON: {}", name, e.what()));
  }
}

// Context for messages: "scene_gt.json: image 3, object 0: ...".
struct Where {
  std::string_view name;
  std::string path;
  template <typename... Args>
  [[noreturn]] void fail(fmt::format_string<Args...> f, Args&&... args) const {
    throw Error(fmt::format("{}: {}{}", name, path.empty() ? "" : path + ": ", fmt::format(f, std::forward<Args>(args)...)));
  }
};

const json& member(const json& obj, const char* key, const Where& w) {
  if (!obj.is_object()) w.fail("expected an object");
  const auto it = obj.find(key);
  if (it == obj.end()) w.fail("'{}' is missing", key);
  return *it;
}

double number(const json& v, const char* key, const Where& w) {
  if (!v.is_number()) w.fail("'{}' must be a number", key);
  const double d = v.get<double>();
  if (!std::isfinite(d)) w.fail("'{}' is not finite", key);
  return d;
}

double number_member(const json& obj, const char* key, const Where& w) { return number(member(obj, key, w), key, w); }

int int_member(const json& obj, const char* key, const Where& w) {
  const double d = number_member(obj, key, w);
  if (d != std::floor(d) || std::abs(d) > 2e9) w.fail("'{}' must be a whole number", key);
  return static_cast<int>(d);
}

std::vector<double> numbers(const json& obj, const char* key, std::size_t count, const Where& w) {
  const json& v = member(obj, key, w);
  if (!v.is_array() || v.size() != count) w.fail("'{}' must be {} numbers", key, count);
  std::vector<double> out;
  for (const json& x : v) out.push_back(number(x, key, w));
  return out;
}

// Rotations as files hold them: rounded. Each is taken as its nearest rotation; those off
// orthonormal by more than a file's last digit are counted, and said once per file.
struct RotationTally {
  int adjusted = 0;
  double worst = 0;
  std::string worst_where;

  Eigen::Matrix3d take(const std::vector<double>& r, const char* key, const Where& w) {
    Eigen::Matrix3d M;
    for (int i = 0; i < 9; ++i) M(i / 3, i % 3) = r[static_cast<std::size_t>(i)];
    const NearRotation n = nearest_rotation(M);
    if (n.kind == NearRotation::Kind::Reflection) {
      w.fail("'{}' is a reflection (determinant {:.3g}), not a rotation", key, M.determinant());
    }
    if (n.kind == NearRotation::Kind::NotRigid) {
      const Eigen::Vector3d& s = n.singular_values;
      w.fail("'{}' is not a rotation matrix: it is scaled or sheared (singular values {:.4g}, {:.4g}, {:.4g}; "
             "rounding explains at most {:g} from 1)", key, s[0], s[1], s[2], kMaxRotationRounding);
    }
    if (n.deviation > kSilentRotationRounding) {
      ++adjusted;
      if (n.deviation > worst) {
        worst = n.deviation;
        worst_where = w.path;
      }
    }
    return n.R;
  }

  void report(std::string_view name, std::vector<std::string>* notes) const {
    if (!notes || adjusted == 0) return;
    notes->push_back(fmt::format("{}: {} rotation{} off orthonormal by up to {:.1e} ({} the most), taken as the nearest "
                                 "rotation{}", name, adjusted, adjusted == 1 ? " is" : "s are", worst, worst_where,
                                 adjusted == 1 ? "" : "s"));
  }
};

int parse_id(const std::string& key, const Where& w) {
  int id = 0;
  const auto [end, ec] = std::from_chars(key.data(), key.data() + key.size(), id);
  if (ec != std::errc() || end != key.data() + key.size() || id < 0) w.fail("key '{}' is not an id", key);
  return id;
}

// Visits a json object keyed by ids: {"1": ..., "2": ...}.
template <typename F>
void for_each_id(const json& root, std::string_view name, const char* what, F&& visit) {
  if (!root.is_object()) throw Error(fmt::format("{}: expected an object keyed by {} id", name, what));
  for (const auto& [key, value] : root.items()) {
    const Where w{name, fmt::format("{} {}", what, key)};
    visit(parse_id(key, w), value, w);
  }
}

CameraIntrinsics intrinsics_from_K(const std::vector<double>& K, const Where& w) {
  CameraIntrinsics c{K[0], K[4], K[2], K[5], 0, 0};
  if (!(c.fx > 0 && c.fy > 0)) w.fail("cam_K has non-positive focal lengths");
  return c;
}

double depth_scale(const json& obj, const Where& w) {
  if (!obj.contains("depth_scale")) return 1.0;
  const double s = number_member(obj, "depth_scale", w);
  if (!(s > 0 && s < 1000)) w.fail("depth_scale {} is out of range", s);
  return s;
}

json matrix_json(const Eigen::Matrix3d& R) {
  json a = json::array();
  for (int i = 0; i < 9; ++i) a.push_back(R(i / 3, i % 3));
  return a;
}

json vector_json(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

}  // namespace

BopCamera parse_bop_camera(std::string_view json_text, std::string_view name) {
  const json root = parse_json(json_text, name);
  const Where w{name, ""};
  BopCamera cam;
  cam.K = {number_member(root, "fx", w), number_member(root, "fy", w), number_member(root, "cx", w),
           number_member(root, "cy", w), int_member(root, "width", w), int_member(root, "height", w)};
  try {
    cam.K.validate();
  } catch (const Error& e) {
    w.fail("{}", e.what());
  }
  cam.depth_scale_mm = depth_scale(root, w);
  return cam;
}

SceneCameras parse_scene_camera(std::string_view json_text, std::string_view name) {
  SceneCameras out;
  for_each_id(parse_json(json_text, name), name, "image", [&](int id, const json& v, const Where& w) {
    out[id] = BopCamera{intrinsics_from_K(numbers(v, "cam_K", 9, w), w), depth_scale(v, w)};
  });
  return out;
}

SceneGroundTruth parse_scene_gt(std::string_view json_text, std::string_view name, std::vector<std::string>* notes) {
  SceneGroundTruth out;
  RotationTally rotations;
  for_each_id(parse_json(json_text, name), name, "image", [&](int id, const json& list, const Where& w) {
    if (!list.is_array()) w.fail("expected a list of objects");
    auto& poses = out[id];
    for (std::size_t i = 0; i < list.size(); ++i) {
      const Where wi{name, fmt::format("{}, object {}", w.path, i)};
      const Eigen::Matrix3d R = rotations.take(numbers(list[i], "cam_R_m2c", 9, wi), "cam_R_m2c", wi);
      const auto t = numbers(list[i], "cam_t_m2c", 3, wi);
      poses.push_back({int_member(list[i], "obj_id", wi),
                       make_transform(R, Eigen::Vector3d(t[0], t[1], t[2]) / 1000.0)});
    }
  });
  rotations.report(name, notes);
  return out;
}

SceneGroundTruthInfo parse_scene_gt_info(std::string_view json_text, std::string_view name) {
  SceneGroundTruthInfo out;
  for_each_id(parse_json(json_text, name), name, "image", [&](int id, const json& list, const Where& w) {
    if (!list.is_array()) w.fail("expected a list of objects");
    auto& infos = out[id];
    for (std::size_t i = 0; i < list.size(); ++i) {
      const Where wi{name, fmt::format("{}, object {}", w.path, i)};
      GroundTruthInfo info;
      info.visib_fract = number_member(list[i], "visib_fract", wi);
      if (info.visib_fract < 0 || info.visib_fract > 1) wi.fail("visib_fract {} is not in 0..1", info.visib_fract);
      if (list[i].contains("px_count_all")) info.px_count_all = int_member(list[i], "px_count_all", wi);
      if (list[i].contains("px_count_valid")) info.px_count_valid = int_member(list[i], "px_count_valid", wi);
      if (list[i].contains("px_count_visib")) info.px_count_visib = int_member(list[i], "px_count_visib", wi);
      for (auto [key, box] : {std::pair{"bbox_obj", &info.bbox_obj}, std::pair{"bbox_visib", &info.bbox_visib}}) {
        if (!list[i].contains(key)) continue;
        const auto b = numbers(list[i], key, 4, wi);
        for (int k = 0; k < 4; ++k) (*box)[static_cast<std::size_t>(k)] = static_cast<int>(b[static_cast<std::size_t>(k)]);
      }
      infos.push_back(info);
    }
  });
  return out;
}

ModelsInfo parse_models_info(std::string_view json_text, std::string_view name, std::vector<std::string>* notes) {
  ModelsInfo out;
  RotationTally rotations;
  for_each_id(parse_json(json_text, name), name, "object", [&](int id, const json& v, const Where& w) {
    ModelInfo m;
    m.diameter_m = number_member(v, "diameter", w) / 1000.0;
    if (!(m.diameter_m > 0)) w.fail("diameter must be positive");
    m.min_m = Eigen::Vector3d(number_member(v, "min_x", w), number_member(v, "min_y", w), number_member(v, "min_z", w)) / 1000.0;
    m.size_m = Eigen::Vector3d(number_member(v, "size_x", w), number_member(v, "size_y", w), number_member(v, "size_z", w)) / 1000.0;
    if (v.contains("symmetries_discrete")) {
      const json& list = v["symmetries_discrete"];
      if (!list.is_array()) w.fail("symmetries_discrete must be a list");
      for (const json& s : list) {
        if (!s.is_array() || s.size() != 16) w.fail("each discrete symmetry must be 16 numbers");
        std::vector<double> a;
        for (const json& x : s) a.push_back(number(x, "symmetries_discrete", w));
        const Eigen::Matrix3d R = rotations.take({a[0], a[1], a[2], a[4], a[5], a[6], a[8], a[9], a[10]}, "symmetries_discrete", w);
        m.symmetries_discrete.push_back(make_transform(R, Eigen::Vector3d(a[3], a[7], a[11]) / 1000.0));
      }
    }
    if (v.contains("symmetries_continuous")) {
      const json& list = v["symmetries_continuous"];
      if (!list.is_array()) w.fail("symmetries_continuous must be a list");
      for (const json& s : list) {
        const auto axis = numbers(s, "axis", 3, w);
        const auto offset = numbers(s, "offset", 3, w);
        const Eigen::Vector3d a(axis[0], axis[1], axis[2]);
        if (!(a.norm() > 1e-9)) w.fail("a continuous symmetry has a zero axis");
        m.symmetries_continuous.push_back({a.normalized(), Eigen::Vector3d(offset[0], offset[1], offset[2]) / 1000.0});
      }
    }
    out[id] = std::move(m);
  });
  rotations.report(name, notes);
  return out;
}

std::vector<BopTarget> parse_bop_targets(std::string_view json_text, std::string_view name) {
  const json root = parse_json(json_text, name);
  if (!root.is_array()) throw Error(fmt::format("{}: expected a list of targets (scene_id, im_id, obj_id, inst_count)", name));
  std::vector<BopTarget> out;
  out.reserve(root.size());
  for (std::size_t i = 0; i < root.size(); ++i) {
    const Where w{name, fmt::format("target {}", i)};
    BopTarget t{int_member(root[i], "scene_id", w), int_member(root[i], "im_id", w), int_member(root[i], "obj_id", w),
                int_member(root[i], "inst_count", w)};
    if (t.scene_id < 0 || t.im_id < 0 || t.obj_id < 0) w.fail("ids must not be negative");
    if (t.inst_count < 1) w.fail("inst_count {} is below 1", t.inst_count);
    out.push_back(t);
  }
  const auto key = [](const BopTarget& t) { return std::tuple(t.scene_id, t.im_id, t.obj_id); };
  std::stable_sort(out.begin(), out.end(), [&](const BopTarget& a, const BopTarget& b) { return key(a) < key(b); });
  for (std::size_t i = 1; i < out.size(); ++i) {
    if (key(out[i]) == key(out[i - 1])) {
      throw Error(fmt::format("{}: object {} is listed twice for scene {}, image {}", name, out[i].obj_id, out[i].scene_id,
                              out[i].im_id));
    }
  }
  return out;
}

std::string format_bop_camera(const BopCamera& c) {
  return json{{"fx", c.K.fx}, {"fy", c.K.fy}, {"cx", c.K.cx}, {"cy", c.K.cy}, {"width", c.K.width},
              {"height", c.K.height}, {"depth_scale", c.depth_scale_mm}}.dump(1) + "\n";
}

std::string format_scene_camera(const SceneCameras& cameras) {
  json root = json::object();
  for (const auto& [id, c] : cameras) {
    root[std::to_string(id)] = {{"cam_K", {c.K.fx, 0.0, c.K.cx, 0.0, c.K.fy, c.K.cy, 0.0, 0.0, 1.0}},
                                {"depth_scale", c.depth_scale_mm}};
  }
  return root.dump(1) + "\n";
}

std::string format_scene_gt(const SceneGroundTruth& gt) {
  json root = json::object();
  for (const auto& [id, poses] : gt) {
    json list = json::array();
    for (const auto& p : poses) {
      list.push_back({{"cam_R_m2c", matrix_json(p.T_camera_object.linear())},
                      {"cam_t_m2c", vector_json(p.T_camera_object.translation() * 1000.0)},
                      {"obj_id", p.obj_id}});
    }
    root[std::to_string(id)] = std::move(list);
  }
  return root.dump(1) + "\n";
}

std::string format_scene_gt_info(const SceneGroundTruthInfo& info) {
  json root = json::object();
  for (const auto& [id, infos] : info) {
    json list = json::array();
    for (const auto& i : infos) {
      list.push_back({{"bbox_obj", i.bbox_obj}, {"bbox_visib", i.bbox_visib}, {"px_count_all", i.px_count_all},
                      {"px_count_valid", i.px_count_valid}, {"px_count_visib", i.px_count_visib},
                      {"visib_fract", i.visib_fract}});
    }
    root[std::to_string(id)] = std::move(list);
  }
  return root.dump(1) + "\n";
}

std::string format_models_info(const ModelsInfo& models) {
  json root = json::object();
  for (const auto& [id, m] : models) {
    json o = {{"diameter", m.diameter_m * 1000.0},
              {"min_x", m.min_m.x() * 1000.0}, {"min_y", m.min_m.y() * 1000.0}, {"min_z", m.min_m.z() * 1000.0},
              {"size_x", m.size_m.x() * 1000.0}, {"size_y", m.size_m.y() * 1000.0}, {"size_z", m.size_m.z() * 1000.0}};
    if (!m.symmetries_discrete.empty()) {
      json list = json::array();
      for (const Transform& S : m.symmetries_discrete) {
        json a = json::array();
        for (int r = 0; r < 4; ++r) {
          for (int c = 0; c < 4; ++c) a.push_back(c == 3 && r < 3 ? S(r, c) * 1000.0 : S(r, c));
        }
        list.push_back(std::move(a));
      }
      o["symmetries_discrete"] = std::move(list);
    }
    if (!m.symmetries_continuous.empty()) {
      json list = json::array();
      for (const auto& s : m.symmetries_continuous) {
        list.push_back({{"axis", vector_json(s.axis)}, {"offset", vector_json(s.offset_m * 1000.0)}});
      }
      o["symmetries_continuous"] = std::move(list);
    }
    root[std::to_string(id)] = std::move(o);
  }
  return root.dump(1) + "\n";
}

namespace {

std::string read_text(const fs::path& path) {
  const auto bytes = read_file_bytes(path, kMaxJsonBytes);
  return std::string(bytes.begin(), bytes.end());
}

bool all_digits(const std::string& s) {
  return !s.empty() && s.size() <= 9 && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

}  // namespace

std::vector<BopTarget> read_bop_targets(const fs::path& path) { return parse_bop_targets(read_text(path), path.string()); }

namespace {

bool has_scene_folder(const fs::path& dir) {
  std::error_code ec;
  for (const auto& scene : fs::directory_iterator(dir, ec)) {
    if (scene.is_directory() && all_digits(scene.path().filename().string()) && fs::exists(scene.path() / "scene_camera.json", ec)) {
      return true;
    }
  }
  return false;
}

bool has_meshes(const fs::path& dir) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string stem = entry.path().stem().string();
    if (entry.path().extension() == ".ply" && stem.starts_with("obj_") && all_digits(stem.substr(4))) return true;
  }
  return false;
}

}  // namespace

BopLayout scan_bop_layout(const fs::path& root) {
  std::error_code ec;
  if (!fs::is_directory(root, ec)) throw Error(fmt::format("{}: not a directory", root.string()));
  BopLayout layout;
  layout.root = root;
  for (const auto& entry : fs::directory_iterator(root, ec)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_directory()) {
      if (name.starts_with("models") && has_meshes(entry.path())) {
        layout.model_folders.push_back(name);
      } else if (has_scene_folder(entry.path())) {
        const std::size_t cut = name.find('_');
        layout.splits.push_back({name, name.substr(0, cut), cut == std::string::npos ? "" : name.substr(cut + 1)});
      }
    } else if (entry.path().extension() == ".json") {
      if (name == "camera.json" || name.starts_with("camera_")) layout.camera_files.push_back(name);
      if (name.starts_with("test_targets") || name.starts_with("val_targets")) layout.target_files.push_back(name);
    }
  }
  std::sort(layout.splits.begin(), layout.splits.end(), [](const auto& a, const auto& b) { return a.folder < b.folder; });
  std::sort(layout.model_folders.begin(), layout.model_folders.end());
  std::sort(layout.camera_files.begin(), layout.camera_files.end());
  std::sort(layout.target_files.begin(), layout.target_files.end());
  return layout;
}

BopSplitFolder resolve_bop_split(const BopLayout& layout, std::string_view name) {
  std::vector<std::string> all;
  for (const BopSplitFolder& s : layout.splits) {
    if (s.folder == name) return s;
    all.push_back(s.folder);
  }
  std::vector<const BopSplitFolder*> typed;
  for (const BopSplitFolder& s : layout.splits) {
    if (s.split == name) typed.push_back(&s);
  }
  if (typed.size() == 1) return *typed.front();
  const fs::path wanted = layout.root / std::string(name);
  if (typed.size() > 1) {
    std::vector<std::string> names;
    for (const auto* s : typed) names.push_back(s->folder);
    throw Error(fmt::format("{}: the dataset has {} '{}' splits ({}): name one with --split", wanted.string(), typed.size(),
                            name, fmt::join(names, ", ")));
  }
  throw Error(fmt::format("{}: no split '{}' in the dataset ({})", wanted.string(), name,
                          all.empty() ? std::string("it has no split folder with scenes in it")
                                      : fmt::format("its splits: {}", fmt::join(all, ", "))));
}

std::string resolve_models_folder(const BopLayout& layout, std::string_view name) {
  const auto has = [&](std::string_view folder) {
    return std::find(layout.model_folders.begin(), layout.model_folders.end(), folder) != layout.model_folders.end();
  };
  if (name != "models" || has(name)) return std::string(name);  // asked for by name: reading it says what is missing
  for (const char* preferred : {"models_cad", "models_eval"}) {
    if (has(preferred)) return preferred;
  }
  if (!layout.model_folders.empty()) return layout.model_folders.front();
  std::error_code ec;
  return fs::is_directory(layout.root / "models", ec) ? std::string("models") : std::string();  // models_info.json alone
}

std::map<int, fs::path> find_bop_model_files(const fs::path& dir) {
  std::map<int, fs::path> files;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string stem = entry.path().stem().string();
    if (entry.path().extension() == ".ply" && stem.starts_with("obj_") && stem.size() > 4 && stem.size() <= 13 &&
        all_digits(stem.substr(4))) {
      files[std::stoi(stem.substr(4))] = entry.path();
    }
  }
  return files;
}

BopDataset open_bop_dataset(const fs::path& root, std::string_view split_name, const BopOpenOptions& options) {
  std::error_code ec;
  const BopLayout layout = scan_bop_layout(root);
  const BopSplitFolder split = resolve_bop_split(layout, split_name);
  const fs::path split_dir = root / split.folder;
  BopDataset ds;
  ds.root = root;
  ds.split = split.folder;
  // The image size: camera.json, else the camera file of the split's sensor (T-LESS, HB), else the
  // dataset's only camera file; without one it is taken from each depth image.
  std::optional<std::string> camera_file;
  for (const std::string& candidate : {std::string("camera.json"), fmt::format("camera_{}.json", split.type)}) {
    if (!camera_file && std::find(layout.camera_files.begin(), layout.camera_files.end(), candidate) != layout.camera_files.end()) {
      camera_file = candidate;
    }
  }
  if (!camera_file && layout.camera_files.size() == 1) camera_file = layout.camera_files.front();
  if (camera_file) ds.camera = parse_bop_camera(read_text(root / *camera_file), (root / *camera_file).string());
  ds.models_dir = resolve_models_folder(layout, options.models_dir);
  const bool has_eval_models =
      std::find(layout.model_folders.begin(), layout.model_folders.end(), "models_eval") != layout.model_folders.end();
  ds.eval_models_dir = has_eval_models ? "models_eval" : ds.models_dir;
  const fs::path models_dir = root / ds.models_dir;
  if (const fs::path p = models_dir / "models_info.json"; !ds.models_dir.empty() && fs::exists(p, ec)) {
    ds.models = parse_models_info(read_text(p), p.string(), &ds.notes);
  }
  if (!ds.models_dir.empty() && fs::is_directory(models_dir, ec)) ds.model_files = find_bop_model_files(models_dir);

  std::vector<std::pair<int, fs::path>> scenes;
  for (const auto& entry : fs::directory_iterator(split_dir)) {
    const std::string dir_name = entry.path().filename().string();
    if (entry.is_directory() && all_digits(dir_name)) scenes.emplace_back(std::stoi(dir_name), entry.path());
  }
  std::sort(scenes.begin(), scenes.end());
  if (scenes.empty()) throw Error(fmt::format("{}: no scene folders (000000, 000001, ...)", split_dir.string()));

  for (const auto& [scene_id, dir] : scenes) {
    const fs::path camera_path = dir / "scene_camera.json";
    const SceneCameras cameras = parse_scene_camera(read_text(camera_path), camera_path.string());
    SceneGroundTruth gt;
    SceneGroundTruthInfo gt_info;
    const fs::path gt_path = dir / "scene_gt.json", info_path = dir / "scene_gt_info.json";
    if (fs::exists(gt_path, ec)) gt = parse_scene_gt(read_text(gt_path), gt_path.string(), &ds.notes);
    if (fs::exists(info_path, ec)) gt_info = parse_scene_gt_info(read_text(info_path), info_path.string());
    for (const auto& [im_id, poses] : gt) {
      if (!cameras.count(im_id)) {
        throw Error(fmt::format("{}: image {} has ground truth but no camera in scene_camera.json", gt_path.string(), im_id));
      }
    }
    for (const auto& [im_id, infos] : gt_info) {
      const auto it = gt.find(im_id);
      if (it == gt.end() || it->second.size() != infos.size()) {
        throw Error(fmt::format("{}: image {} lists {} objects but scene_gt.json lists {}", info_path.string(), im_id,
                                infos.size(), it == gt.end() ? 0 : it->second.size()));
      }
    }
    for (const auto& [im_id, camera] : cameras) {
      BopImage image;
      image.scene_id = scene_id;
      image.im_id = im_id;
      image.camera = camera;
      if (ds.camera) {
        image.camera.K.width = ds.camera->K.width;
        image.camera.K.height = ds.camera->K.height;
      }
      const fs::path bop_name = dir / "depth" / fmt::format("{:06d}.png", im_id);
      const fs::path ycb_name = dir / fmt::format("{:06d}-depth.png", im_id);
      if (fs::exists(bop_name, ec)) image.depth_path = bop_name;
      else if (fs::exists(ycb_name, ec)) image.depth_path = ycb_name;
      else if (fs::exists(dir / "depth" / fmt::format("{:06d}.tif", im_id), ec)) {
        throw Error(fmt::format("{}: image {}'s depth is a TIFF (depth/{:06d}.tif, as ITODD's); viewpose reads 16-bit PNG "
                                "depth", dir.string(), im_id, im_id));
      } else {
        throw Error(fmt::format("{}: no depth image for image {} (looked for depth/{:06d}.png and {:06d}-depth.png)",
                                dir.string(), im_id, im_id, im_id));
      }
      if (auto it = gt.find(im_id); it != gt.end()) image.gt = it->second;
      if (auto it = gt_info.find(im_id); it != gt_info.end()) image.gt_info = it->second;
      ds.images.push_back(std::move(image));
    }
  }
  return ds;
}

BopFrame load_bop_frame(const BopImage& image) {
  BopFrame frame;
  frame.depth = read_depth_png(image.depth_path, image.camera.depth_scale_mm / 1000.0);
  frame.K = image.camera.K;
  if (frame.K.width == 0 && frame.K.height == 0) {
    frame.K.width = frame.depth.width;
    frame.K.height = frame.depth.height;
  } else if (frame.K.width != frame.depth.width || frame.K.height != frame.depth.height) {
    throw Error(fmt::format("{}: image is {}x{} but camera.json says {}x{}", image.depth_path.string(), frame.depth.width,
                            frame.depth.height, frame.K.width, frame.K.height));
  }
  return frame;
}

}  // namespace viewpose
