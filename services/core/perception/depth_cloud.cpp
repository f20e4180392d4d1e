#include "core/perception/cloud_filter.hpp"
#include "core/perception/depth_cloud.hpp"
#include "core/perception/neighbours.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>
#include <stdexcept>

namespace pbnbv {

PointCloud depth_to_object_cloud(const std::vector<float>& depth_m, const CameraIntrinsics& k,
                                 const DepthRange& range, const Pose& object_T_camera,
                                 const CloudCrop& crop, double voxel_m, CloudStats* stats) {
  k.validate();
  if (depth_m.size() != static_cast<std::size_t>(k.width) * k.height) {
    throw std::invalid_argument("depth image has " + std::to_string(depth_m.size()) +
                                " pixels, intrinsics say " + std::to_string(k.width) + "x" +
                                std::to_string(k.height));
  }
  CloudStats s;
  std::vector<Eigen::Vector3d> kept;
  kept.reserve(depth_m.size() / 4);
  const Eigen::Matrix3d r = object_T_camera.linear();
  const Eigen::Vector3d t = object_T_camera.translation();
  const double floor_z = crop.ground_z_m + crop.ground_clearance_m;
  // Readings near the turntable top, for its plane: within 15 mm (beyond any calibrated rig's
  // error and any camera's noise at its range) either side of where the kinematics put it.
  constexpr double kGroundBand = 0.015;
  std::vector<Eigen::Vector3d> ground;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const double z = depth_m[static_cast<std::size_t>(v) * k.width + u];
      if (!std::isfinite(z) || z < range.min_m || z > range.max_m) continue;
      ++s.num_valid_pixels;
      const Eigen::Vector3d p = r * back_project(k, u, v, z) + t;
      if (crop.fit_ground && std::abs(p.z() - crop.ground_z_m) < kGroundBand) ground.push_back(p);
      if ((!crop.volume_m.isEmpty() && !crop.volume_m.contains(p)) || p.z() <= floor_z) {
        ++s.num_cropped;
        continue;
      }
      kept.push_back(p);
    }
  }
  Eigen::Vector3d abc;
  double sigma = 0;
  const bool fitted = crop.fit_ground && fit_ground_plane(ground, &abc, &sigma);
  if (fitted) {
    s.ground_points = static_cast<int>(ground.size());
    s.ground_offset_m = abc.z() - crop.ground_z_m;
    s.ground_sigma_m = sigma;
    s.ground_abc = abc;
  }
  PointCloud cloud;
  cloud.reserve(kept.size());
  for (const Eigen::Vector3d& p : kept) {
    if (fitted && p.z() - (abc.x() * p.x() + abc.y() * p.y() + abc.z()) <= crop.ground_clearance_m + 3 * sigma) {
      ++s.num_cropped;
      continue;
    }
    cloud.emplace_back(p.cast<float>());
  }
  if (stats) *stats = s;
  return voxel_downsample(cloud, voxel_m);
}

bool fit_ground_plane(const std::vector<Eigen::Vector3d>& points, Eigen::Vector3d* abc, double* sigma_m) {
  constexpr std::size_t kMinPoints = 50;
  if (points.size() < kMinPoints) return false;
  std::vector<char> use(points.size(), 1);
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  double sigma = 0;
  std::vector<double> residual(points.size());
  for (int iteration = 0; iteration < 4; ++iteration) {
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    std::size_t n = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (!use[i]) continue;
      const Eigen::Vector3d row(points[i].x(), points[i].y(), 1.0);
      ata += row * row.transpose();
      atb += row * points[i].z();
      ++n;
    }
    if (n < kMinPoints) return false;
    x = ata.ldlt().solve(atb);
    if (!x.allFinite()) return false;
    for (std::size_t i = 0; i < points.size(); ++i) {
      residual[i] = points[i].z() - (x.x() * points[i].x() + x.y() * points[i].y() + x.z());
    }
    std::vector<double> a;
    a.reserve(n);
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (use[i]) a.push_back(std::abs(residual[i]));
    }
    std::nth_element(a.begin(), a.begin() + a.size() / 2, a.end());
    sigma = 1.4826 * a[a.size() / 2];
    const double keep = std::max(3 * sigma, 1e-6);
    for (std::size_t i = 0; i < points.size(); ++i) use[i] = std::abs(residual[i]) <= keep;
  }
  // A turntable top tilted by more than 5 degrees is not what the readings show.
  if (std::hypot(x.x(), x.y()) > std::tan(5.0 * 3.14159265358979323846 / 180.0)) return false;
  *abc = x;
  *sigma_m = sigma;
  return true;
}

