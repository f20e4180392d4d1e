// PCD files as PCL writes them (ascii and binary, extra fields), read back to the coordinates
// written, and the files it cannot read refused naming why.
#include "core/io/pcd_file.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

#include "file_test_util.hpp"

namespace pbnbv {
namespace {

using testing::expect_error;

class PcdFiles : public testing::TempDirTest {};

const char* const kHeader =
    "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS {}\nSIZE {}\nTYPE {}\nCOUNT {}\n"
    "WIDTH {}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {}\nDATA {}\n";

std::string header(const std::string& fields, const std::string& size, const std::string& type,
                   const std::string& count, int points, const std::string& data) {
  return fmt::format(fmt::runtime(kHeader), fields, size, type, count, points, points, data);
}

TEST_F(PcdFiles, AsciiWithAnExtraFieldFirst) {
  const std::string p = write("a.pcd", header("rgb x y z", "4 4 4 4", "U F F F", "1 1 1 1", 2, "ascii") +
                                           "4278190080 0.5 -1.25 2\n0 1e-3 nan 3\n");
  const PointCloud c = read_pcd(p);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0], Eigen::Vector3f(0.5f, -1.25f, 2.0f));
  EXPECT_FLOAT_EQ(c[1].x(), 1e-3f);
  EXPECT_TRUE(std::isnan(c[1].y()));
}

TEST_F(PcdFiles, BinaryFloatAndDouble) {
  // x y z as float with a 3-float normal between y and z; then x y z as double.
  std::string body;
  const float row[] = {1, 2, 9, 9, 9, 3};
  body.append(reinterpret_cast<const char*>(row), sizeof row);
  const std::string p = write("b.pcd", header("x y normal z", "4 4 4 4", "F F F F", "1 1 3 1", 1, "binary") + body);
  ASSERT_EQ(read_pcd(p).size(), 1u);
  EXPECT_EQ(read_pcd(p)[0], Eigen::Vector3f(1, 2, 3));

  std::string dbody;
  const double drow[] = {0.25, -0.5, 4};
  dbody.append(reinterpret_cast<const char*>(drow), sizeof drow);
  const std::string q = write("d.pcd", header("x y z", "8 8 8", "F F F", "1 1 1", 1, "binary") + dbody);
  EXPECT_EQ(read_pcd(q)[0], Eigen::Vector3f(0.25f, -0.5f, 4.0f));
}

TEST_F(PcdFiles, RefusedNamingWhy) {
  expect_error([&] { read_pcd(path("missing.pcd")); }, {"missing.pcd"});
  expect_error([&] { read_pcd(write("c.pcd", header("x y z", "4 4 4", "F F F", "1 1 1", 1, "binary_compressed"))); },
               {"c.pcd", "binary_compressed is not supported"});
  expect_error([&] { read_pcd(write("t.pcd", header("x y z", "4 4 4", "F F F", "1 1 1", 3, "binary") + "12345678")); },
               {"t.pcd", "8 bytes", "need 36"});
  expect_error([&] { read_pcd(write("n.pcd", header("a b c", "4 4 4", "F F F", "1 1 1", 1, "ascii") + "1 2 3\n")); },
               {"n.pcd", "no x, y and z"});
  expect_error([&] { read_pcd(write("s.pcd", header("x y z", "4 4 4", "F F F", "1 1 1", 2, "ascii") + "1 2 3\n")); },
               {"s.pcd", "after 1 of 2 points"});
  expect_error([&] { read_pcd(write("p.ply", "ply\nformat ascii 1.0\n")); }, {"p.ply", "no FIELDS"});
}

// Counts a header declares beyond what the file can hold are refused before anything is
// allocated for them (found by fuzz_cloud_file: POINTS 4999...9, 60 TB reserved).
TEST_F(PcdFiles, CountsBeyondTheFileAreRefusedBeforeReading) {
  const std::string many = header("x y z", "4 4 4", "F F F", "1 1 1", 2000000000, "ascii") + "0 0 0\n";
  const std::string a = write("many.pcd", many);
  expect_error([&] { read_pcd(a); }, {a, fmt::format("POINTS 2000000000: more points than a file of {} bytes can hold (6 bytes a point at least)", many.size())});
  const std::string b = write("wide.pcd", header("x y z", "16 4 4", "F F F", "1 1 1", 1, "binary") + std::string(24, '\0'));
  expect_error([&] { read_pcd(b); }, {b, "field x has SIZE 16; a PCD value takes 1, 2, 4 or 8 bytes"});
  const std::string c = write("stride.pcd", header("x y z n", "4 4 4 4", "F F F F", "1 1 1 100000", 1, "binary") + std::string(24, '\0'));
  expect_error([&] { read_pcd(c); }, {c, "the FIELDS take 400012 bytes a point, more than the file's"});
}

}  // namespace
}  // namespace pbnbv
