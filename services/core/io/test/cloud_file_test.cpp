#include "core/io/cloud_file.hpp"

#include <gtest/gtest.h>

#include "file_test_util.hpp"
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

namespace pbnbv {
namespace {

namespace fs = std::filesystem;
using testing::expect_error;
using testing::put_be;

class CloudFiles : public testing::TempDirTest {};

TEST_F(CloudFiles, PlyRoundTripIsExact) {
  std::mt19937 rng(5);
  std::normal_distribution<float> g(0.0f, 0.3f);
  PointCloud c;
  for (int i = 0; i < 1000; ++i) c.emplace_back(g(rng), g(rng), g(rng));
  c.emplace_back(-0.0f, 1e-30f, 3.4e38f);
  const std::string p = path("c.ply");
  write_ply(c, p);
  // The body is 12 bytes a point (float x y z, no normals) after the header.
  std::ifstream in(p, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t body = text.find("property float z\nend_header\n");
  ASSERT_NE(body, std::string::npos);
  EXPECT_EQ(fs::file_size(p) - 12 * c.size(), body + std::string("property float z\nend_header\n").size());
  EXPECT_EQ(text.find("property float nx"), std::string::npos);
  const PointCloud r = read_ply(p);
  EXPECT_EQ(r, c);

  write_ply({}, path("empty.ply"));
  EXPECT_TRUE(read_ply(path("empty.ply")).empty());
}

TEST_F(CloudFiles, ReadAsciiWithExtrasAndFaces) {
  const std::string p = write("a.ply",
                              "ply\r\nformat ascii 1.0\r\ncomment crlf header\r\n"
                              "element vertex 3\r\nproperty double x\r\nproperty uchar red\r\n"
                              "property double y\r\nproperty double z\r\nproperty float nx\r\n"
                              "element face 1\r\nproperty list uchar int vertex_indices\r\n"
                              "end_header\r\n"
                              "0.5 255 -1 2e-3 0\r\n1 0 2 3 0.5\r\n-4 7 5 6 1\r\n3 0 1 2\r\n");
  const PointCloud r = read_ply(p);
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[0], Eigen::Vector3f(0.5f, -1.0f, 2e-3f));
  EXPECT_EQ(r[1], Eigen::Vector3f(1, 2, 3));
  EXPECT_EQ(r[2], Eigen::Vector3f(-4, 5, 6));

  // A cloud may hold invalid points (a mesh may not): written and read as they are. As text,
  // "nan" is not a number to CGAL's reader.
  const PointCloud with_nan = {Eigen::Vector3f(1, 2, 3), Eigen::Vector3f(std::nanf(""), 0, 0)};
  write_ply(with_nan, path("nan.ply"));
  const PointCloud c = read_ply(path("nan.ply"));
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0], with_nan[0]);
  EXPECT_TRUE(std::isnan(c[1].x()));
  const std::string q = write("nan_text.ply",
                              "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                              "property float y\nproperty float z\nend_header\n1 2 3\nnan 0 0\n");
  expect_error([&] { read_ply(q); }, {q, "line 9", "'nan 0 0'"});
}

TEST_F(CloudFiles, ReadBinaryBigEndianDouble) {
  std::string s =
      "ply\nformat binary_big_endian 1.0\nelement camera 1\nproperty float fx\n"
      "element vertex 2\nproperty double x\nproperty double y\nproperty double z\n"
      "property list uchar float extra\nend_header\n";
  const float fx = 600.0f;
  put_be(s, &fx, 4);
  const double v[2][3] = {{0.1, 0.2, 0.3}, {-1.5, 2.25, 1e3}};
  for (const auto& p : v) {
    for (double c : p) put_be(s, &c, 8);
    s.push_back(1);
    const float e = 9.0f;
    put_be(s, &e, 4);
  }
  const PointCloud r = read_ply(write("be.ply", s));
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0], Eigen::Vector3f(0.1f, 0.2f, 0.3f));
  EXPECT_EQ(r[1], Eigen::Vector3f(-1.5f, 2.25f, 1e3f));
}

