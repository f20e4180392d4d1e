// Point cloud files: read by CGAL's point-set PLY reader, written by our own (see write_ply).
#include "core/io/cloud_file.hpp"
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
#include <stdexcept>
#include <string>
#include <vector>

#include "core/base/format.hpp"
#include "core/io/file_checks.hpp"

namespace pbnbv {

namespace {

// Throws "<ctx>: <path>: <what>".
[[noreturn]] void fail(const char* ctx, const std::string& path, const std::string& what) {
  throw std::runtime_error(fmt::format("{}: {}: {}", ctx, path, what));
}

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
void write_ply(const PointCloud& cloud, const std::string& path) {
  const char* ctx = "write_ply";
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment written by pbnbv\nelement vertex " +
                    std::to_string(cloud.size()) +
                    "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  const std::size_t header = out.size();
  out.resize(header + 12 * cloud.size());
  char* dst = &out[header];
  for (const auto& p : cloud) {
    for (int k = 0; k < 3; ++k) {
      const float f = p[k];
      unsigned char b[4];
      std::memcpy(b, &f, 4);
      if (!host_little_endian()) std::reverse(b, b + 4);
      std::memcpy(dst, b, 4);
      dst += 4;
    }
  }
  // Atomically (temporary file + rename): a reader, or a process restarted after a crash, never
  // sees half a cloud.
  try {
    write_text_atomic(out, path);
  } catch (const std::exception& e) {
    fail(ctx, path, e.what());
  }
}

PointCloud read_ply(const std::string& path) {
  const char* ctx = "read_ply";
  using Point = CGAL::Simple_cartesian<double>::Point_3;
  check_input_file(path, ctx);
  std::ifstream in(path, std::ios::binary);
  const PlyHeader header = check_ply_header(in, path, ctx, false);
  in.clear();
  in.seekg(0);
  CGAL::IO::set_mode(in, CGAL::IO::BINARY);
  std::vector<Point> points;
  points.reserve(header.vertices);
  if (!CGAL::IO::read_PLY_with_properties(in, std::back_inserter(points),
                                          CGAL::IO::make_ply_point_reader(CGAL::Identity_property_map<Point>()))) {
    fail(ctx, path, ply_failure(header, path, in));
  }
  PointCloud cloud;
  cloud.reserve(points.size());
  for (const auto& p : points) {
    cloud.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  }
  return cloud;
}

}  // namespace pbnbv
