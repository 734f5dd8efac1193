#pragma once
// The camera back-ends, each in its own file and built only when its library is found.
#include <memory>
#include <string>

#include "viewpose/sensor/depth_source.hpp"

namespace viewpose::detail {

std::unique_ptr<DepthSource> open_freenect(int index);          // freenect_source.cpp
std::unique_ptr<DepthSource> open_openni2(const std::string& uri);  // openni2_source.cpp (empty: any device)
std::unique_ptr<DepthSource> open_recording(const std::filesystem::path& dir);  // depth_source.cpp

}  // namespace viewpose::detail
