#pragma once
// Cleaning a depth image of what real cameras add and no surface explains, before it becomes a
// cloud or carves the map (the camera service and the mapping service apply the same filter to
// the same frame):
//   - flying pixels: a reading that lies between its two neighbours on opposite sides (left and
//     right, up and down, or across a diagonal) and farther from each than a surface at
//     max_incidence_deg to the view ray would put it: a pixel that saw both sides of a depth edge;
//   - speckles: a connected region of fewer than min_region_px readings (neighbours connected
//     where their depths differ by no more than that same steepest surface allows).
// A real surface less steep than max_incidence_deg is never removed: on an exact image the
// filter removes nothing but surfaces seen within 2 degrees of edge-on and regions smaller than
// min_region_px (core/perception/test/depth_filter_test.cpp, the camera's tests).
#include <vector>

#include "core/geometry/camera_model.hpp"

namespace pbnbv {

struct DepthFilterParams {
  bool enabled = true;
  double max_incidence_deg = 85.0;  // the steepest surface kept, degrees between ray and normal
  int min_region_px = 20;           // smaller connected regions are speckles
};

struct DepthFilterStats {
  int flying = 0;          // readings removed as flying pixels
  int speckle_pixels = 0;  // readings removed in speckles
  int speckles = 0;        // regions removed
};

// Removes (sets to 0) the flying pixels and speckles of `depth_m` (row-major, k.width x
// k.height, 0 = no reading). Throws std::invalid_argument when the size disagrees with k.
DepthFilterStats filter_depth(std::vector<float>& depth_m, const CameraIntrinsics& k, const DepthFilterParams& p = {});

}  // namespace pbnbv
