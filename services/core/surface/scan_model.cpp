#include "core/surface/scan_model.hpp"
#include "core/base/version.hpp"

#include <algorithm>
#include <chrono>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "core/base/format.hpp"
#include "core/io/cloud_file.hpp"
#include "core/io/json.hpp"
#include "core/perception/depth_cloud.hpp"
#include "core/perception/neighbours.hpp"
#include "core/surface/scan_mesh.hpp"

namespace fs = std::filesystem;

namespace pbnbv {

ScanModel::ScanModel(fs::path folder, double voxel_m, double new_surface_radius_m)
    : folder_(std::move(folder)), voxel_m_(voxel_m), radius_m_(new_surface_radius_m) {
  if (!(radius_m_ > 0)) {
    throw std::invalid_argument("the new-surface radius must be positive, not " + std::to_string(radius_m_));
  }
}

void ScanModel::clear() {
  ++revision_;
  model_.points.clear();
  model_.normals.clear();
  model_.colours.clear();
  poses_.clear();
}

bool ScanModel::restore() {
  const fs::path path = folder_ / "cloud.ply";
  if (folder_.empty() || !fs::exists(path)) return false;
  ++revision_;
  CloudExtras extras;
  model_.points = read_ply(path.string(), extras);
  poses_ = extras.camera_poses;
  model_.normals = extras.normals;
  model_.colours = extras.colours;
  if (model_.normals.size() != model_.points.size()) {
    // A cloud.ply written before normals were: fit them to the neighbours, facing away from the
    // cloud's centre (the cameras look at the object from outside).
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const auto& p : model_.points) centre += p.cast<double>();
    if (!model_.points.empty()) centre /= static_cast<double>(model_.points.size());
    model_.normals = neighbour_normals(model_.points, centre);
    for (auto& n : model_.normals) n = -n;
  }
  return true;
}

ModelUpdate ScanModel::add_view(int view, const PointCloud& points, std::vector<Eigen::Vector3f> normals,
                                const Pose& object_T_camera, bool merge, const std::vector<Rgb>& colours,
                                const NeighbourIndex* model_index) {
  const auto t0 = std::chrono::steady_clock::now();
  ModelUpdate u;
  if (!colours.empty() && colours.size() != points.size()) {
    throw std::invalid_argument("view " + std::to_string(view + 1) + ": " + std::to_string(colours.size()) +
                                " colours for " + std::to_string(points.size()) + " points");
  }
  if (normals.empty() && !points.empty()) {
    normals = neighbour_normals(points, object_T_camera.translation());
  } else if (normals.size() != points.size()) {
    throw std::invalid_argument("view " + std::to_string(view + 1) + ": " + std::to_string(normals.size()) +
                                " normals for " + std::to_string(points.size()) + " points");
  } else {
    u.normals_from_depth = true;
  }
  if (!folder_.empty()) {
    u.frame_file = frame_file_of(view);
    fs::create_directories(folder_ / "frames");
    write_ply(points, (folder_ / u.frame_file).string(), CloudExtras{normals, {object_T_camera}, colours});
  }
  if (merge) {
    u.new_surface = model_index ? new_surface(points, *model_index, radius_m_) : new_surface(points, model_.points, radius_m_);
    merge_into_voxels(model_, points, normals, colours, voxel_m_);  // sizes checked above
    ++revision_;
    poses_.push_back(object_T_camera);
    if (!folder_.empty()) {
      write_ply(model_.points, (folder_ / "cloud.ply").string(), CloudExtras{model_.normals, poses_, model_.colours});
    }
  }
  u.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return u;
}

namespace {

PointCloud moved(const PointCloud& points, const Pose& q) {
  PointCloud out;
  out.reserve(points.size());
  for (const auto& p : points) out.emplace_back((q * p.cast<double>()).cast<float>());
  return out;
}

std::vector<Eigen::Vector3f> turned(const std::vector<Eigen::Vector3f>& normals, const Pose& q) {
  const Eigen::Matrix3f r = q.linear().cast<float>();
  std::vector<Eigen::Vector3f> out;
  out.reserve(normals.size());
  for (const auto& n : normals) out.emplace_back(r * n);
  return out;
}

// A frame file (points, normals, camera pose) moved by q, rewritten in place.
void move_frame_file(const fs::path& file, const Pose& q) {
  CloudExtras extras;
  const PointCloud points = read_ply(file.string(), extras);
  for (Pose& pose : extras.camera_poses) pose = q * pose;
  extras.normals = turned(extras.normals, q);
  write_ply(moved(points, q), file.string(), extras);
}

// A depth image's JSON: its camera pose moved by q (a file without one is left as it is).
void move_depth_pose(const fs::path& file, const Pose& q) {
  nlohmann::json j = read_json(file.string());
  if (!j.contains("object_T_camera")) return;
  j["object_T_camera"] = to_json(q * pose_from_json(j["object_T_camera"], file.string()));
  write_json_atomic(j, file.string());
}

// The depth images' scale (units per metre): 0.1 mm, the pipeline's resolution, where the camera's
// range fits 16 bits (6.5535 m), else 1 mm.
int depth_png_scale(const DepthRange& range) { return range.max_m <= 6.5535 ? 10000 : 1000; }

// Open3D's column-major 3x3 intrinsic matrix.
nlohmann::json intrinsic_matrix(const CameraIntrinsics& k) { return {k.fx, 0.0, 0.0, 0.0, k.fy, 0.0, k.cx, k.cy, 1.0}; }

}  // namespace

