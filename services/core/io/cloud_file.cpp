// Point cloud files: read by CGAL's point-set PLY reader, written by our own (see write_ply).
#include "core/io/cloud_file.hpp"
#include "core/base/version.hpp"
#include "core/io/json.hpp"

#include <CGAL/IO/read_ply_points.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/property_map.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <utility>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/base/format.hpp"
#include "core/io/file_checks.hpp"

namespace pbnbv {

namespace {

// Whether the machine stores numbers little-endian (PLY's binary_little_endian byte order).
bool host_little_endian() {
  const std::uint16_t one = 1;
  unsigned char c;
  std::memcpy(&c, &one, 1);
  return c == 1;
}

}  // namespace

// Our own writer, kept: on 300k points (mesh_file_bench BM_WritePly, CPU time, medians) it takes
// 1.4-1.8 ms against 18.4-18.7 ms for CGAL's write_PLY and 34-39 ms for PCL's savePLYFileBinary,
// and the coordinator writes every view's frame and the grown cloud.ply in its "accumulate"
// stage (0.010 s per view in the README). PCL's writer would also bring pcl_io and VTK into the
// coordinator: 76 shared libraries instead of 15, and 29 ms more per process start.
void write_ply(const PointCloud& cloud, const std::string& path, const CloudExtras& extras) {
  const char* ctx = "write_ply";
  const bool normals = !extras.normals.empty();
  if (normals && extras.normals.size() != cloud.size()) {
    throw std::invalid_argument(fmt::format("{}: {}: {} normals for {} points", ctx, path, extras.normals.size(), cloud.size()));
  }
  const bool colours = !extras.colours.empty();
  if (colours && extras.colours.size() != cloud.size()) {
    throw std::invalid_argument(fmt::format("{}: {}: {} colours for {} points", ctx, path, extras.colours.size(), cloud.size()));
  }
  std::string out =
      "ply\nformat binary_little_endian 1.0\ncomment written by pbnbv " + std::string(pbnbv_version()) + "\ncomment units metres\n"
      "comment frame object (the scan's object frame: object.obj's normalised mesh frame, z up; on the arm rig it "
      "turns with the turntable)\n"
      "comment camera_pose_format x y z qw qx qy qz (camera optical frame, x right y down z forward, in the object "
      "frame; m, unit quaternion)\n";
  for (const Pose& pose : extras.camera_poses) {
    double position[3], quat[4];
    pose_to_arrays(pose, position, quat);
    out += fmt::format("comment camera_pose {} {} {} {} {} {} {}\n", position[0], position[1], position[2], quat[0],
                       quat[1], quat[2], quat[3]);
  }
  out += "element vertex " + std::to_string(cloud.size()) + "\nproperty float x\nproperty float y\nproperty float z\n";
  if (normals) out += "property float nx\nproperty float ny\nproperty float nz\n";
  if (colours) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out += "end_header\n";
  const std::size_t header = out.size();
  const std::size_t stride = (normals ? 24 : 12) + (colours ? 3 : 0);
  out.resize(header + stride * cloud.size());
  char* dst = &out[header];
  auto put = [&dst](const Eigen::Vector3f& v) {
    for (int k = 0; k < 3; ++k) {
      const float f = v[k];
      unsigned char b[4];
      std::memcpy(b, &f, 4);
      if (!host_little_endian()) std::reverse(b, b + 4);
      std::memcpy(dst, b, 4);
      dst += 4;
    }
  };
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    put(cloud[i]);
    if (normals) put(extras.normals[i]);
    if (colours) {
      std::memcpy(dst, extras.colours[i].data(), 3);
      dst += 3;
    }
  }
  // Atomically (temporary file + rename): a reader, or a process restarted after a crash, never
  // sees half a cloud.
  try {
    write_text_atomic(out, path);
  } catch (const std::exception& e) {
    file_error(ctx, path, e.what());
  }
}

PointCloud read_ply(const std::string& path) {
  CloudExtras ignored;
  return read_ply(path, ignored);
}

