#pragma once
// The working volume: where an object of unknown shape may be. On the arm rig it stands on the
// turntable top, centred on the turntable axis; on the free rig it is centred on the origin. A
// scan of an unknown object needs only this (never a mesh): the object frame sits at its centre,
// the arm keeps out of it, and the clouds are cropped to it. The bounding box B of the method is
// measured from what the camera sees (the map), as for every scan.
#include <Eigen/Geometry>
#include <string>

namespace pbnbv {

struct WorkingVolume {
  enum class Shape { kCylinder, kBox };
  Shape shape = Shape::kCylinder;
  double radius_m = 0;                // cylinder: radius about the turntable axis
  double size_x_m = 0, size_y_m = 0;  // box: edges along the turntable's x and y
  double height_m = 0;                // both: height above the turntable top

  // Centred on the object frame's origin (the volume's centre): x, y within the radius or the
  // half edges, z within +-height/2.
  Eigen::AlignedBox3d bounds() const;
  // "cylinder:R,H" or "box:X,Y,Z" (m), as parse_working_volume reads it.
  std::string to_text() const;
};

// Reads "cylinder:R,H" (radius, height) or "box:X,Y,Z" (edges), in metres. Throws
// std::invalid_argument naming the text and what is wrong (unknown shape, a missing or extra
// number, a size not positive or above 3 m).
WorkingVolume parse_working_volume(const std::string& text);

}  // namespace pbnbv
