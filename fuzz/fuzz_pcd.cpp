// libFuzzer target: the PCD reader, and a write/read round trip of whatever it accepts.
#include <cstddef>
#include <cstdint>
#include <span>

#include "viewpose/core/error.hpp"
#include "viewpose/io/pcd.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const viewpose::PcdFile f = viewpose::parse_pcd(std::span(data, size), "fuzz.pcd");
    f.cloud.check_consistent();  // a cloud the reader returns is always well-formed
    if (f.cloud.size() <= 4096) {
      const auto again = viewpose::parse_pcd(viewpose::encode_pcd(f.cloud, viewpose::PcdEncoding::BinaryCompressed), "re");
      if (again.cloud.size() != f.cloud.size()) __builtin_trap();
    }
  } catch (const viewpose::Error&) {
  }
  return 0;
}
