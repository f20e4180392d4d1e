#pragma once
// The model of a scan as its registration service keeps it: the accepted views' registered
// points merged into one cloud (voxel-downsampled; each voxel's normal the mean of its points'
// normals; the merged views' camera poses), and each view's own cloud. With a folder, every view
// is written to frames/view_NNN.ply and the model, after each merged view, to cloud.ply: binary
// PLY with normals and the camera poses in the header (core/io/cloud_file.hpp), which users'
// tools (Open3D, MeshLab, PCL) read. cloud.ply is also the state a restarted service continues
// from. Plain data and files, no bus.
#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/base/pose.hpp"
#include "core/geometry/camera_model.hpp"
#include "core/geometry/colour_image.hpp"
#include "core/io/mesh_file.hpp"
#include "core/geometry/mesh_summary.hpp"
#include "core/geometry/point_cloud.hpp"
#include "core/perception/depth_cloud.hpp"
#include "core/perception/new_surface.hpp"

namespace pbnbv {

// What adding a view did.
struct ModelUpdate {
  std::string frame_file;                  // "frames/view_NNN.ply" ("" without a folder)
  bool normals_from_depth = false;         // the view's normals came with it (the depth image's);
                                           // false: fitted to its points' nearest neighbours
  std::optional<NewSurface> new_surface;   // merged views: what the view added to the model
  double seconds = 0;                      // wall time of the update and the writes
};

// A depth image as the camera took it: planar depth, m, row-major (0 or non-finite: no reading).
struct DepthImage {
  const std::vector<float>* depth_m = nullptr;
  CameraIntrinsics intrinsics;
  DepthRange range;
  int64_t seq = -1;  // the camera's frame number
};

class ScanModel {
 public:
  // A model downsampled at voxel_m (<= 0: every point kept), new surface counted within
  // new_surface_radius_m (> 0); `folder` empty: nothing is written.
  ScanModel(std::filesystem::path folder, double voxel_m, double new_surface_radius_m);

  // Continues the model written in folder/cloud.ply (a restarted service). False when there is
  // none. Throws naming the file when it cannot be read.
  bool restore();
  void clear();

  // Adds view `view`: `points` (object frame, the registered ones when accepted) with `normals`
  // (one per point, zero where none was found; empty: fitted here to the nearest points, facing
  // the camera) and `colours` (one per point; empty: none) seen from object_T_camera. Writes
  // frames/view_NNN.ply; when `merge`, counts its new surface against the model before it, merges
  // it and writes cloud.ply (coloured once any merged view had colours: each voxel the mean of its
  // points', kNoColour where only views without colour saw it). Throws std::invalid_argument when
  // the normals or colours are neither empty nor one per point. `model_index`: a k-d tree over
  // points() as they are now (revision() unchanged since it was built), for the new surface; none:
  // built here.
  ModelUpdate add_view(int view, const PointCloud& points, std::vector<Eigen::Vector3f> normals,
                       const Pose& object_T_camera, bool merge, const std::vector<Rgb>& colours = {},
                       const NeighbourIndex* model_index = nullptr);

  // Writes the view's depth image as depth/view_NNN.png (with `write_png`: 16-bit, in units of
  // 1 / depth_scale m: 0.1 mm where the camera's range fits 16 bits, else 1 mm) and
  // depth/view_NNN.json beside it (the intrinsics, also as Open3D's intrinsic_matrix, the depth
  // scale, range, frame number and the camera pose, `registered` or kinematic), and rewrites
  // trajectory.json. Returns "depth/view_NNN.png".
  // With `colour` (the frame's colour image as a JPEG and its camera), also writes it as
  // colour/view_NNN.jpg and gives its camera in the JSON's "colour" (size, intrinsics, lens,
  // depth_T_colour, the colour camera's pose in the object frame).
  using PngWriter = std::function<void(const std::vector<float>& depth_m, int width, int height, int units_per_metre,
                                       const std::string& path)>;
  struct ColourFile {
    ColourImage camera;          // its rgb is not used
    std::vector<uint8_t> jpeg;   // the image
  };
  std::string write_depth(int view, const DepthImage& image, const Pose& object_T_camera, bool registered,
                          const PngWriter& write_png, const ColourFile* colour = nullptr) const;

  // Writes trajectory.json: every depth image's camera as Open3D's PinholeCameraTrajectory
  // (read_pinhole_camera_trajectory; extrinsic = the object frame into the camera, column-major,
  // with the intrinsics), in view order, the views' file names in pbnbv_views. Kept up to date
  // by write_depth and when views move.
  void write_trajectory() const;

  // Meshes the frames of `views` (frames/view_NNN.ply in the folder, each with its camera pose
  // from the header; `camera` the camera that took them, `point_spacing_m` their downsampling
  // voxel) into mesh.ply and mesh.obj in the folder (core/surface/scan_mesh.hpp). Throws naming
  // the file or the cause when there is no folder, a frame is missing or unreadable, or the
  // frames give no triangles.
  // mesh.obj in `unit` (mesh.ply stays in metres).
  MeshSummary mesh(const std::vector<int>& views, const CameraIntrinsics& camera, double point_spacing_m,
                   LengthUnit unit = LengthUnit::kMetre) const;

  // Moves the model into another frame: new = q * old for its points, normals and camera poses,
  // and in the folder for cloud.ply, every frames/view_NNN.ply and every depth/view_NNN.json's
  // pose (the registration service ties the model's frame to the object's this way once the
  // mount's estimate says where it lies). Throws naming a file it cannot read or write.
  void move_frame(const Pose& q);
  // Moves one view's frame (frames/view_NNN.ply: points, normals, pose; depth/view_NNN.json's
  // pose) by q, then rebuilds the merged cloud from the frames of `merged` (in order) and
  // rewrites cloud.ply: a view placed again once its pose is known better. Needs a folder.
  void move_view(int view, const Pose& q, const std::vector<int>& merged);
  // Several views moved (each by its own q), then cloud.ply rebuilt once.
  void move_views(const std::vector<std::pair<int, Pose>>& moves, const std::vector<int>& merged);

  // A view's frame as written (frames/view_NNN.ply), taken back into its camera frame by the
  // pose in its header: its points and normals as the camera saw them (a restarted service's
  // mount estimate refits to them). Throws naming the file when there is none or it has no pose.
  void view_in_camera_frame(int view, PointCloud& points, std::vector<Eigen::Vector3f>& normals) const;

  const PointCloud& points() const { return model_.points; }
  const std::vector<Eigen::Vector3f>& normals() const { return model_.normals; }
  const std::vector<Rgb>& colours() const { return model_.colours; }  // empty, or one per point
  const std::vector<Pose>& camera_poses() const { return poses_; }
  const std::filesystem::path& folder() const { return folder_; }
  // Counts the changes of the merged cloud (every clear, restore, merge and move): what is derived
  // from points() is current while this has not changed.
  std::uint64_t revision() const { return revision_; }

 private:
  std::filesystem::path folder_;
  double voxel_m_;
  double radius_m_;
  VoxelCloud model_;  // normals: one per point (zero: none); colours: empty (no merged view had
                      // colours), or one per point
  std::vector<Pose> poses_;               // the merged views' camera poses, in order
  std::uint64_t revision_ = 0;
};

}  // namespace pbnbv
