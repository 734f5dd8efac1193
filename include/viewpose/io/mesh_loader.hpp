#pragma once
// Meshes of any format assimp reads (OBJ, STL, PLY, OFF, glTF, ...), flattened into one triangle
// mesh in metres. Files carry no unit, so the caller says which one the file uses.
#include <filesystem>
#include <string>
#include <vector>

#include "viewpose/core/mesh.hpp"
#include "viewpose/core/units.hpp"

namespace viewpose {

struct LoadedMesh {
  TriangleMesh mesh;                  ///< metres, in the file's own frame
  std::vector<std::string> warnings;  ///< e.g. a size that looks like the other unit
};

/// Throws viewpose::Error naming the file when it is missing, unreadable or holds no triangles.
LoadedMesh load_mesh(const std::filesystem::path& path, LengthUnit file_unit);

}  // namespace viewpose
