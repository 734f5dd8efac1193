#include "viewpose/io/inspect.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "viewpose/core/error.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/io/bop_results.hpp"
#include "viewpose/io/depth_png.hpp"
#include "viewpose/core/file.hpp"
#include "viewpose/io/mesh_loader.hpp"
#include "viewpose/io/pcd.hpp"
#include "viewpose/io/ply.hpp"

namespace viewpose {

namespace fs = std::filesystem;

namespace {

std::string lower_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

void describe_points(FileInfo& info, const std::vector<Eigen::Vector3f>& points) {
  info.bbox = bounding_box(points);
  info.unit_guess = guess_length_unit(info.bbox);
  if (info.points == 0) info.problems.push_back("empty: no points");
  else if (info.valid_points == 0) info.problems.push_back("no valid points (every point is NaN or infinite)");
}

FileInfo inspect_cloud(const PointCloud& cloud, std::string kind, std::vector<std::string> fields) {
  FileInfo info;
  info.kind = std::move(kind);
  info.points = cloud.size();
  info.valid_points = cloud.count_finite();
  info.width = cloud.width;
  info.height = cloud.height;
  info.fields = std::move(fields);
  describe_points(info, cloud.points);
  return info;
}

FileInfo inspect_depth_png(const fs::path& path, const InspectOptions& options) {
  const DepthImage depth = read_depth_png(path, options.depth_png_metres_per_unit);
  if (options.camera && options.camera->width != 0 &&
      (options.camera->width != depth.width || options.camera->height != depth.height)) {
    throw Error(fmt::format("{}: image is {}x{} but the camera is {}x{}", path.string(), depth.width, depth.height,
                            options.camera->width, options.camera->height));
  }
  FileInfo info;
  info.kind = "16-bit depth PNG";
  info.points = depth.depth_m.size();
  info.valid_points = depth.count_valid();
  info.width = depth.width;
  info.height = depth.height;
  float lo = INFINITY, hi = -INFINITY;
  for (float z : depth.depth_m) {
    if (std::isfinite(z) && z > 0) { lo = std::min(lo, z); hi = std::max(hi, z); }
  }
  if (info.valid_points > 0) {
    info.notes.push_back(fmt::format("depth {:.4f} to {:.4f} m at {} m per unit", lo, hi, options.depth_png_metres_per_unit));
    // What `recognize` warns of, said here too: a median outside a depth camera's range.
    if (const std::string w = depth_scale_warning(depth, options.depth_png_metres_per_unit * 1000.0); !w.empty()) {
      info.notes.push_back("warning: " + w);
    }
  } else {
    info.problems.push_back("no valid pixels (every depth is 0)");
  }
  if (options.camera) {
    CameraIntrinsics K = *options.camera;
    if (K.width == 0 && K.height == 0) {
      K.width = depth.width;
      K.height = depth.height;
    }
    const PointCloud cloud = depth_to_cloud(depth, K);  // throws, naming both sizes, on a mismatch
    info.bbox = bounding_box(cloud.points);
    info.bbox_unit = LengthUnit::Metres;
    info.notes.push_back(fmt::format("intrinsics fx {} fy {} cx {} cy {}", K.fx, K.fy, K.cx, K.cy));
  }
  return info;
}

FileInfo inspect_json(const fs::path& path) {
  const auto bytes = read_file_bytes(path);
  const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  const std::string name = path.string();
  nlohmann::json root;
  try {
    root = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw Error(fmt::format("{}: invalid JSON: {}", name, e.what()));
  }
  FileInfo info;
  const auto first_value = [&]() -> const nlohmann::json* {
    return root.is_object() && !root.empty() ? &root.begin().value() : nullptr;
  };
  const nlohmann::json* first = first_value();
  if (root.is_object() && root.contains("fx")) {
    const BopCamera cam = parse_bop_camera(text, name);
    info.kind = "BOP camera.json";
    info.width = cam.K.width;
    info.height = cam.K.height;
    info.notes.push_back(fmt::format("fx {} fy {} cx {} cy {}, depth scale {} mm per unit", cam.K.fx, cam.K.fy, cam.K.cx,
                                     cam.K.cy, cam.depth_scale_mm));
  } else if (first && first->is_object() && first->contains("cam_K")) {
    const SceneCameras cams = parse_scene_camera(text, name);
    info.kind = "BOP scene_camera.json";
    info.notes.push_back(fmt::format("{} images", cams.size()));
  } else if (first && first->is_object() && first->contains("diameter")) {
    const ModelsInfo models = parse_models_info(text, name);
    info.kind = "BOP models_info.json";
    for (const auto& [id, m] : models) {
      info.notes.push_back(fmt::format("object {}: diameter {:.1f} mm, {} discrete and {} continuous symmetries", id,
                                       m.diameter_m * 1000.0, m.symmetries_discrete.size(), m.symmetries_continuous.size()));
    }
  } else if (first && first->is_array() && !first->empty() && (*first)[0].contains("visib_fract")) {
    const SceneGroundTruthInfo gt_info = parse_scene_gt_info(text, name);
    info.kind = "BOP scene_gt_info.json";
    info.notes.push_back(fmt::format("{} images", gt_info.size()));
  } else if (first && first->is_array()) {
    const SceneGroundTruth gt = parse_scene_gt(text, name);
    std::size_t poses = 0;
    std::set<int> objects;
    for (const auto& [id, list] : gt) {
      poses += list.size();
      for (const auto& p : list) objects.insert(p.obj_id);
    }
    info.kind = "BOP scene_gt.json";
    info.notes.push_back(fmt::format("{} images, {} poses of {} objects", gt.size(), poses, objects.size()));
  } else {
    throw Error(fmt::format("{}: JSON that is not a BOP camera, scene or models file", name));
  }
  return info;
}

FileInfo inspect_dataset(const fs::path& dir) {
  FileInfo info;
  info.kind = "BOP dataset folder";
  const BopLayout layout = scan_bop_layout(dir);
  if (layout.splits.empty()) {
    throw Error(fmt::format("{}: a folder with no BOP split in it (no SPLIT/SCENE/scene_camera.json)", dir.string()));
  }
  std::vector<std::string> notes;
  for (const BopSplitFolder& split : layout.splits) {
    const BopDataset ds = open_bop_dataset(dir, split.folder);
    std::set<int> scenes, objects;
    std::set<double> depth_scales;
    std::size_t poses = 0, ycb_named = 0;
    for (const auto& im : ds.images) {
      scenes.insert(im.scene_id);
      poses += im.gt.size();
      for (const auto& g : im.gt) objects.insert(g.obj_id);
      depth_scales.insert(im.camera.depth_scale_mm);
      ycb_named += im.depth_path.parent_path().filename() != "depth";
    }
    const std::string what = split.type.empty() ? fmt::format("split '{}'", split.folder)
                                                : fmt::format("split '{}' ({}, {})", split.folder, split.split, split.type);
    std::vector<std::string> scales;
    for (double s : depth_scales) scales.push_back(fmt::format("{:g}", s));
    info.notes.push_back(fmt::format("{}: {} scenes, {} images, {} ground-truth poses of {} objects; depth {} ({} mm per "
                                     "unit){}", what, scenes.size(), ds.images.size(), poses, objects.size(),
                                     ycb_named == ds.images.size() ? "SCENE/NNNNNN-depth.png (YCB-Video's naming)"
                                                                   : "SCENE/depth/NNNNNN.png",
                                     fmt::join(scales, ", "), ds.camera ? fmt::format(", {} x {}", ds.camera->K.width, ds.camera->K.height) : ""));
    for (const auto& note : ds.notes) {
      if (std::find(notes.begin(), notes.end(), note) == notes.end()) notes.push_back(note);
    }
  }
  const std::string models = resolve_models_folder(layout);
  for (const std::string& folder : layout.model_folders) {
    std::size_t meshes = 0;
    for (const auto& entry : fs::directory_iterator(dir / folder)) meshes += entry.path().extension() == ".ply";
    std::string with_info = "no models_info.json";
    if (fs::exists(dir / folder / "models_info.json")) {
      const auto bytes = read_file_bytes(dir / folder / "models_info.json");
      const ModelsInfo mi = parse_models_info(std::string(bytes.begin(), bytes.end()), (dir / folder / "models_info.json").string());
      const auto symmetric = std::count_if(mi.begin(), mi.end(), [](const auto& kv) {
        return !kv.second.symmetries_discrete.empty() || !kv.second.symmetries_continuous.empty();
      });
      with_info = fmt::format("models_info.json with {} objects, {} of them symmetric", mi.size(), symmetric);
    }
    std::vector<std::string> uses;
    if (folder == models) uses.push_back("recognition's default");
    if (folder == "models_eval" || (folder == models && std::find(layout.model_folders.begin(), layout.model_folders.end(),
                                                                  "models_eval") == layout.model_folders.end())) {
      uses.push_back("scoring");
    }
    info.notes.push_back(fmt::format("{}/: {} meshes, {}{}", folder, meshes, with_info,
                                     uses.empty() ? "" : fmt::format(" (used for {})", fmt::join(uses, " and "))));
  }
  if (layout.model_folders.empty()) info.problems.push_back("no models folder (models/ with obj_NNNNNN.ply): nothing to recognize or score");
  if (!layout.camera_files.empty()) info.notes.push_back(fmt::format("cameras: {}", fmt::join(layout.camera_files, ", ")));
  for (const std::string& file : layout.target_files) {
    const std::vector<BopTarget> targets = read_bop_targets(dir / file);
    std::set<std::pair<int, int>> images;
    std::set<int> objects;
    int instances = 0;
    for (const BopTarget& t : targets) {
      images.insert({t.scene_id, t.im_id});
      objects.insert(t.obj_id);
      instances += t.inst_count;
    }
    info.notes.push_back(fmt::format("targets: {}: {} instances of {} objects to find in {} images (viewpose bop --targets)",
                                     file, instances, objects.size(), images.size()));
  }
  for (const auto& note : notes) info.notes.push_back("note: " + note);
  return info;
}

}  // namespace

FileInfo inspect_file(const fs::path& path, const InspectOptions& options) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return inspect_dataset(path);
  if (!fs::exists(path, ec)) throw Error(fmt::format("{}: no such file", path.string()));
  const std::string ext = lower_extension(path);
  if (ext == ".pcd") {
    const PcdFile pcd = read_pcd(path);
    std::vector<std::string> fields;
    for (const auto& f : pcd.header.fields) fields.push_back(f.count == 1 ? f.name : fmt::format("{}[{}]", f.name, f.count));
    auto info = inspect_cloud(pcd.cloud, fmt::format("PCD point cloud ({}, v{})", to_string(pcd.header.encoding),
                                                     pcd.header.version), std::move(fields));
    info.bbox_unit = LengthUnit::Metres;  // PCL writes metres
    return info;
  }
  if (ext == ".ply") {
    const PlyFile ply = read_ply(path);
    std::vector<std::string> fields;
    for (const auto& e : ply.elements) {
      if (e.name == "vertex") fields = e.properties;
    }
    auto info = inspect_cloud(ply.cloud, fmt::format("PLY {} ({})", ply.has_faces() ? "mesh" : "point cloud",
                                                     to_string(ply.encoding)), std::move(fields));
    info.faces = ply.mesh.triangles.size();
    for (const auto& e : ply.elements) info.notes.push_back(fmt::format("element {}: {}", e.name, e.count));
    return info;
  }
  if (ext == ".png") return inspect_depth_png(path, options);
  if (ext == ".json") return inspect_json(path);
  if (ext == ".csv") {
    const auto results = read_bop_results(path);
    std::set<std::pair<int, int>> images;
    std::set<int> objects;
    for (const auto& r : results) {
      images.insert({r.scene_id, r.im_id});
      objects.insert(r.obj_id);
    }
    FileInfo info;
    info.kind = "BOP19 results CSV";
    info.notes.push_back(fmt::format("{} estimates over {} images, {} objects", results.size(), images.size(), objects.size()));
    return info;
  }
  static const std::set<std::string> kMeshExtensions = {".obj", ".stl", ".off", ".gltf", ".glb", ".fbx", ".dae", ".3ds"};
  if (kMeshExtensions.count(ext)) {
    // Loaded at scale 1 so the box is in the file's own units; the guess then says which they are.
    const LoadedMesh loaded = load_mesh(path, LengthUnit::Metres);
    FileInfo info;
    info.kind = fmt::format("mesh ({})", ext.substr(1));
    info.points = loaded.mesh.vertices.size();
    info.valid_points = info.points;
    info.faces = loaded.mesh.triangles.size();
    info.fields = loaded.mesh.normals.empty() ? std::vector<std::string>{"x", "y", "z"}
                                              : std::vector<std::string>{"x", "y", "z", "nx", "ny", "nz"};
    describe_points(info, loaded.mesh.vertices);
    return info;
  }
  throw Error(fmt::format("{}: unknown file type '{}' (viewpose reads .pcd .ply .obj .stl .off .png .json .csv, and "
                          "BOP dataset folders)", path.string(), ext));
}

}  // namespace viewpose
