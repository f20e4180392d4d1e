#pragma once
// Frame-to-model registration: refines a new frame's pose against the accumulated model with
// point-to-plane ICP (PCL), starting from the kinematic pose, and weighs ICP's correction against
// how well the rig knows that pose. The kinematic pose is a prior with a known uncertainty (1 sigma
// per axis, from the rig's errors or its calibration); ICP's estimate has the uncertainty of its
// point-to-plane information matrix and residual. The correction taken is the two combined (each
// direction weighted by its information: where the overlap pins the pose down better than the rig
// does, ICP's; where it does not, the kinematics'), so an exact kinematic pose stays exact. A view
// whose alignment cannot be trusted (too little overlap, a poor fit, ICP not settled, a correction
// the rig's uncertainty does not allow) is not thrown away: it is placed at its kinematic pose and
// flagged, with the reason.
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/point_cloud.hpp"
#include "core/base/pose.hpp"
#include "core/perception/neighbours.hpp"
#include "core/perception/perception_options.hpp"

namespace pbnbv {

struct RegistrationParams {
  double voxel_m = kIcpVoxel.value;      // both clouds downsampled to this for ICP
  double max_correspondence_m = 0.02;    // ICP correspondence distance (coarse-to-fine from here)
  int max_iterations = 60;
  // Gates: ICP's alignment is trusted only if all hold (else the kinematic pose, flagged).
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
  // The kinematic pose's uncertainty, 1 sigma per axis: the camera's position and orientation as
  // the rig's kinematics give them (a calibrated arm: about 0.5 mm and 0.1 deg).
  double prior_translation_m = 0.0005;
  double prior_rotation_deg = 0.1;
  // ICP's correction is not taken when the prior makes it this improbable: its Mahalanobis
  // distance under the prior (6 degrees of freedom) above this many sigma.
  double max_prior_sigmas = 5.0;
  // Neighbouring residuals of ICP are not independent (the model's and the frame's errors are
  // smooth over a patch): the information of N pairs counts as that of N / this.
  double pairs_per_independent = 25.0;
  // The residual below which no ICP fit is believed to be (the model's own sampling), m.
  double min_residual_m = 0.00005;
};

// A small rigid motion about a point c: its rotation vector, then how far it moves c (the
// parametrisation of registration's covariances).
using Twist = Eigen::Matrix<double, 6, 1>;
// [a]x: the matrix of the cross product a x (.).
Eigen::Matrix3d skew(const Eigen::Vector3d& a);
using TwistCovariance = Eigen::Matrix<double, 6, 6>;
Twist twist_about(const Pose& t, const Eigen::Vector3d& c);
Pose pose_from_twist(const Twist& d, const Eigen::Vector3d& c);

// ICP's own proposal where it was weighed against the prior (not flagged, not degenerate): the
// correction it found, the point its covariance is about, and that covariance.
struct IcpProposal {
  Pose correction = Pose::Identity();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  TwistCovariance covariance = TwistCovariance::Identity();
};

struct RegistrationResult {
  bool accepted = false;      // the view is merged (with `correction` applied): every view with
                              // points, the first included
  bool refined = false;       // a correction was taken (false: kinematic pose kept)
  bool flagged = false;       // the alignment could not be trusted: kinematic pose kept, `reason`
                              // says why (not set when the kinematic pose fits the model)
  std::string reason;         // what was done and why, with the figures
  double constraint = 0;      // smallest normalised eigenvalue of the point-to-plane
                              // information matrix of the overlap (0: a direction is free)
  Pose correction = Pose::Identity();  // object_T_object: registered = correction * kinematic
  double translation_m = 0;   // |correction| translation
  double rotation_deg = 0;    // |correction| rotation angle
  double icp_translation_m = 0;  // what ICP alone proposed (before the prior), its size
  double icp_rotation_deg = 0;
  double prior_sigmas = 0;    // ICP's proposal's Mahalanobis distance from the kinematic pose
                              // (under the prior's and ICP's covariances together)
  double overlap = 0;         // after alignment
  double rmse_m = 0;          // after alignment
  int iterations = 0;
  bool converged = false;
  double time_s = 0;
  std::optional<IcpProposal> icp;  // for estimating what is wrong the same way in every view
};

// The model as ICP reads it, prepared once per model: its finite points downsampled to
// params.voxel_m and, with `fit_normals`, a normal fitted to each one's nearest neighbours over the
// whole of it (without: register_frame fits them over the part near each frame, as the model given
// whole does). A caller that registers many frames to the same model (the registration service:
// every view to the views before it) prepares it once, while the rig moves to the next view,
// instead of on the next frame's way.
struct RegistrationModel {
  double voxel_m = 0;                   // the params.voxel_m it was prepared for
  std::size_t finite = 0;               // the model's finite points
  std::size_t dropped = 0;              // its non-finite points, left out
  PointCloud points;                    // the finite points downsampled
  SurfaceNormals normals;               // per point of `points` (valid 0: no plane fitted); empty:
                                        // not fitted
  std::string error;                    // what failed while preparing it (register_frame then
                                        // keeps the kinematic pose, flagged, saying so)
};
RegistrationModel registration_model(const PointCloud& model, const RegistrationParams& params, bool fit_normals = true);

// Registers `frame` (already in the object frame by the kinematic pose) to `model`. `camera_m`:
// the camera's kinematic position in the object frame (the lever of its rotation error; without
// it, rotations are taken about the overlap's centre). The first frame of a scan (empty model) is
// accepted as is. Throws nothing for bad clouds: too few points, or a failure inside ICP, keep
// the kinematic pose, flagged, saying so; only a frame without a finite point is not accepted.
RegistrationResult register_frame(const PointCloud& model, const PointCloud& frame,
                                  const RegistrationParams& params,
                                  const std::optional<Eigen::Vector3d>& camera_m = std::nullopt);
// The same with the model prepared (registration_model with the same params.voxel_m; another
// voxel is refused: std::invalid_argument naming both).
RegistrationResult register_frame(const RegistrationModel& model, const PointCloud& frame,
                                  const RegistrationParams& params,
                                  const std::optional<Eigen::Vector3d>& camera_m = std::nullopt);

// Applies a correction to every point.
PointCloud transform_cloud(const PointCloud& cloud, const Pose& transform);

}  // namespace pbnbv
