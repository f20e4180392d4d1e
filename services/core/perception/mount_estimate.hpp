#pragma once
// The camera mount's error, estimated across a scan's views (a hand-eye refinement that improves
// as the scan goes on). An error that is the same in every view: the camera sits at
// flange_T_camera * E instead of the rig file's flange_T_camera, so view i's true pose is its
// kinematic pose K_i times E. The model is built in the first view's kinematic frame (K_1 is
// taken as exact), so registration finds for view i the correction
//     C_i = K_1 E^-1 K_1^-1  K_i E K_i^-1          (registered = C_i * kinematic)
// which, over views seen from different directions, pins E down: a Gauss-Newton fit of E to
// ICP's proposals, each weighed by its covariance, with the rig's stated pose sigma as a prior.
// Then:
//   - the next view's correction is predicted (the registration prior's mean moves there);
//   - the model's frame is related to the object frame: object = K_1 E K_1^-1 * model (up to a
//     turn about the turntable's axis, which no view can tell: a turntable zero error turns every
//     view alike).
// The proposals of single alignments slide when the mount is far off (an uncalibrated one puts
// views 10-20 mm apart): mount_from_views fits E to the views' clouds themselves instead, every
// view against every other at once (E moves them all), which a view's own alignment cannot do,
// with each view's own small error (joints, backlash) fitted alongside: where the fit puts every
// view (fitted_correction) is a multi-view alignment the registration service places them by.
// Plain data and functions; the registration service keeps one per scan.
#include <Eigen/Core>
#include <optional>
#include <utility>
#include <vector>

#include "core/base/pose.hpp"
#include "core/perception/registration.hpp"

namespace pbnbv {

// One view's evidence: its kinematic pose and ICP's proposal for it, expressed against the first
// view's kinematic frame (the model's frame).
struct MountObservation {
  int view = -1;                       // which view (for saying which were left out)
  Pose kinematic = Pose::Identity();   // object_T_camera by the rig file
  IcpProposal proposal;                // registered = proposal.correction * kinematic
};

struct MountEstimate {
  Pose error = Pose::Identity();  // E: the true mount is the rig file's times this (camera frame)
  TwistCovariance covariance = TwistCovariance::Identity();  // of E's twist about the camera centre
  int views = 0;                  // observations it rests on (the consistent ones)
  int outliers = 0;               // observations left out: more than 4 sigma from the fit of the rest
  double sigma_m = 0;             // largest 1-sigma of its translation, m
  double sigma_deg = 0;           // largest 1-sigma of its rotation, degrees
  // mount_from_views: each paired view's own error D_i as fitted alongside (view i at K_i E D_i).
  std::vector<std::pair<int, Pose>> view_errors;
  double translation_m() const;
  double rotation_deg() const;
};

class MountEstimator {
 public:
  // The prior on E: each axis, 1 sigma (the rig's stated pose uncertainty).
  MountEstimator(double prior_translation_m, double prior_rotation_deg);

  // The first view's kinematic pose (the model's frame). Views before it are not taken.
  void set_first(const Pose& kinematic);
  bool has_first() const { return first_.has_value(); }
  void add(const MountObservation& o);
  const std::vector<MountObservation>& observations() const { return observations_; }
  const std::optional<Pose>& first() const { return first_; }

  // A fit of E from the views' clouds (mount_from_views): from then on it is the estimate, and
  // the proposals only tell which views slid (more than 4 sigma from it).
  void set_from_views(const MountEstimate& e);
  bool from_views() const { return from_views_.has_value(); }