void ScanModel::write_trajectory() const {
  if (folder_.empty() || !fs::is_directory(folder_ / "depth")) return;
  std::vector<fs::path> views;
  for (const auto& entry : fs::directory_iterator(folder_ / "depth")) {
    if (entry.path().extension() == ".json" && entry.path().stem().string().rfind("view_", 0) == 0) views.push_back(entry.path());
  }
  std::sort(views.begin(), views.end());
  nlohmann::json parameters = nlohmann::json::array();
  nlohmann::json names = nlohmann::json::array();
  for (const fs::path& file : views) {
    const nlohmann::json j = read_json(file.string());
    if (!j.contains("object_T_camera")) continue;
    // Open3D's extrinsic: the world (here the object frame) into the camera, column-major 4x4.
    const Eigen::Matrix4d extrinsic = pose_from_json(j["object_T_camera"], file.string()).inverse().matrix();
    std::vector<double> columns(extrinsic.data(), extrinsic.data() + 16);
    const CameraIntrinsics k{j.at("width").get<int>(), j.at("height").get<int>(), j.at("fx").get<double>(),
                             j.at("fy").get<double>(), j.at("cx").get<double>(), j.at("cy").get<double>()};
    parameters.push_back({{"class_name", "PinholeCameraParameters"},
                          {"extrinsic", columns},
                          {"intrinsic", {{"width", k.width}, {"height", k.height}, {"intrinsic_matrix", intrinsic_matrix(k)}}},
                          {"version_major", 1},
                          {"version_minor", 0}});
    names.push_back("depth/" + file.filename().string());
  }
  const nlohmann::json trajectory = {{"class_name", "PinholeCameraTrajectory"},
                                     {"parameters", parameters},
                                     {"version_major", 1},
                                     {"version_minor", 0},
                                     {"pbnbv_version", std::string(pbnbv_version())},
                                     {"pbnbv_views", names},
                                     {"pbnbv_frame", "object (the extrinsics map it into each camera)"}};
  write_json_atomic(trajectory, (folder_ / "trajectory.json").string());
}

void ScanModel::move_frame(const Pose& q) {
  ++revision_;
  model_.points = moved(model_.points, q);
  model_.normals = turned(model_.normals, q);
  for (Pose& pose : poses_) pose = q * pose;
  if (folder_.empty()) return;
  write_ply(model_.points, (folder_ / "cloud.ply").string(), CloudExtras{model_.normals, poses_, model_.colours});
  if (fs::is_directory(folder_ / "frames")) {
    for (const auto& entry : fs::directory_iterator(folder_ / "frames")) {
      if (entry.path().extension() == ".ply") move_frame_file(entry.path(), q);
    }
  }
  if (fs::is_directory(folder_ / "depth")) {
    for (const auto& entry : fs::directory_iterator(folder_ / "depth")) {
      if (entry.path().extension() == ".json") move_depth_pose(entry.path(), q);
    }
  }
  write_trajectory();
}

void ScanModel::move_view(int view, const Pose& q, const std::vector<int>& merged) { move_views({{view, q}}, merged); }

void ScanModel::move_views(const std::vector<std::pair<int, Pose>>& moves, const std::vector<int>& merged) {
  if (folder_.empty()) throw std::invalid_argument("no scan folder: a view cannot be placed again");
  for (const auto& [view, q] : moves) {
    move_frame_file(folder_ / frame_file_of(view), q);
    const fs::path depth = folder_ / "depth" / view_file(view, "json");
    if (fs::exists(depth)) move_depth_pose(depth, q);
  }
  write_trajectory();
  PointCloud all;
  std::vector<Eigen::Vector3f> all_normals;
  std::vector<Rgb> all_colours;
  bool coloured = false;
  std::vector<Pose> poses;
  for (const int v : merged) {
    CloudExtras e;
    const PointCloud p = read_ply((folder_ / frame_file_of(v)).string(), e);
    all.insert(all.end(), p.begin(), p.end());
    e.normals.resize(p.size(), Eigen::Vector3f::Zero());
    all_normals.insert(all_normals.end(), e.normals.begin(), e.normals.end());
    coloured = coloured || !e.colours.empty();
    e.colours.resize(p.size(), kNoColour);
    all_colours.insert(all_colours.end(), e.colours.begin(), e.colours.end());
    if (!e.camera_poses.empty()) poses.push_back(e.camera_poses.front());
  }
  ++revision_;
  model_ = VoxelCloud{};
  merge_into_voxels(model_, all, all_normals, coloured ? all_colours : std::vector<Rgb>{}, voxel_m_);
  poses_ = poses;
  write_ply(model_.points, (folder_ / "cloud.ply").string(), CloudExtras{model_.normals, poses_, model_.colours});
}

