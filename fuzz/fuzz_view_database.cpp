// libFuzzer target: the view database reader. A mutated file almost never keeps its CRC-32, so
// half the inputs (first byte even) are taken as a payload and given a valid header and checksum
// around it: the parser behind the checksum is fuzzed too. Whatever the reader accepts must be a
// consistent database, and must survive a write/read round trip.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "viewpose/core/error.hpp"
#include "viewpose/database/view_database.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::span<const std::uint8_t> rest(data + 1, size - 1);
  const std::vector<std::uint8_t> bytes = (data[0] & 1) ? std::vector<std::uint8_t>(rest.begin(), rest.end())
                                                        : viewpose::ViewDatabase::file_from_payload(rest);
  try {
    const viewpose::ViewDatabase db = viewpose::ViewDatabase::deserialize(bytes, "fuzz.vpdb");
    for (const auto& v : db.views) {
      if (v.object >= db.objects.size()) __builtin_trap();
    }
    for (const auto& o : db.objects) {
      for (const viewpose::TriangleMesh* mesh : {&o.mesh, &o.drawn_mesh})
        for (const auto& t : mesh->triangles)
          for (std::uint32_t i : t)
            if (i >= mesh->vertices.size()) __builtin_trap();
      for (std::uint32_t c : o.nearest_cells)
        if (c > o.model_points.size()) __builtin_trap();
    }
    const viewpose::ViewDatabase again = viewpose::ViewDatabase::deserialize(db.serialize(), "again");
    if (again.views.size() != db.views.size() || again.objects.size() != db.objects.size()) __builtin_trap();
  } catch (const viewpose::Error&) {
  }
  return 0;
}