  // The fit (identity with the prior's covariance before any observation). Observations that
  // disagree with the others (an alignment that slid to a wrong fit: its residual more than 4
  // sigma) are left out, the worst first, and the rest fitted again.
  const MountEstimate& estimate() const { return estimate_; }
  // Sure enough to be used: at least `min_views` consistent observations and its sigma within
  // 1 mm and 0.2 degrees, or within half the prior's (it knows the mount twice as well as the
  // rig file does: an uncalibrated rig's 4 mm / 0.65 deg halved).
  bool trusted(int min_views = 3) const;
  // The views whose observations the fit left out (their alignment slid: placed wrong).
  const std::vector<int>& outlier_views() const { return outlier_views_; }
  // The correction C_i the estimate predicts for a view at `kinematic`.
  Pose predicted_correction(const Pose& kinematic) const;
  // The correction that places a view where the clouds' fit put it: the mount's, and the view's
  // own error as fitted alongside (K_1 E^-1 K_1^-1 K E D K^-1). None for a view the fit did not
  // pair with another, or before a fit to the clouds.
  std::optional<Pose> fitted_correction(int view, const Pose& kinematic) const;
  // object_T_model: where the model's points lie in the object frame by the estimate.
  Pose object_T_model() const;

 private:
  void refit();
  double prior_t_, prior_r_;
  std::optional<Pose> first_;
  std::vector<MountObservation> observations_;
  std::optional<MountEstimate> from_views_;
  MountEstimate estimate_;
  std::vector<int> outlier_views_;
};

// C = K1 E^-1 K1^-1 K E K^-1.
Pose mount_correction(const Pose& first, const Pose& kinematic, const Pose& error);

// One view for mount_from_views: its points and their unit normals in the camera frame (the
// normals facing the camera; a zero normal: none), and its kinematic pose (object_T_camera by the
// rig file).
struct MountView {
  int view = -1;
  Pose kinematic = Pose::Identity();
  PointCloud points;
  std::vector<Eigen::Vector3f> normals;
};

struct MountFitParams {
  // Correspondences farther apart than this are not paired: coarse to fine, each stage iterated
  // to convergence (the first must exceed how far apart the mount error puts the views).
  std::vector<double> correspondence_m = {0.04, 0.02, 0.01, 0.005};
  int iterations_per_stage = 8;
  double max_normal_angle_deg = 30.0;  // pairs whose normals disagree more are not paired
  int points_per_view = 1500;          // each view's points thinned to about this many
  int min_points = 50;                 // views with fewer are left out
  // As in registration, neighbouring residuals are not independent: N pairs inform as N / this
  // (fewer than ICP's 25: the points are thinned to a few millimetres apart).
  double pairs_per_independent = 4.0;
  double min_residual_m = 0.0002;      // the residual sigma is taken as at least this
  // Each view's own pose error beyond the mount's (joint encoders, turntable backlash), 1 sigma
  // per axis: the prior on the D_i fitted alongside E.
  double per_view_translation_m = 0.0003;
  double per_view_rotation_deg = 0.03;
};

// E fitted to the views' agreement: each view's points, placed by K_i E D_i, lie on the surfaces of
// the other views placed by K_j E D_j (point-to-plane, every ordered pair of views, Gauss-Newton on
// the twists of E and of every view's own small pose error D_i about the camera centre, starting
// from `start`), with the prior N(identity, the rig's stated sigma per axis) on E and the per-view
// prior on each D_i. Fitting the D_i alongside keeps what single views' errors leave between the
// clouds out of E. Directions no pair pins down (E's turn about the axis of a turntable that alone
// moved the camera) stay at the prior's. The covariance is E's in the joint fit (the D_i
// marginalised): the pairs' information at the final residual sigma, plus the priors. `views`
// counts the views that were paired with another. Fewer than two usable views: the start, with the
// prior's covariance.
// (The turntable top each view sees is not used: on objects wider than the platter or standing on
// a flat base, the readings near its height are the object's, 1-4 degrees and up to 23 mm off.)
MountEstimate mount_from_views(const std::vector<MountView>& views, const Pose& start, double prior_translation_m,
                               double prior_rotation_deg, const MountFitParams& params = {});

}  // namespace pbnbv
