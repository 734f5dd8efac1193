// libFuzzer target: the PLY reader (point clouds and meshes).
#include <cstddef>
#include <cstdint>
#include <span>

#include "viewpose/core/error.hpp"
#include "viewpose/io/ply.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const viewpose::PlyFile f = viewpose::parse_ply(std::span(data, size), "fuzz.ply");
    f.cloud.check_consistent();
    f.mesh.check_consistent();  // every face index the reader returns names a real vertex
    (void)f.mesh.surface_area();
  } catch (const viewpose::Error&) {
  }
  return 0;
}
