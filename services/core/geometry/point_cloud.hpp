#pragma once
// A point cloud as the pipeline passes it around: points in metres, in the frame the caller
// states (the object frame everywhere in a scan).
#include <Eigen/Core>
#include <vector>

namespace pbnbv {

using PointCloud = std::vector<Eigen::Vector3f>;

}  // namespace pbnbv
