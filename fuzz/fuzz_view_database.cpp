// libFuzzer target: the view database reader. A mutated file almost never keeps its CRC-32, so
// half the inputs (first byte even) are taken as a payload and given a valid header and checksum
// around it: the parser behind the checksum is fuzzed too. Whatever the reader accepts must be a
// consistent database, and must survive a write/read round trip.
#include <zlib.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

#include "viewpose/core/error.hpp"
#include "viewpose/database/view_database.hpp"

namespace {

std::vector<std::uint8_t> with_header(std::span<const std::uint8_t> payload) {
  static constexpr char kMagic[8] = {'V', 'P', 'D', 'B', '\r', '\n', '\x1a', '\n'};
  std::vector<std::uint8_t> file(32, 0);
  std::memcpy(file.data(), kMagic, 8);
  const std::uint32_t version = viewpose::ViewDatabase::kFormatVersion, bom = 0x01020304;
  const std::uint64_t size = payload.size();
  const auto crc = static_cast<std::uint32_t>(crc32(0, payload.data(), static_cast<uInt>(payload.size())));
  std::memcpy(file.data() + 8, &version, 4);
  std::memcpy(file.data() + 12, &bom, 4);
  std::memcpy(file.data() + 16, &size, 8);
  std::memcpy(file.data() + 24, &crc, 4);
  file.insert(file.end(), payload.begin(), payload.end());
  return file;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::span<const std::uint8_t> rest(data + 1, size - 1);
  const std::vector<std::uint8_t> bytes = (data[0] & 1) ? std::vector<std::uint8_t>(rest.begin(), rest.end()) : with_header(rest);
  try {
    const viewpose::ViewDatabase db = viewpose::ViewDatabase::deserialize(bytes, "fuzz.vpdb");
    for (const auto& v : db.views) {
      if (v.object >= db.objects.size() || v.normals.size() != v.points.size()) __builtin_trap();
    }
    for (const auto& o : db.objects) {
      for (const auto& t : o.mesh.triangles)
        for (std::uint32_t i : t)
          if (i >= o.mesh.vertices.size()) __builtin_trap();
    }
    const viewpose::ViewDatabase again = viewpose::ViewDatabase::deserialize(db.serialize(), "again");
    if (again.views.size() != db.views.size() || again.objects.size() != db.objects.size()) __builtin_trap();
  } catch (const viewpose::Error&) {
  }
  return 0;
}
