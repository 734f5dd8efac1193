#include "viewpose/io/mesh_loader.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/Importer.hpp>
#include <system_error>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"

namespace viewpose {

LoadedMesh load_mesh(const std::filesystem::path& path, LengthUnit file_unit) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw Error(fmt::format("{}: {}", path.string(), std::filesystem::exists(path, ec) ? "not a regular file" : "no such file"));
  }
  Assimp::Importer importer;
  // Points and lines are not surfaces: drop them rather than fail.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene = importer.ReadFile(path.string(), aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                                              aiProcess_PreTransformVertices | aiProcess_SortByPType);
  if (scene == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0 || scene->mRootNode == nullptr) {
    throw Error(fmt::format("{}: cannot read the mesh: {}", path.string(), importer.GetErrorString()));
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
