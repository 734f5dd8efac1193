#pragma once
// Parameterized meshes of everyday objects, so that everything (the demo, the tests, the seed
// experiment) runs with no external file. All in metres, +z up, origin at the bounding-box centre
// (as BOP models are), standing on their base at z = -height/2.
#include <string>
#include <string_view>
#include <vector>

#include "viewpose/core/mesh.hpp"

namespace viewpose {

/// A laundry-detergent jug like the thesis's Tide bottle (its figure 15): a rounded-rectangle body
/// narrowing at the shoulder, a screw cap off-centre on one side of the top and a carrying handle
/// looping over the other side. Its handle and cap are what tell its sides apart.
struct JugShape {
  double height = 0.27;        ///< body height, base to shoulder top (the cap adds to it)
  double width = 0.17;         ///< across the front face (x)
  double depth = 0.11;         ///< front to back (y)
  double shoulder = 0.30;      ///< share of the height over which the body narrows
  double cap_radius = 0.024;
  double cap_height = 0.035;
  double handle_radius = 0.04;  ///< radius of the handle's arc
  double handle_thickness = 0.012;
};
TriangleMesh make_jug(const JugShape& shape = {});

/// A closed cylinder (a can), `segments` around.
TriangleMesh make_can(double radius = 0.033, double height = 0.123, int segments = 48);

/// A mug: an open cylinder with a wall, a bottom and a handle.
TriangleMesh make_mug(double radius = 0.041, double height = 0.095, double wall = 0.004);

/// A UV sphere centred on the origin: `rings` rings from pole to pole, twice as many segments
/// around (about 4 rings^2 triangles).
TriangleMesh make_sphere(double radius, int rings = 90);

/// Names make_named_shape knows: "jug", "box", "can", "mug".
std::vector<std::string> shape_names();
/// The shape of that name at its default size ("box" is a 6 x 9.5 x 20 cm carton); throws
/// viewpose::Error for other names.
TriangleMesh make_named_shape(std::string_view name);

/// Moves a mesh so that its bounding-box centre is the origin (the BOP convention).
void centre_on_bounding_box(TriangleMesh& mesh);

}  // namespace viewpose