void ScanModel::view_in_camera_frame(int view, PointCloud& points, std::vector<Eigen::Vector3f>& normals) const {
  if (folder_.empty()) throw std::invalid_argument("no scan folder: view " + std::to_string(view) + " has no file");
  const fs::path file = folder_ / frame_file_of(view);
  CloudExtras extras;
  points = read_ply(file.string(), extras);
  if (extras.camera_poses.size() != 1) throw std::invalid_argument(file.string() + ": no camera pose in its header");
  const Pose camera_T_object = extras.camera_poses.front().inverse();
  const Eigen::Matrix3f turn = camera_T_object.linear().cast<float>();
  for (auto& p : points) p = (camera_T_object * p.cast<double>()).cast<float>();
  normals = std::move(extras.normals);
  normals.resize(points.size(), Eigen::Vector3f::Zero());
  for (auto& n : normals) n = turn * n;
}

MeshSummary ScanModel::mesh(const std::vector<int>& views, const CameraIntrinsics& camera, double point_spacing_m,
                            LengthUnit unit) const {
  if (folder_.empty()) throw std::invalid_argument("no scan folder to mesh in");
  std::vector<SurfaceFrame> frames;
  for (const int v : views) {
    const fs::path file = folder_ / "frames" / view_file(v, "ply");
    CloudExtras extras;
    PointCloud points = read_ply(file.string(), extras);
    if (extras.camera_poses.size() != 1) throw std::invalid_argument(file.string() + ": no camera pose in its header");
    frames.push_back({std::move(points), extras.camera_poses.front(), std::move(extras.colours)});
  }
  SurfaceSettings s;
  s.camera = camera;
  s.point_spacing_m = point_spacing_m;
  return mesh_scan(folder_, frames, s, false, unit);
}

std::string ScanModel::write_depth(int view, const DepthImage& image, const Pose& object_T_camera, bool registered,
                                   const PngWriter& write_png, const ColourFile* colour) const {
  if (folder_.empty() || !image.depth_m) return "";
  fs::create_directories(folder_ / "depth");
  const std::string png = view_file(view, "png");
  const CameraIntrinsics& k = image.intrinsics;
  const int scale = depth_png_scale(image.range);
  write_png(*image.depth_m, k.width, k.height, scale, (folder_ / depth_file_of(view)).string());
  const nlohmann::json intrinsics = {
      {"image", png},
      {"width", k.width},
      {"height", k.height},
      {"fx", k.fx},
      {"fy", k.fy},
      {"cx", k.cx},
      {"cy", k.cy},
      {"intrinsic_matrix", intrinsic_matrix(k)},
      {"depth_scale", scale},
      {"depth_units", "value / depth_scale = planar depth along the optical axis, m; 0 = no reading"},
      {"depth_min_m", image.range.min_m},
      {"depth_max_m", image.range.max_m},
      {"depth_frame_seq", image.seq},
      {"object_T_camera", to_json(object_T_camera)},
      {"pose_frame", "object"},
      {"registered", registered}};
  nlohmann::json j = intrinsics;
  if (colour && !colour->jpeg.empty()) {
    fs::create_directories(folder_ / "colour");
    const std::string jpg = view_file(view, "jpg");
    write_text_atomic(std::string(colour->jpeg.begin(), colour->jpeg.end()), (folder_ / "colour" / jpg).string());
    const ColourImage& c = colour->camera;
    const CameraIntrinsics& ck = c.intrinsics;
    const std::array<double, 5> d = c.distortion.coefficients();
    j["colour"] = {{"image", "../colour/" + jpg},
                   {"width", ck.width},
                   {"height", ck.height},
                   {"fx", ck.fx},
                   {"fy", ck.fy},
                   {"cx", ck.cx},
                   {"cy", ck.cy},
                   {"intrinsic_matrix", intrinsic_matrix(ck)},
                   {"distortion_k1_k2_p1_p2_k3", d},
                   {"depth_T_colour", to_json(c.depth_T_colour)}};
  }
  write_json_atomic(j, (folder_ / "depth" / view_file(view, "json")).string());
  write_trajectory();
  return depth_file_of(view);
}

}  // namespace pbnbv
