// libFuzzer target: the view database reader. A mutated file almost never keeps its CRC-32, so
// half the inputs (first byte even) are taken as a payload and given valid headers and checksums
// around it: the parser behind the checksum is fuzzed too. Of those, with the first byte's second
// bit set, the next four bytes say how much of the rest is the payload; what follows is the pair
// tables. Whatever the reader accepts must be a consistent database, and must survive a write/read
// round trip; read without its pair tables, it must be the same database without them.
#include <cstddef>
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

#include "viewpose/core/error.hpp"
#include "viewpose/database/view_database.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::span<const std::uint8_t> rest(data + 1, size - 1);
  std::vector<std::uint8_t> bytes;
  if (data[0] & 1) {
    bytes.assign(rest.begin(), rest.end());
  } else if ((data[0] & 2) && rest.size() >= 4) {
    std::uint32_t payload = 0;
    std::memcpy(&payload, rest.data(), 4);
    const std::span<const std::uint8_t> parts = rest.subspan(4);
    payload = static_cast<std::uint32_t>(std::min<std::size_t>(payload, parts.size()));
    bytes = viewpose::ViewDatabase::file_from_payload(parts.first(payload), parts.subspan(payload));
  } else {
    bytes = viewpose::ViewDatabase::file_from_payload(rest);
  }
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
      if (o.pair_table) {
        for (const std::uint32_t e : o.pair_table->entries)
          if ((e >> viewpose::PpfTable::kAlphaBits) >= o.pair_table->sampled.size()) __builtin_trap();
        if (o.pair_table->key_start.empty() || o.pair_table->key_start.back() != o.pair_table->entries.size()) __builtin_trap();
      }
    }
    const viewpose::ViewDatabase without = viewpose::ViewDatabase::deserialize(bytes, "fuzz.vpdb", {.pair_tables = false});
    if (without.views.size() != db.views.size() || without.objects.size() != db.objects.size()) __builtin_trap();
    for (const auto& o : without.objects)
      if (o.pair_table) __builtin_trap();
    const viewpose::ViewDatabase again = viewpose::ViewDatabase::deserialize(db.serialize(), "again");
    if (again.views.size() != db.views.size() || again.objects.size() != db.objects.size()) __builtin_trap();
  } catch (const viewpose::Error&) {
  }
  return 0;
}
