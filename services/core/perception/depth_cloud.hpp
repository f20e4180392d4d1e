#pragma once
// Turning one depth frame into an object-frame cloud: decode, back-project, transform, crop,
// downsample. Plain functions; the camera service calls them.
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "core/geometry/camera_model.hpp"
#include "core/geometry/colour_image.hpp"
#include "core/geometry/point_cloud.hpp"
#include "core/base/pose.hpp"

namespace pbnbv {

struct CloudCrop {
  Eigen::AlignedBox3d volume_m;  // working volume, object frame (closed); empty: no limit
  double ground_z_m = -1e9;  // object-frame z of the turntable top; points at or below
  double ground_clearance_m = 0;  // ground_z + clearance are dropped
  // The turntable top as this frame sees it: a plane fitted to the readings near ground_z (the
  // kinematic pose's error and the camera's noise move and blur it), and the points within
  // clearance + 3 sigma of its readings' scatter above it dropped as well.
  bool fit_ground = true;
};

struct CloudStats {
  int num_valid_pixels = 0;
  int num_cropped = 0;
  int ground_points = 0;         // readings the turntable's plane was fitted to (0: no fit)
  double ground_offset_m = 0;    // the fitted plane's height above ground_z at the object's axis
  double ground_sigma_m = 0;     // its readings' scatter about it (robust)
  Eigen::Vector3d ground_abc = Eigen::Vector3d::Zero();  // the plane: z = a x + b y + c
};

// The plane z = a x + b y + c through `points` (object frame), robustly: least squares, then
// again on the points within 3 robust sigmas (1.4826 x the median absolute residual), three
// times. Returns false when fewer than 50 points or the plane tilts more than 5 degrees.
bool fit_ground_plane(const std::vector<Eigen::Vector3d>& points, Eigen::Vector3d* abc, double* sigma_m);


// Back-projects every pixel whose depth is finite and inside `range`, maps it with
// object_T_camera, keeps the points inside the crop, then voxel-downsamples.
PointCloud depth_to_object_cloud(const std::vector<float>& depth_m, const CameraIntrinsics& k,
                                 const DepthRange& range, const Pose& object_T_camera,
                                 const CloudCrop& crop, double voxel_m, CloudStats* stats);

// A unit normal per object-frame point from the depth image it came from: the point is projected
// into the image with object_T_camera (the registered pose maps the registered points to the
// pixels they came from), its normal is the cross product of the depth image's central
// differences `step_px` pixels either side (one side where the other has no reading or lies
// across a depth jump of more than 5 % of the depth), turned to face the camera and rotated into
// the object frame. Zero where the point falls outside the image or its neighbourhood has no
// readings.
std::vector<Eigen::Vector3f> depth_normals(const PointCloud& points, const std::vector<float>& depth_m,
                                           const CameraIntrinsics& k, const Pose& object_T_camera, int step_px = 2);

// Where the depth image is gone: the plane fitted to each point's `neighbours` nearest points
// (estimate_normals), turned to face `camera_m` (object frame). Zero where no plane was fitted.
std::vector<Eigen::Vector3f> neighbour_normals(const PointCloud& points, const Eigen::Vector3d& camera_m,
                                               int neighbours = 12);

// The normals of `points` averaged into the voxels of voxel_downsample(points, voxel_m) =
// `downsampled` (zero normals are left out; a voxel without any gets a zero normal). voxel_m <= 0
// (nothing merged, `downsampled` = `points`): each point's own normal.
std::vector<Eigen::Vector3f> voxel_normals(const PointCloud& points, const std::vector<Eigen::Vector3f>& normals,
                                           const PointCloud& downsampled, double voxel_m);

// The colours of `points` averaged into the voxels of voxel_downsample(points, voxel_m) =
// `downsampled`, channel by channel (a voxel without any gets kNoColour).
std::vector<Rgb> voxel_colours(const PointCloud& points, const std::vector<Rgb>& colours, const PointCloud& downsampled,
                               double voxel_m);

// A cloud downsampled at a voxel size: one point per voxel (the centroid of what fell in it), its
// normal and, when `colours` is not empty, its colour, in voxel_downsample's order.
struct VoxelCloud {
  PointCloud points;
  std::vector<Eigen::Vector3f> normals;  // one per point
  std::vector<Rgb> colours;              // empty, or one per point
};

// Merges `points` (with one normal each, and colours: empty or one each) into `model`: the result
// is what voxel_downsample, voxel_normals and voxel_colours of the model's points followed by the
// new ones give (bit for bit; colours from the first coloured merge on, kNoColour for points that
// had none), with the model's untouched voxels copied instead of sorted and summed again: the
// cost is linear in the model and sorts only the new points. Falls back to the full computation
// when the model is not in voxel order (not made by these functions) or a new centroid rounds
// across its voxel's face (and for voxel_m <= 0: every point kept). Throws std::invalid_argument
// when the normals or colours are not one per point.
void merge_into_voxels(VoxelCloud& model, const PointCloud& points, const std::vector<Eigen::Vector3f>& normals,
                       const std::vector<Rgb>& colours, double voxel_m);

}  // namespace pbnbv