std::vector<Eigen::Vector3f> depth_normals(const PointCloud& points, const std::vector<float>& depth_m,
                                           const CameraIntrinsics& k, const Pose& object_T_camera, int step_px) {
  std::vector<Eigen::Vector3f> normals(points.size(), Eigen::Vector3f::Zero());
  if (depth_m.size() != static_cast<std::size_t>(k.width) * k.height) {
    throw std::invalid_argument("depth_normals: the depth image has " + std::to_string(depth_m.size()) +
                                " pixels, the intrinsics " + std::to_string(k.width) + " x " + std::to_string(k.height));
  }
  const Pose camera_T_object = object_T_camera.inverse();
  const Eigen::Matrix3d R = object_T_camera.linear();
  auto depth_at = [&](int u, int v) -> double {
    if (u < 0 || v < 0 || u >= k.width || v >= k.height) return 0.0;
    const float z = depth_m[static_cast<std::size_t>(v) * k.width + u];
    return (std::isfinite(z) && z > 0.0f) ? z : 0.0;
  };
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d q = camera_T_object * points[i].cast<double>();
    if (!(q.z() > 0.0)) continue;
    const int u = static_cast<int>(std::lround(k.fx * q.x() / q.z() + k.cx));
    const int v = static_cast<int>(std::lround(k.fy * q.y() / q.z() + k.cy));
    double zc = depth_at(u, v);
    if (zc == 0.0) zc = q.z();
    const Eigen::Vector3d c = back_project(k, u, v, zc);
    // A neighbour's point, or nothing when it has no reading or lies across a depth jump.
    auto near = [&](int du, int dv, Eigen::Vector3d& p) {
      const double z = depth_at(u + du, v + dv);
      if (z == 0.0 || std::abs(z - zc) > 0.05 * zc) return false;
      p = back_project(k, u + du, v + dv, z);
      return true;
    };
    auto difference = [&](int du, int dv, Eigen::Vector3d& d) {
      Eigen::Vector3d a, b;
      const bool fa = near(du, dv, a), fb = near(-du, -dv, b);
      if (fa && fb) d = a - b;
      else if (fa) d = a - c;
      else if (fb) d = c - b;
      else return false;
      return true;
    };
    Eigen::Vector3d dx, dy;
    if (!difference(step_px, 0, dx) || !difference(0, step_px, dy)) continue;
    Eigen::Vector3d n = dx.cross(dy);
    if (!(n.norm() > 0.0)) continue;
    n.normalize();
    if (n.dot(-c) < 0.0) n = -n;  // towards the camera (its centre is the optical frame's origin)
    normals[i] = (R * n).cast<float>();
  }
  return normals;
}

std::vector<Eigen::Vector3f> neighbour_normals(const PointCloud& points, const Eigen::Vector3d& camera_m, int neighbours) {
  SurfaceNormals s = estimate_normals(points, neighbours);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!s.valid[i]) {
      s.normals[i] = Eigen::Vector3f::Zero();
      continue;
    }
    if (s.normals[i].dot(camera_m.cast<float>() - points[i]) < 0.0f) s.normals[i] = -s.normals[i];
  }
  return s.normals;
}