PointCloud read_ply(const std::string& path, CloudExtras& extras) {
  const char* ctx = "read_ply";
  using Kernel = CGAL::Simple_cartesian<double>;
  using Point = Kernel::Point_3;
  using Vector = Kernel::Vector_3;
  using PointNormal = std::pair<Point, Vector>;
  check_input_file(path, ctx);
  std::ifstream in(path, std::ios::binary);
  const PlyHeader header = check_ply_header(in, path, ctx, false);
  // The header's lines again: normals and camera poses.
  in.clear();
  in.seekg(0);
  extras = CloudExtras{};
  bool has_normals = false;
  for (std::string line; std::getline(in, line) && line.rfind("end_header", 0) != 0;) {
    if (line == "property float nx" || line == "property double nx") has_normals = true;
    if (line.rfind("comment camera_pose ", 0) == 0) {
      std::istringstream words(line.substr(20));
      double position[3], quat[4];
      if (!(words >> position[0] >> position[1] >> position[2] >> quat[0] >> quat[1] >> quat[2] >> quat[3])) {
        file_error(ctx, path, "a camera_pose comment is not 'x y z qw qx qy qz': " + line);
      }
      extras.camera_poses.push_back(pose_from_arrays(position, quat, path + " camera_pose"));
    }
  }
  in.clear();
  in.seekg(0);
  CGAL::IO::set_mode(in, CGAL::IO::BINARY);
  std::vector<PointNormal> points;
  points.reserve(header.vertices);
  const bool ok =
      has_normals
          ? CGAL::IO::read_PLY_with_properties(
                in, std::back_inserter(points),
                CGAL::IO::make_ply_point_reader(CGAL::First_of_pair_property_map<PointNormal>()),
                CGAL::IO::make_ply_normal_reader(CGAL::Second_of_pair_property_map<PointNormal>()))
          : CGAL::IO::read_PLY_with_properties(
                in, std::back_inserter(points),
                CGAL::IO::make_ply_point_reader(CGAL::First_of_pair_property_map<PointNormal>()));
  if (!ok) file_error(ctx, path, ply_failure(header, path, in));
  PointCloud cloud;
  cloud.reserve(points.size());
  for (const auto& [p, n] : points) {
    cloud.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    if (has_normals) extras.normals.emplace_back(static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z()));
  }
  extras.colours = read_ply_colours(path, cloud.size());
  return cloud;
}

std::vector<Rgb> read_ply_colours(const std::filesystem::path& path, std::size_t points) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  if (!std::getline(in, line) || line.rfind("ply", 0) != 0) return {};
  struct Property {
    std::string type, name;
  };
  std::string format;
  std::vector<Property> props;
  std::size_t count = 0;
  bool seen_vertex = false, in_vertex = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    if (word == "format") {
      ls >> format;
    } else if (word == "element") {
      std::string name;
      std::size_t n = 0;
      ls >> name >> n;
      in_vertex = name == "vertex" && !seen_vertex;
      if (in_vertex) {
        seen_vertex = true;
        count = n;
      } else if (!seen_vertex && n > 0) {
        return {};
      }
    } else if (word == "property" && in_vertex) {
      Property p;
      ls >> p.type >> p.name;
      if (p.type == "list") return {};
      props.push_back(p);
    } else if (word == "end_header") {
      break;
    }
  }
  if (!seen_vertex || count != points || count == 0) return {};
  static const char* const kChannels[3] = {"red", "green", "blue"};
  int channel[3] = {-1, -1, -1};
  for (std::size_t i = 0; i < props.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      if (props[i].name == kChannels[c]) channel[c] = static_cast<int>(i);
    }
  }
  if (channel[0] < 0 || channel[1] < 0 || channel[2] < 0) return {};
  const auto size_of = [](const std::string& t) -> std::size_t {
    if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
    if (t == "int" || t == "uint" || t == "int32" || t == "uint32" || t == "float" || t == "float32") return 4;
    if (t == "double" || t == "float64") return 8;
    return 0;
  };
  // A channel's value on 0..255 from the number read, by its type.
  const auto to_byte = [](const std::string& t, double v) -> uint8_t {
    if (t == "float" || t == "float32" || t == "double" || t == "float64") v *= 255.0;
    if (t == "ushort" || t == "uint16") v /= 257.0;
    if (!std::isfinite(v)) return 0;
    return static_cast<uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
  };
  std::vector<Rgb> out(count);
  if (format == "ascii") {
    for (std::size_t i = 0; i < count; ++i) {
      if (!std::getline(in, line)) return {};
      std::istringstream ls(line);
      std::vector<double> v(props.size());
      for (double& x : v) {
        if (!(ls >> x)) return {};
      }
      for (int c = 0; c < 3; ++c) out[i][c] = to_byte(props[channel[c]].type, v[channel[c]]);
    }
    return out;
  }
  if (format != "binary_little_endian") return {};
  std::size_t stride = 0;
  std::vector<std::size_t> offset;
  for (const Property& p : props) {
    const std::size_t n = size_of(p.type);
    if (n == 0) return {};
    offset.push_back(stride);
    stride += n;
  }
  std::vector<char> data(stride * count);
  if (!in.read(data.data(), static_cast<std::streamsize>(data.size()))) return {};
  const auto number = [](const std::string& t, const char* at) -> double {
    const auto get = [at](auto v) {
      std::memcpy(&v, at, sizeof v);
      return static_cast<double>(v);
    };
    if (t == "char" || t == "int8") return get(int8_t{});
    if (t == "uchar" || t == "uint8") return get(uint8_t{});
    if (t == "short" || t == "int16") return get(int16_t{});
    if (t == "ushort" || t == "uint16") return get(uint16_t{});
    if (t == "int" || t == "int32") return get(int32_t{});
    if (t == "uint" || t == "uint32") return get(uint32_t{});
    if (t == "float" || t == "float32") return get(float{});
    return get(double{});
  };
  for (std::size_t i = 0; i < count; ++i) {
    for (int c = 0; c < 3; ++c) {
      const Property& p = props[static_cast<std::size_t>(channel[c])];
      out[i][c] = to_byte(p.type, number(p.type, data.data() + i * stride + offset[static_cast<std::size_t>(channel[c])]));
    }
  }
  return out;
}

}  // namespace pbnbv
