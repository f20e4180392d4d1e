#pragma once
// A surface mesh from registered depth frames. Two methods:
//   - TSDF fusion: each frame's points are splatted into a depth image of its camera (nearest
//     point per pixel, a pixel about as wide as the frames' point spacing), every voxel near the
//     frame's points gets the point-to-plane distance to its pixel's point (the normal from the
//     image neighbours' points, turned to the camera, the neighbours as many pixels apart as the
//     frame's measured depth noise needs (tsdf_frame_noise); along the ray where there is none),
//     truncated and averaged over the frames; marching cubes (PCL's tables) extracts the zero
//     level where every corner was seen. Unseen surface stays open (holes).
//   - Poisson (PCL) on all the frames' points with their normals (k nearest neighbours, turned to
//     the camera): always closed.
// The mesh's topology (boundary loops, watertightness, volume) is in mesh_topology.hpp.
#include <vector>

#include "core/base/pose.hpp"
#include "core/geometry/camera_model.hpp"
#include "core/geometry/colour_image.hpp"
#include "core/geometry/mesh.hpp"
#include "core/geometry/point_cloud.hpp"
#include "core/surface/surface_options.hpp"

namespace pbnbv {

// One registered frame: its points (object frame) and the camera that saw them.
struct SurfaceFrame {
  PointCloud points;
  Pose object_T_camera = Pose::Identity();
  std::vector<Rgb> colours;  // one per point, or empty (none): the mesh's vertex colours come from them
};

struct SurfaceSettings {
  MeshMethod method = kMeshMethod.value;
  double voxel_m = kMeshVoxel.value;
  double truncation_voxels = kMeshTruncation.value;
  int poisson_depth = kPoissonDepth.value;
  int normal_neighbours = kMeshNormalNeighbours.value;
  double fill_holes_m = kMeshFillHoles.value;  // holes with a shorter rim are closed (scan_mesh)
  CameraIntrinsics camera;
  double point_spacing_m = 0;  // the frames' downsampling voxel (0: one point per pixel)
  void validate() const;       // throws std::invalid_argument naming the bad setting
};

// What the fusion did, for the record.
struct SurfaceStats {
  std::size_t frames = 0, points = 0;
  std::size_t voxels = 0;   // TSDF voxels allocated
  int image_scale = 1;      // TSDF: camera pixels per depth-image pixel (median over frames)
  double depth_noise_m = 0; // TSDF: the frames' measured depth noise (median over frames)
  int normal_step = 1;      // TSDF: the normals' neighbours this many depth-image pixels apart (median)
};

// A frame's depth noise as the TSDF measures it on the frame's own depth image (the splat): the
// median absolute second difference of three neighbouring depths along a row, over 6^(1/2)
// (robust: depth edges and missing pixels left out; a smooth surface's curvature adds little);
// and the step its normals take: neighbours at least 4 sigma apart (noise tilts a normal by about
// a quarter radian), 1 to 8 pixels; 1 for an exact camera.
struct FrameNoise {
  double sigma_m = 0;  // the measured depth noise (0: too few neighbouring pixels to tell)
  double pixel_m = 0;  // a depth-image pixel's width at the frame's median depth
  int normal_step = 1;
};
FrameNoise tsdf_frame_noise(const SurfaceFrame& f, const SurfaceSettings& s);

// The mesh of the frames by `s.method`, triangles counter-clockwise seen from outside (the
// cameras' side). Throws std::invalid_argument when there are no points or a setting is bad.
TriangleMesh build_surface(const std::vector<SurfaceFrame>& frames, const SurfaceSettings& s,
                           SurfaceStats* stats = nullptr);
TriangleMesh fuse_tsdf(const std::vector<SurfaceFrame>& frames, const SurfaceSettings& s,
                       SurfaceStats* stats = nullptr);
TriangleMesh poisson_surface(const std::vector<SurfaceFrame>& frames, const SurfaceSettings& s,
                             SurfaceStats* stats = nullptr);

}  // namespace pbnbv