namespace {

struct VoxelKey {
  int64_t x, y, z;
  bool operator==(const VoxelKey& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct VoxelKeyHash {
  std::size_t operator()(const VoxelKey& k) const {
    return std::hash<int64_t>()(k.x * 73856093LL ^ k.y * 19349663LL ^ k.z * 83492791LL);
  }
};
VoxelKey voxel_key(const Eigen::Vector3f& p, double voxel_m) {
  return VoxelKey{static_cast<int64_t>(std::floor(p.x() / voxel_m)), static_cast<int64_t>(std::floor(p.y() / voxel_m)),
                  static_cast<int64_t>(std::floor(p.z() / voxel_m))};
}

}  // namespace

std::vector<Eigen::Vector3f> voxel_normals(const PointCloud& points, const std::vector<Eigen::Vector3f>& normals,
                                           const PointCloud& downsampled, double voxel_m) {
  if (!(voxel_m > 0)) {  // nothing was merged: each point's own normal
    std::vector<Eigen::Vector3f> out(downsampled.size(), Eigen::Vector3f::Zero());
    for (std::size_t i = 0; i < out.size() && i < normals.size(); ++i) {
      if (normals[i].norm() > 0.0f) out[i] = normals[i].normalized();
    }
    return out;
  }
  std::unordered_map<VoxelKey, Eigen::Vector3f, VoxelKeyHash> sums;
  for (std::size_t i = 0; i < points.size() && i < normals.size(); ++i) {
    if (!points[i].allFinite() || normals[i].isZero()) continue;
    auto [it, added] = sums.try_emplace(voxel_key(points[i], voxel_m), Eigen::Vector3f::Zero());
    it->second += normals[i];
  }
  std::vector<Eigen::Vector3f> out(downsampled.size(), Eigen::Vector3f::Zero());
  for (std::size_t i = 0; i < downsampled.size(); ++i) {
    const auto it = sums.find(voxel_key(downsampled[i], voxel_m));
    if (it != sums.end() && it->second.norm() > 0.0f) out[i] = it->second.normalized();
  }
  return out;
}

std::vector<Rgb> voxel_colours(const PointCloud& points, const std::vector<Rgb>& colours, const PointCloud& downsampled,
                               double voxel_m) {
  if (!(voxel_m > 0)) return colours;  // nothing was merged: one colour per point as it came
  std::unordered_map<VoxelKey, Eigen::Vector4d, VoxelKeyHash> sums;  // r g b count
  for (std::size_t i = 0; i < points.size() && i < colours.size(); ++i) {
    if (!points[i].allFinite()) continue;
    auto [it, added] = sums.try_emplace(voxel_key(points[i], voxel_m), Eigen::Vector4d::Zero());
    it->second += Eigen::Vector4d(colours[i][0], colours[i][1], colours[i][2], 1.0);
  }
  std::vector<Rgb> out(downsampled.size(), kNoColour);
  for (std::size_t i = 0; i < downsampled.size(); ++i) {
    const auto it = sums.find(voxel_key(downsampled[i], voxel_m));
    if (it == sums.end()) continue;
    const Eigen::Vector4d& s = it->second;
    for (int c = 0; c < 3; ++c) out[i][static_cast<std::size_t>(c)] = static_cast<uint8_t>(std::lround(s[c] / s[3]));
  }
  return out;
}

}  // namespace pbnbv

namespace pbnbv {

namespace {

using VoxelIndex = std::array<int64_t, 3>;

// The full computation: the model's points followed by the new ones, downsampled, their normals
// and colours averaged into the voxels.
void merge_by_downsampling(VoxelCloud& model, const PointCloud& points, const std::vector<Eigen::Vector3f>& normals,
                           const std::vector<Rgb>& colours, double voxel_m, bool coloured) {
  PointCloud grown = model.points;
  grown.insert(grown.end(), points.begin(), points.end());
  std::vector<Eigen::Vector3f> grown_normals = model.normals;
  grown_normals.insert(grown_normals.end(), normals.begin(), normals.end());
  std::vector<Rgb> grown_colours;
  if (coloured) {
    grown_colours = model.colours;
    grown_colours.resize(model.points.size(), kNoColour);
    if (colours.empty()) {
      grown_colours.resize(grown.size(), kNoColour);
    } else {
      grown_colours.insert(grown_colours.end(), colours.begin(), colours.end());
    }
  }
  model.points = voxel_downsample(grown, voxel_m);
  model.normals = voxel_normals(grown, grown_normals, model.points, voxel_m);
  if (coloured) model.colours = voxel_colours(grown, grown_colours, model.points, voxel_m);
}

// One voxel's sums, in the order voxel_downsample, voxel_normals and voxel_colours add.
struct VoxelSum {
  double x = 0, y = 0, z = 0;
  std::size_t count = 0;
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();
  Eigen::Vector4d colour = Eigen::Vector4d::Zero();  // r g b count
  void add(const Eigen::Vector3f& p, const Eigen::Vector3f& n, const Rgb& c) {
    x += p.x();
    y += p.y();
    z += p.z();
    ++count;
    if (!n.isZero()) normal += n;
    colour += Eigen::Vector4d(c[0], c[1], c[2], 1.0);
  }
};

}  // namespace

void merge_into_voxels(VoxelCloud& model, const PointCloud& points, const std::vector<Eigen::Vector3f>& normals,
                       const std::vector<Rgb>& colours, double voxel_m) {
  if (normals.size() != points.size() || (!colours.empty() && colours.size() != points.size())) {
    throw std::invalid_argument("merge_into_voxels: " + std::to_string(normals.size()) + " normals and " +
                                std::to_string(colours.size()) + " colours for " + std::to_string(points.size()) +
                                " points (one each, or no colours)");
  }
  if (model.normals.size() != model.points.size() ||
      (!model.colours.empty() && model.colours.size() != model.points.size())) {
    throw std::invalid_argument("merge_into_voxels: a model of " + std::to_string(model.points.size()) + " points with " +
                                std::to_string(model.normals.size()) + " normals and " +
                                std::to_string(model.colours.size()) + " colours");
  }
  const bool coloured = !model.colours.empty() || !colours.empty();
  if (!(voxel_m > 0) || !std::isfinite(voxel_m)) {  // nothing is merged: every point kept
    merge_by_downsampling(model, points, normals, colours, voxel_m, coloured);
    return;
  }
  // The model's voxels: one point each, in increasing order, or the full computation.
  const std::size_t n = model.points.size();
  std::vector<VoxelIndex> model_index(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (!voxel_index(model.points[i], voxel_m, model_index[i].data()) || (i > 0 && !(model_index[i - 1] < model_index[i]))) {
      merge_by_downsampling(model, points, normals, colours, voxel_m, coloured);
      return;
    }
  }
  // The new points by voxel, each voxel's in their order (as the downsampling sums them).
  struct New {
    VoxelIndex q;
    uint32_t index;
  };
  std::vector<New> added;
  added.reserve(points.size());
  for (std::size_t j = 0; j < points.size(); ++j) {
    New a;
    if (voxel_index(points[j], voxel_m, a.q.data())) added.push_back({a.q, static_cast<uint32_t>(j)});
  }
  std::stable_sort(added.begin(), added.end(), [](const New& a, const New& b) { return a.q < b.q; });

  VoxelCloud out;
  out.points.reserve(n + added.size());
  out.normals.reserve(n + added.size());
  if (coloured) out.colours.reserve(n + added.size());
  const auto model_colour = [&](std::size_t i) { return model.colours.empty() ? kNoColour : model.colours[i]; };
  const auto new_colour = [&](std::size_t j) { return colours.empty() ? kNoColour : colours[j]; };
  const auto emit = [&](const VoxelSum& s) {
    const double inv = 1.0 / static_cast<double>(s.count);
    out.points.emplace_back(static_cast<float>(s.x * inv), static_cast<float>(s.y * inv), static_cast<float>(s.z * inv));
    out.normals.push_back(s.normal.norm() > 0.0f ? Eigen::Vector3f(s.normal.normalized()) : Eigen::Vector3f::Zero());
    if (coloured) {
      Rgb c;
      for (int k = 0; k < 3; ++k) c[static_cast<std::size_t>(k)] = static_cast<uint8_t>(std::lround(s.colour[k] / s.colour[3]));
      out.colours.push_back(c);
    }
  };
  std::size_t i = 0, j = 0;
  while (i < n || j < added.size()) {
    const bool take_model = i < n && (j == added.size() || !(added[j].q < model_index[i]));
    const VoxelIndex q = take_model ? model_index[i] : added[j].q;
    VoxelSum s;
    if (take_model) {
      s.add(model.points[i], model.normals[i], model_colour(i));
      ++i;
    }
    const bool grows = j < added.size() && added[j].q == q;
    for (; j < added.size() && added[j].q == q; ++j) s.add(points[added[j].index], normals[added[j].index], new_colour(added[j].index));
    emit(s);
    VoxelIndex centre;
    if (grows && (!voxel_index(out.points.back(), voxel_m, centre.data()) || centre != q)) {
      // A centroid across its voxel's face: its normal and colour would be looked up in the
      // neighbour's sums, as the full computation does.
      merge_by_downsampling(model, points, normals, colours, voxel_m, coloured);
      return;
    }
  }
  model = std::move(out);
}

}  // namespace pbnbv
