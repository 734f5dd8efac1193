#pragma once
// Lengths are metres everywhere inside viewpose. Files come in metres (PCD, most OBJ/STL) or
// millimetres (BOP models, many CAD exports); the unit is converted once, where the file is read.
#include <string>
#include <string_view>

#include "viewpose/core/point_cloud.hpp"

namespace viewpose {

enum class LengthUnit { Metres, Millimetres };

/// Metres per one unit of the file: 1 or 0.001.
double metres_per_unit(LengthUnit unit);
std::string_view to_string(LengthUnit unit);
/// "m" / "mm" (also "metres", "millimetres"); throws viewpose::Error for anything else.
LengthUnit parse_length_unit(std::string_view text);

/// A guess of the unit a box of coordinates was written in. Real objects and depth-camera scenes
/// span 1 cm to 10 m, so a diagonal of 10 file units or more is read as millimetres, less as metres.
struct UnitGuess {
  LengthUnit unit = LengthUnit::Metres;
  std::string reason;  ///< one sentence a person can check
};
UnitGuess guess_length_unit(const BoundingBox& box);

/// A warning when a box said to be in `declared` units looks like the other unit (a bottle 150 m
/// tall), or an empty string when the size is plausible.
std::string unit_mismatch_warning(const BoundingBox& box, LengthUnit declared);

}  // namespace viewpose
