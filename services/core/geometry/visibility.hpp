#pragma once
// Which ground-truth surface samples a camera view sees: the benchmark's observable coverage
// (eval/bench.cpp) and the oracle planner's gain (core/planning/planner.hpp plan_oracle).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/geometry/camera_model.hpp"
#include "core/base/pose.hpp"
#include "core/geometry/mesh.hpp"

namespace pbnbv {

// Surface samples with the outward unit normal of the triangle each lies on.
struct SurfaceSamples {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> normals;  // (b - a) x (c - a) normalised; zero on a zero-area one
};

// sample_surface(mesh, n, seed) with its face normals: the same points as
// CoverageEvaluator(mesh, {n, seed, ...}).samples().
// Throws std::invalid_argument for zero area or a triangle index out of range.
SurfaceSamples sample_surface_with_normals(const TriangleMesh& mesh, std::size_t n,
                                           std::uint64_t seed);

struct VisibilityParams {
  CameraIntrinsics camera;
  DepthRange range;
  double surface_offset_m = 0.001;  // the segment test starts this far from the sample towards
                                    // the camera (no self-hit); finite, >= 0
  double max_incidence_deg = 85.0;  // a sample seen at a grazing angle beyond this (angle between
                                    // the surface normal and the direction to the camera) does
                                    // not count; in [0, 90]; needs normals
  int threads = 0;                  // at most this many workers; 0: one per core (core/base/parallel.hpp)
};

// mask[i] = 1 when sample i is seen by at least one view (object_T_camera, optical frame): it
// projects inside the image (u in [-0.5, width - 0.5), v likewise: pixel centres at integers, as
// back_project and the twin's renderer), its planar depth is within the range, the surface faces
// the camera within max_incidence (if normals is empty the incidence test is skipped; a zero
// normal skips it for that sample), and the segment from the sample (moved surface_offset_m
// towards the camera) to the camera centre does not hit the mesh (MeshTree,
// core/geometry/mesh_tree.hpp).
// Each sample stops at the first view that sees it. No views: all zeros.
// Throws std::invalid_argument naming the argument for: normals size neither 0 nor samples size,
// a mesh without triangles or with a triangle index out of range, a non-finite sample, normal or
// view, bad camera/range (validate()), a bad offset, incidence or thread count.
std::vector<uint8_t> visible_from_any(const TriangleMesh& mesh,
                                      const std::vector<Eigen::Vector3d>& samples,
                                      const std::vector<Eigen::Vector3d>& normals,
                                      const std::vector<Pose>& views, const VisibilityParams& p);

// counts[j] = the samples view j sees (the rules of visible_from_any) that already_seen does not
// flag (already_seen[i] != 0: not counted; empty: none seen yet). The mesh's tree is built once;
// the views are shared out over the workers. Throws as visible_from_any, and for an
// already_seen whose size is neither 0 nor the number of samples.
std::vector<int> count_newly_visible(const TriangleMesh& mesh,
                                     const std::vector<Eigen::Vector3d>& samples,
                                     const std::vector<Eigen::Vector3d>& normals,
                                     const std::vector<Pose>& views,
                                     const std::vector<uint8_t>& already_seen,
                                     const VisibilityParams& p);

}  // namespace pbnbv
