#include "core/io/cloud_file.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>

namespace pbnbv {

namespace detail {
// Defined in mesh.cpp: the shared PLY reader (see there).
void read_ply_file(const std::string& path, const char* ctx, bool require_finite,
                   std::vector<Eigen::Vector3d>& vertices, std::vector<Eigen::Vector3i>* triangles);
}  // namespace detail

namespace {

[[noreturn]] void fail(const char* ctx, const std::string& path, const std::string& what) {
  throw std::runtime_error(std::string(ctx) + ": " + path + ": " + what);
}

bool host_little_endian() {
  const uint16_t one = 1;
  unsigned char c;
  std::memcpy(&c, &one, 1);
  return c == 1;
}

}  // namespace

void write_ply(const PointCloud& cloud, const std::string& path) {
  const char* ctx = "write_ply";
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment written by pbnbv\nelement vertex " +
                    std::to_string(cloud.size()) +
                    "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  const size_t header = out.size();
  out.resize(header + 12 * cloud.size());
  char* dst = &out[header];
  const bool le = host_little_endian();
  for (const auto& p : cloud) {
    for (int k = 0; k < 3; ++k) {
      const float f = p[k];
      unsigned char b[4];
      std::memcpy(b, &f, 4);
      if (!le) std::reverse(b, b + 4);
      std::memcpy(dst, b, 4);
      dst += 4;
    }
  }
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) fail(ctx, path, std::string("cannot open for writing: ") + std::strerror(errno));
  f.write(out.data(), static_cast<std::streamsize>(out.size()));
  f.close();
  if (!f) fail(ctx, path, "write failed");
}

PointCloud read_ply(const std::string& path) {
  std::vector<Eigen::Vector3d> v;
  detail::read_ply_file(path, "read_ply", false, v, nullptr);
  PointCloud cloud;
  cloud.reserve(v.size());
  for (const auto& p : v) cloud.push_back(p.cast<float>());
  return cloud;
}
}  // namespace pbnbv
