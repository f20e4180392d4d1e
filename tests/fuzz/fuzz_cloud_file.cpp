// libFuzzer target: a point cloud file as the evaluation and a user's --cloud read it. The first
// byte picks the reader: even, PLY (read_ply with its normals and camera_pose comments); odd,
// PCD (read_pcd). The rest is the file. What a reader accepts must hold together: one normal per
// point when there are normals, unit quaternions in the camera poses.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "core/io/cloud_file.hpp"
#include "core/io/pcd_file.hpp"
#include "fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const bool ply = data[0] % 2 == 0;
  const std::string path = pbnbv::fuzz::write_input(pbnbv::fuzz::as_text(data + 1, size - 1), ply ? "cloud.ply" : "cloud.pcd");
  try {
    if (ply) {
      pbnbv::CloudExtras extras;
      const pbnbv::PointCloud cloud = pbnbv::read_ply(path, extras);
      if (!extras.normals.empty() && extras.normals.size() != cloud.size()) {
        std::fprintf(stderr, "read_ply: %zu normals for %zu points\n", extras.normals.size(), cloud.size());
        std::abort();
      }
      for (const pbnbv::Pose& p : extras.camera_poses) {
        if (!p.matrix().allFinite()) {
          std::fprintf(stderr, "read_ply accepted a non-finite camera pose\n");
          std::abort();
        }
      }
    } else {
      pbnbv::read_pcd(path);
    }
  } catch (const std::exception&) {  // refused, naming the file
  }
  return 0;
}
