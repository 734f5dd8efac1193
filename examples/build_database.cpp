// A view database from mesh files, saved for `viewpose recognize --db` or a Recognizer:
//
//   build_database objects.vpdb mug.ply bowl.obj --mm
//   build_database shapes.vpdb jug can
//
// Meshes carry no unit: say which one they use (BOP and most CAD exports: millimetres).
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "viewpose/core/error.hpp"
#include "viewpose/database/view_database.hpp"
#include "viewpose/io/object_models.hpp"

int main(int argc, char** argv) {
  using namespace viewpose;
  if (argc < 3) {
    std::fprintf(stderr, "usage: build_database OUT.vpdb MESH... [--mm]\n");
    return 2;
  }
  LengthUnit unit = LengthUnit::Metres;
  std::vector<std::string> meshes;
  for (int i = 2; i < argc; ++i) {
    if (std::strcmp(argv[i], "--mm") == 0) unit = LengthUnit::Millimetres;
    else meshes.emplace_back(argv[i]);
  }
  try {
    // Mesh files in `unit`, or the built-in shapes' names (jug, box, can, mug); ids 1, 2, ... in order.
    LoadedObjectModels loaded = load_object_models(meshes, unit);
    for (const std::string& w : loaded.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    const std::vector<ObjectModel>& objects = loaded.objects;
    const ViewDatabase db = build_view_database(objects, DatabaseParams{}, [](std::size_t done, std::size_t total) {
      std::fprintf(stderr, "\rrendered %zu of %zu objects", done, total);
    });
    std::fprintf(stderr, "\n");
    db.save(argv[1]);
    std::printf("%s: %zu objects, %zu views\n", argv[1], db.objects.size(), db.views.size());
  } catch (const Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
