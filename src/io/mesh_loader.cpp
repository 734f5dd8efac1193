#include "viewpose/io/mesh_loader.hpp"

#include <dlfcn.h>

#include <assimp/cimport.h>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <memory>
#include <mutex>
#include <string>
#include <system_error>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"

namespace viewpose {

namespace {

// assimp is opened the first time a mesh is read, not as every program starts: linked, its loading
// and relocation cost each process 7.5 ms (measured with perf stat against an empty program on this
// project's 2-core VM; the `viewpose` command starts twice, start_environment.cpp), and only
// `db build`, `info` and `simulate` read meshes. Its C interface is used, whose functions dlsym
// finds by name. VIEWPOSE_ASSIMP_SONAME is the library the build found (src/CMakeLists.txt).
class Assimp {
 public:
  static const Assimp& get() {
    static const Assimp api;
    if (!api.error_.empty()) throw Error(api.error_);
    return api;
  }
  decltype(&aiCreatePropertyStore) create_store = nullptr;
  decltype(&aiReleasePropertyStore) release_store = nullptr;
  decltype(&aiSetImportPropertyInteger) set_integer = nullptr;
  decltype(&aiImportFileExWithProperties) import = nullptr;
  decltype(&aiReleaseImport) release = nullptr;
  decltype(&aiGetErrorString) error_string = nullptr;
  /// The C interface keeps its last error in one place for the whole process: one import at a time.
  std::mutex& importing() const { return importing_; }

 private:
  Assimp() {
    void* library = ::dlopen(VIEWPOSE_ASSIMP_SONAME, RTLD_NOW | RTLD_LOCAL);
    if (library == nullptr) {
      const char* why = ::dlerror();
      error_ = fmt::format("cannot open assimp ({}), which reads mesh files: {} (Debian: apt-get install libassimp5)",
                           VIEWPOSE_ASSIMP_SONAME, why ? why : "unknown error");
      return;
    }
    const auto find = [&](auto& function, const char* name) {
      function = reinterpret_cast<std::remove_reference_t<decltype(function)>>(::dlsym(library, name));
      if (function == nullptr && error_.empty()) error_ = fmt::format("{} has no {}: not the assimp this viewpose was built with", VIEWPOSE_ASSIMP_SONAME, name);
    };
    find(create_store, "aiCreatePropertyStore");
    find(release_store, "aiReleasePropertyStore");
    find(set_integer, "aiSetImportPropertyInteger");
    find(import, "aiImportFileExWithProperties");
    find(release, "aiReleaseImport");
    find(error_string, "aiGetErrorString");
    // (Never closed: the process may read another mesh later.)
  }
  std::string error_;
  mutable std::mutex importing_;
};

}  // namespace

LoadedMesh load_mesh(const std::filesystem::path& path, LengthUnit file_unit) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw Error(fmt::format("{}: {}", path.string(), std::filesystem::exists(path, ec) ? "not a regular file" : "no such file"));
  }
  const Assimp& assimp = Assimp::get();
  const std::lock_guard lock(assimp.importing());
  const std::unique_ptr<aiPropertyStore, decltype(assimp.release_store)> properties(assimp.create_store(), assimp.release_store);
  // Points and lines are not surfaces: drop them rather than fail.
  assimp.set_integer(properties.get(), AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const std::unique_ptr<const aiScene, decltype(assimp.release)> imported(
      assimp.import(path.c_str(), aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices | aiProcess_SortByPType,
                    nullptr, properties.get()),
      assimp.release);
  const aiScene* scene = imported.get();
  if (scene == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0 || scene->mRootNode == nullptr) {
    throw Error(fmt::format("{}: cannot read the mesh: {}", path.string(), assimp.error_string()));
  }
  const float scale = static_cast<float>(metres_per_unit(file_unit));
  LoadedMesh out;
  TriangleMesh& mesh = out.mesh;
  bool all_normals = true;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) all_normals = all_normals && scene->mMeshes[m]->HasNormals();
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* am = scene->mMeshes[m];
    if ((am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0) continue;
    const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      const aiVector3D& p = am->mVertices[v];
      mesh.vertices.emplace_back(p.x * scale, p.y * scale, p.z * scale);
      if (all_normals) {
        const aiVector3D& n = am->mNormals[v];
        mesh.normals.emplace_back(n.x, n.y, n.z);
      }
    }
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;
      mesh.triangles.push_back({base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
    }
  }
  if (mesh.triangles.empty()) throw Error(fmt::format("{}: the file holds no triangles", path.string()));
  mesh.check_consistent();
  BoundingBox box_in_file_units = bounding_box(mesh);
  if (!box_in_file_units.empty) {
    box_in_file_units.min /= scale;
    box_in_file_units.max /= scale;
  }
  if (std::string w = unit_mismatch_warning(box_in_file_units, file_unit); !w.empty()) {
    out.warnings.push_back(fmt::format("{}: {}", path.string(), w));
  }
  return out;
}

}  // namespace viewpose