TEST_F(CloudFiles, Errors) {
  const std::string missing = path("missing.ply");
  expect_error([&] { read_ply(missing); }, {missing, "does not exist"});
  const std::string notply = write("x.ply", "solid nope\n");
  expect_error([&] { read_ply(notply); }, {notply, "ply"});
  const std::string noxyz = write("noxyz.ply",
                                  "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                  "property float y\nend_header\n1 2\n");
  expect_error([&] { read_ply(noxyz); }, {noxyz, "x, y or z"});
  const std::string bad = write("bad.ply",
                                "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                                "property float y\nproperty float z\nend_header\n1 2 3\n1 2 three\n");
  expect_error([&] { read_ply(bad); }, {bad, "line 9", "'1 2 three'"});
  const std::string uchar_xyz = write("uchar.ply",
                                      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                      "property uchar y\nproperty float z\nend_header\n1 2 3\n");
  expect_error([&] { read_ply(uchar_xyz); }, {uchar_xyz, "'y' is not float or double"});
  // CGAL reads each of these through a null pointer (found by fuzz_cloud_file): a normal's
  // component of another type, and a second vertex element (CGAL checks the first, reads the last).
  const std::string uchar_normal = write("uchar_normal.ply",
                                         "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                         "property float z\nproperty float nx\nproperty uchar ny\nproperty float nz\n"
                                         "end_header\n1 2 3 0 1 0\n");
  expect_error([&] { read_ply(uchar_normal); }, {uchar_normal, "PLY vertex property 'ny' is not float or double"});
  const std::string twice = write("twice.ply",
                                  "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                  "property float z\nelement vertex 1\nproperty uchar x\nend_header\n1 2 3\n1\n");
  expect_error([&] { read_ply(twice); }, {twice, "PLY header line 7: a second element 'vertex'"});
  PointCloud c(10, Eigen::Vector3f(1, 2, 3));
  const std::string p = path("cut.ply");
  write_ply(c, p);
  fs::resize_file(p, fs::file_size(p) - 5);
  expect_error([&] { read_ply(p); }, {p, "truncated"});
  const std::string unwritable = path("no/dir/c.ply");
  expect_error([&] { write_ply(c, unwritable); }, {unwritable});
}

// Normals and camera poses go into the file and come back; a file without them reads as before.
TEST(CloudFile, NormalsAndCameraPosesRoundTrip) {
  const fs::path path = fs::temp_directory_path() / ("pbnbv_cloud_normals_" + std::to_string(::getpid()) + ".ply");
  const PointCloud points = {Eigen::Vector3f(0.1f, 0.2f, 0.3f), Eigen::Vector3f(-0.1f, 0, 0.05f)};
  CloudExtras extras;
  extras.normals = {Eigen::Vector3f(0, 0, 1), Eigen::Vector3f(1, 0, 0)};
  Pose a = Pose::Identity();
  a.translation() = Eigen::Vector3d(0.5, -0.25, 0.125);
  a.linear() = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  extras.camera_poses = {a, Pose::Identity()};
  write_ply(points, path.string(), extras);
  std::ifstream in(path);
  std::string header((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  header = header.substr(0, header.find("end_header"));
  EXPECT_NE(header.find("comment units metres\n"), std::string::npos) << header;
  EXPECT_NE(header.find("comment camera_pose 0.5 -0.25 0.125 "), std::string::npos) << header;
  EXPECT_NE(header.find("property float nx\nproperty float ny\nproperty float nz\n"), std::string::npos) << header;
  CloudExtras back;
  const PointCloud read = read_ply(path.string(), back);
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read[1], points[1]);
  ASSERT_EQ(back.normals.size(), 2u);
  EXPECT_EQ(back.normals[1], extras.normals[1]);
  ASSERT_EQ(back.camera_poses.size(), 2u);
  EXPECT_TRUE(back.camera_poses[0].isApprox(a, 1e-12));
  write_ply(points, path.string());  // no extras: x y z only
  EXPECT_EQ(read_ply(path.string(), back).size(), 2u);
  EXPECT_TRUE(back.normals.empty());
  EXPECT_TRUE(back.camera_poses.empty());
  EXPECT_THROW(write_ply(points, path.string(), CloudExtras{{Eigen::Vector3f(0, 0, 1)}, {}}), std::invalid_argument);
  fs::remove(path);
}

// Colours go out as uchar red green blue after the normals, and come back exactly.
TEST(CloudFile, ColoursRoundTrip) {
  const fs::path path = fs::temp_directory_path() / ("pbnbv_cloud_colours_" + std::to_string(::getpid()) + ".ply");
  const PointCloud points = {Eigen::Vector3f(0.1f, 0.2f, 0.3f), Eigen::Vector3f(-0.1f, 0, 0.05f)};
  CloudExtras extras;
  extras.normals = {Eigen::Vector3f(0, 0, 1), Eigen::Vector3f(1, 0, 0)};
  extras.colours = {Rgb{255, 0, 7}, Rgb{1, 128, 254}};
  write_ply(points, path.string(), extras);
  std::ifstream in(path, std::ios::binary);
  std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t end = file.find("end_header\n") + 11;
  EXPECT_NE(file.find("property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header"),
            std::string::npos);
  EXPECT_EQ(file.size() - end, 2u * 27u);  // 6 floats and 3 bytes a point
  EXPECT_EQ(static_cast<unsigned char>(file[end + 24]), 255);
  EXPECT_EQ(static_cast<unsigned char>(file[end + 26]), 7);
  CloudExtras back;
  const PointCloud read = read_ply(path.string(), back);
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(back.colours, extras.colours);
  EXPECT_EQ(back.normals[1], extras.normals[1]);
  extras.colours.pop_back();
  EXPECT_THROW(write_ply(points, path.string(), extras), std::invalid_argument);
  fs::remove(path);
}

}  // namespace
}  // namespace pbnbv
