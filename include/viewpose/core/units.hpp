#pragma once
// Lengths are metres everywhere inside viewpose. Files come in metres (PCD, most OBJ/STL),
// millimetres (BOP models, many CAD exports) or centimetres (some modelling tools); the unit is
// converted once, where the file is read.
#include <string>
#include <string_view>

#include "viewpose/core/point_cloud.hpp"

namespace viewpose {

enum class LengthUnit { Metres, Millimetres, Centimetres };

/// Metres per one unit of the file: 1, 0.001 or 0.01.
double metres_per_unit(LengthUnit unit);
std::string_view to_string(LengthUnit unit);
/// "metres", "millimetres", "centimetres": for messages.
std::string_view unit_name(LengthUnit unit);
/// "m" / "mm" / "cm" (also spelt out); throws viewpose::Error for anything else.
LengthUnit parse_length_unit(std::string_view text);

/// A guess of the unit a box of coordinates was written in. Real objects and depth-camera scenes
/// span 1 cm to 10 m, so a diagonal of 10 file units or more is read as millimetres, less as metres.
struct UnitGuess {
  LengthUnit unit = LengthUnit::Metres;
  std::string reason;  ///< one sentence a person can check
};
UnitGuess guess_length_unit(const BoundingBox& box);

/// A warning when a box said to be in `declared` units is larger than 10 m or smaller than 1 cm
/// across (a bottle 150 m tall), naming the units (and their --unit) that would make it an object
/// of 1 cm to 1.5 m; an empty string when the size is plausible.
std::string unit_mismatch_warning(const BoundingBox& box, LengthUnit declared);

}  // namespace viewpose
