#pragma once
// Frame-to-model registration: refines a new frame's pose against the accumulated model with
// point-to-plane ICP (PCL), starting from the kinematic pose, and gates the result so an
// implausible alignment is rejected (the kinematic pose is then kept).
#include <string>

#include "core/geometry/point_cloud.hpp"
#include "core/base/pose.hpp"

namespace pbnbv {

struct RegistrationParams {
  double voxel_m = 0.002;                // both clouds downsampled to this for ICP
  double max_correspondence_m = 0.02;    // ICP correspondence distance (coarse-to-fine from here)
  int max_iterations = 60;
  // Gates: an alignment is accepted only if all hold.
  double min_overlap = 0.1;              // share of frame points with a model point within
                                         // overlap_distance_m after alignment
  double overlap_distance_m = 0.003;
  double max_rmse_m = 0.002;             // RMS distance of the overlapping points
  double max_translation_m = 0.03;       // size of the correction
  double max_rotation_deg = 3.0;
  int min_points = 200;                  // in the frame and in the model
  // Geometry that does not pin the alignment down in all six directions (a single plane, two
  // planes, a sphere) lets ICP slide: below this smallest normalised eigenvalue of the
  // point-to-plane information matrix the view keeps its kinematic pose (still merged).
  double min_constraint = 0.01;
};

struct RegistrationResult {
  bool accepted = false;      // the view is usable: merge it (with `correction` applied)
  bool refined = false;       // the correction comes from ICP (false: kinematic pose kept)
  std::string reason;         // why accepted or rejected, with the figures
  double constraint = 0;      // smallest normalised eigenvalue of the point-to-plane
                              // information matrix of the overlap (0: a direction is free)
  Pose correction = Pose::Identity();  // object_T_object: registered = correction * kinematic
  double translation_m = 0;   // |correction| translation
  double rotation_deg = 0;    // |correction| rotation angle
  double overlap = 0;         // after alignment
  double rmse_m = 0;          // after alignment
  int iterations = 0;
  bool converged = false;
  double time_s = 0;
};

// Registers `frame` (already in the object frame by the kinematic pose) to `model`. The first
// frame of a scan (empty model) is accepted as is. Throws nothing for bad clouds: too few points
// gives a rejected result saying so.
RegistrationResult register_frame(const PointCloud& model, const PointCloud& frame,
                                  const RegistrationParams& params);

// Applies a correction to every point.
PointCloud transform_cloud(const PointCloud& cloud, const Pose& transform);

}  // namespace pbnbv
