#pragma once
// A known object: its id (BOP obj_id, or 1, 2, ... in the order given), its name and its mesh.
// Databases are built from these, and simulated scenes are made of them.
#include <string>

#include "viewpose/core/mesh.hpp"

namespace viewpose {

struct ObjectModel {
  int id = 0;
  std::string name;
  TriangleMesh mesh;  ///< metres, object frame
};

}  // namespace viewpose
