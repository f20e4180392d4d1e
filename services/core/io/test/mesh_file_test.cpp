#include "core/io/mesh_file.hpp"
#include "core/io/cloud_file.hpp"

#include <gtest/gtest.h>

#include "file_test_util.hpp"
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace pbnbv {
namespace {

namespace fs = std::filesystem;
using testing::expect_error;
using testing::put_be;

class MeshFiles : public testing::TempDirTest {};

// Little helpers for building binary files by hand.
void put_u32_le(std::string& s, uint32_t u) {
  for (int k = 0; k < 4; ++k) s.push_back(static_cast<char>((u >> (8 * k)) & 0xff));
}
void put_f32_le(std::string& s, float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  put_u32_le(s, u);
}
void put_f32_le_at(std::string& s, size_t at, float f) {
  std::string b;
  put_f32_le(b, f);
  s.replace(at, 4, b);
}
Eigen::Vector3d normal(const TriangleMesh& m, const Eigen::Vector3i& t) {
  return (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]);
}
Eigen::Vector3d centroid(const TriangleMesh& m, const Eigen::Vector3i& t) {
  return (m.vertices[t[0]] + m.vertices[t[1]] + m.vertices[t[2]]) / 3.0;
}

// Unit box [0,1]^3 as quads, 1-based corner numbers: corner i+1 has x=bit0, y=bit1, z=bit2.
const char* kBoxCorners =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n";
// Quads (outward, counter-clockwise) with 1-based indices.
const int kBoxQuads[6][4] = {{1, 3, 4, 2}, {5, 6, 8, 7}, {1, 2, 6, 5},
                             {3, 7, 8, 4}, {1, 5, 7, 3}, {2, 4, 8, 6}};

void expect_unit_box(const TriangleMesh& m) {
  EXPECT_EQ(m.vertices.size(), 8u);
  EXPECT_EQ(m.triangles.size(), 12u);
  EXPECT_NEAR(mesh_area(m), 6.0, 1e-12);
  Eigen::Vector3d lo, hi;
  mesh_bounds(m, lo, hi);
  EXPECT_EQ(lo, Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(hi, Eigen::Vector3d(1, 1, 1));
  for (const auto& t : m.triangles) {
    EXPECT_GT(normal(m, t).dot(centroid(m, t) - Eigen::Vector3d(0.5, 0.5, 0.5)), 0.0);
  }
}

// ---- OBJ ---------------------------------------------------------------------------------
TEST_F(MeshFiles, ObjTetrahedronAllVertexForms) {
  const std::string p = write("tet.obj",
                              "# a tetrahedron\n"
                              "o tet\n"
                              "v 0 0 0\n"
                              "v 1 0 0\r\n"
                              "v 0 1 0\n"
                              "v 0 0 1.5e0\n"
                              "vt 0 0\nvt 1 0\nvt 0 1\n"
                              "vn 0 0 1\n"
                              "f 1 3 2\n"
                              "f 1/1 2/2 4/3\n"
                              "f 1/1/1 4/2/1 3/3/1\n"
                              "f 2//1 3//1 4//1  # trailing comment\n");
  const TriangleMesh m = load_mesh(p);
  ASSERT_EQ(m.vertices.size(), 4u);
  ASSERT_EQ(m.triangles.size(), 4u);
  EXPECT_EQ(m.vertices[3], Eigen::Vector3d(0, 0, 1.5));
  EXPECT_EQ(m.triangles[0], Eigen::Vector3i(0, 2, 1));
  EXPECT_EQ(m.triangles[1], Eigen::Vector3i(0, 1, 3));
  EXPECT_EQ(m.triangles[2], Eigen::Vector3i(0, 3, 2));
  EXPECT_EQ(m.triangles[3], Eigen::Vector3i(1, 2, 3));
  // Area: three right triangles (0.5, 0.75, 0.75) + the slanted one.
  const double slanted = 0.5 * Eigen::Vector3d(-1, 1, 0).cross(Eigen::Vector3d(-1, 0, 1.5)).norm();
  EXPECT_NEAR(mesh_area(m), 0.5 + 0.75 + 0.75 + slanted, 1e-12);
}

TEST_F(MeshFiles, ObjQuadsWithNegativeIndices) {
  // The 8 corners, then quads with negative indices (-8 is corner 1) and v/vt forms.
  std::string s = kBoxCorners;
  for (const auto& q : kBoxQuads) {
    s += "f";
    for (int k = 0; k < 4; ++k) s += " " + std::to_string(q[k] - 9) + "/" + std::to_string(k + 1);
    s += "\n";
  }
  const TriangleMesh m = load_mesh(write("box.OBJ", s));  // extension is case-insensitive
  expect_unit_box(m);
  // The first quad (1 3 4 2) is fanned into (1 3 4) and (1 4 2).
  EXPECT_EQ(m.triangles[0], Eigen::Vector3i(0, 2, 3));
  EXPECT_EQ(m.triangles[1], Eigen::Vector3i(0, 3, 1));
}

TEST_F(MeshFiles, ObjNegativeIndicesAreRelativeToCurrentVertexCount) {
  const std::string p = write("rel.obj",
                              "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n"
                              "v 0 0 1\nf -4 -1 -3\n");
  const TriangleMesh m = load_mesh(p);
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[0], Eigen::Vector3i(0, 1, 2));
  EXPECT_EQ(m.triangles[1], Eigen::Vector3i(0, 3, 1));
}

TEST_F(MeshFiles, DegenerateTrianglesAreDropped) {
  const std::string p = write("deg.obj",
                              "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 2 0 0\n"
                              "f 1 3 2\nf 1 2 4\nf 1 1 2\nf 1 2 5\nf 1 4 3\nf 2 3 4\n");
  const TriangleMesh m = load_mesh(p);
  EXPECT_EQ(m.vertices.size(), 5u);
  EXPECT_EQ(m.triangles.size(), 4u);  // the repeated-index and the collinear one are gone
}

// ---- STL ---------------------------------------------------------------------------------
std::string stl_ascii_tetrahedron() {
  const double v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const int f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::string s = "solid tet\n";
  for (const auto& t : f) {
    s += "  facet normal 0 0 0\n    outer loop\n";
    for (int k = 0; k < 3; ++k) {
      s += "      vertex " + std::to_string(v[t[k]][0]) + " " + std::to_string(v[t[k]][1]) + " " +
           std::to_string(v[t[k]][2]) + "\n";
    }
    s += "    endloop\n  endfacet\n";
  }
  s += "endsolid tet\n";
  return s;
}

TEST_F(MeshFiles, StlAsciiMergesDuplicateVertices) {
  const TriangleMesh m = load_mesh(write("tet.stl", stl_ascii_tetrahedron()));
  ASSERT_EQ(m.vertices.size(), 4u);  // 12 corners written, 4 distinct
  ASSERT_EQ(m.triangles.size(), 4u);
  EXPECT_EQ(m.vertices[0], Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(m.vertices[1], Eigen::Vector3d(0, 1, 0));
  EXPECT_EQ(m.vertices[2], Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(m.vertices[3], Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(m.triangles[0], Eigen::Vector3i(0, 1, 2));
  EXPECT_NEAR(mesh_area(m), 1.5 + 0.5 * std::sqrt(3.0), 1e-12);
}

std::string stl_binary_box(const std::string& header_start, float size) {
  const TriangleMesh box = make_box(Eigen::Vector3d(size, size, size));
  std::string s = header_start;
  s.resize(80, ' ');
  put_u32_le(s, static_cast<uint32_t>(box.triangles.size()));
  for (const auto& t : box.triangles) {
    for (int k = 0; k < 3; ++k) put_f32_le(s, 0.0f);
    for (int c = 0; c < 3; ++c) {
      for (int k = 0; k < 3; ++k) put_f32_le(s, static_cast<float>(box.vertices[t[c]][k]));
    }
    s.push_back(0);
    s.push_back(0);
  }
  return s;
}

TEST_F(MeshFiles, StlBinaryWhoseHeaderStartsWithSolid) {
  const std::string bytes = stl_binary_box("solid box exported by a careless tool", 2.0f);
  ASSERT_EQ(bytes.size(), 84u + 50u * 12u);
  const TriangleMesh m = load_mesh(write("box.stl", bytes));
  EXPECT_EQ(m.vertices.size(), 8u);
  EXPECT_EQ(m.triangles.size(), 12u);
  EXPECT_NEAR(mesh_area(m), 24.0, 1e-12);
  for (const auto& v : m.vertices) EXPECT_EQ(v.cwiseAbs(), Eigen::Vector3d(1, 1, 1));
}

TEST_F(MeshFiles, StlBinaryTruncatedIsAnError) {
  std::string bytes = stl_binary_box("binary", 1.0f);
  bytes.resize(bytes.size() - 7);
  const std::string p = write("cut.stl", bytes);
  expect_error([&] { load_mesh(p); }, {p, "truncated"});
  const std::string tiny = write("tiny.stl", std::string(40, '\0'));
  expect_error([&] { load_mesh(tiny); }, {tiny, "truncated"});
}

// ---- OFF ---------------------------------------------------------------------------------
TEST_F(MeshFiles, OffWithCommentsAndColours) {
  std::string s = "COFF # coloured\n# vertex and face counts\n\n8 6 12\n";
  const char* corners[8] = {"0 0 0", "1 0 0", "0 1 0", "1 1 0",
                            "0 0 1", "1 0 1", "0 1 1", "1 1 1"};
  for (const char* c : corners) s += std::string(c) + " 255 0 0 255  # red\n";
  for (const auto& q : kBoxQuads) {
    s += "4";
    for (int k = 0; k < 4; ++k) s += " " + std::to_string(q[k] - 1);
    s += " 0.5 0.5 0.5\n";  // optional face colour
  }
  expect_unit_box(load_mesh(write("box.off", s)));
}

TEST_F(MeshFiles, OffCountsOnHeaderLineAndNoff) {
  const std::string a = write("a.off",
                              "OFF 4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                              "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  const TriangleMesh ma = load_mesh(a);
  EXPECT_EQ(ma.vertices.size(), 4u);
  EXPECT_EQ(ma.triangles.size(), 4u);
  const std::string b = write("b.off",
                              "NOFF\n4 4 0\n0 0 0 0 0 -1\n1 0 0 1 0 0\n0 1 0 0 1 0\n"
                              "0 0 1 0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  const TriangleMesh mb = load_mesh(b);
  EXPECT_EQ(mb.vertices, ma.vertices);
  EXPECT_EQ(mb.triangles, ma.triangles);
}

TEST_F(MeshFiles, OffIndexOutOfRange) {
  const std::string p = write("bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  // Three vertices: indices 0 to 2; the face's third corner names vertex 3.
  expect_error([&] { load_mesh(p); }, {p, "line 6: corner 3 of face 1 is vertex '3'; the file has vertices 0 to 2"});
}

// A header that declares more than the file can hold is refused naming the file and the count
// before anything is reserved for it (before: std::bad_alloc, no file named).
TEST_F(MeshFiles, OffHeaderCountsBeyondTheFileAreRefusedBeforeReading) {
  const std::string huge = write("huge.off", "OFF\n4000000000000 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  expect_error([&] { load_mesh(huge); }, {huge, "declares 4000000000000 vertices", "bytes can hold"});
  const std::string faces = write("faces.off", "OFF 3 90000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  expect_error([&] { load_mesh(faces); }, {faces, "declares 90000000000 faces"});
  // What fuzz_mesh_file found CGAL's OFF scanner doing, each now refused before anything is
  // allocated: a corner count of 4e18 (an allocation of 32 EB) or a negative one (cast to an
  // unsigned count), a corner index of 2e88 (a double cast to an integer: undefined), a face on
  // the counts' line (40,000,000 corners allocated for), an edge count with a face behind it
  // ("5-4000": CGAL reads 5 edges, then a corner -4000, cast to an unsigned index).
  const std::string corners = write("corners.off", "OFF\n# a comment\n3 1 0\n0 0 0\n1 0 0\n\n0 1 0\n4000000000000000000 0 1 2\n");
  expect_error([&] { load_mesh(corners); }, {corners, "line 8: face 1 has 4000000000000000000 corners, more than the file's 3 vertices"});
  const std::string negative = write("negative.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n-4e15 0 1 2\n");
  expect_error([&] { load_mesh(negative); }, {negative, "line 6: face 1's corner count '-4e15' is not a whole number"});
  const std::string index = write("index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 2e88 1\n");
  expect_error([&] { load_mesh(index); }, {index, "line 6: corner 2 of face 1 is vertex '2e88'; the file has vertices 0 to 2"});
  const std::string same_line = write("same_line.off", "OFF\n0 1 0 40000000 1 2\n");
  expect_error([&] { load_mesh(same_line); }, {same_line, "line 2: the OFF counts line has 6 words; expected the vertex, face and edge counts"});
  const std::string edges = write("edges.off", "OFF\n# a 0\n0 1 \n5-4000 1 2\n");
  expect_error([&] { load_mesh(edges); }, {edges, "line 4: face 1's corner count '5-4000' is not a whole number"});
  const std::string few = write("few.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n");
  expect_error([&] { load_mesh(few); }, {few, "line 6: face 1 declares 3 corners and lists 2"});
  const std::string two = write("two.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n");
  expect_error([&] { load_mesh(two); }, {two, "line 6: face 1 has 2 corners, fewer than 3"});
  const std::string word = write("word.off", "OFF\nmany 1 0\n0 0 0\n");
  expect_error([&] { load_mesh(word); }, {word, "vertex count 'many' is not a whole number"});
}

// What is not an ASCII OFF file of 3-D points, and a file shorter than its header, are named.
TEST_F(MeshFiles, OffKeywordsAndTruncationAreNamed) {
  const std::string nul = write("nul.off", std::string("\0OFF\n0 1 0\n", 11));
  expect_error([&] { load_mesh(nul); }, {nul, "line 1: not an OFF file: it starts with '?OFF', not OFF"});
  const std::string four = write("four.off", "4OFF\n1 0 0\n0 0 0 1\n");
  expect_error([&] { load_mesh(four); }, {four, "line 1: '4OFF' is an OFF file of 4 or n dimensions"});
  const std::string binary = write("binary.off", "OFF BINARY\n");
  expect_error([&] { load_mesh(binary); }, {binary, "line 1: a binary OFF file; only ASCII OFF is read"});
  const std::string blank = write("blank.off", "# nothing\n\n");
  expect_error([&] { load_mesh(blank); }, {blank, "not an OFF file: nothing but blank and comment lines"});
  const std::string vertices = write("vertices.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n");
  expect_error([&] { load_mesh(vertices); }, {vertices, "the file ends after 2 of the 3 vertices its header declares"});
  const std::string faces = write("faces.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  expect_error([&] { load_mesh(faces); }, {faces, "the file ends after 1 of the 2 faces its header declares"});
  // Every prefix (a normal, a colour, texture coordinates after each vertex), the counts on the
  // keyword's line, no edge count: a tetrahedron.
  std::string tetrahedron = "STCNOFF 4 4\n";
  for (const char* corner : {"0 0 0", "1 0 0", "0 1 0", "0 0 1"}) tetrahedron += std::string(corner) + " 0 0 1 1 1 1 1 0.5 0.5\n";
  tetrahedron += "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3 255 0 0\n";
  const TriangleMesh m = load_mesh(write("counts.off", tetrahedron));
  EXPECT_EQ(m.vertices.size(), 4u);
  EXPECT_EQ(m.triangles.size(), 4u);
  EXPECT_EQ(m.vertices[3], Eigen::Vector3d(0, 0, 1));
}

// A mesh path that is a link to /dev/zero (read until memory ran out) or a FIFO is refused.
TEST_F(MeshFiles, ALinkToADeviceIsNotAMeshFile) {
  const std::string link = path("zero.obj");
  std::filesystem::create_symlink("/dev/zero", link);
  expect_error([&] { load_mesh(link); }, {link, "not a regular file"});
}

// ---- PLY ---------------------------------------------------------------------------------

// A property line before any element line: CGAL's PLY reader writes through an empty vector's
// back() (found by fuzz_mesh_file, memory corruption under no sanitizer); refused before it runs,
// naming the file and the line, for a mesh and for a cloud.
TEST_F(MeshFiles, PlyPropertyBeforeAnyElementIsRefusedBeforeCgalReadsIt) {
  const std::string p = write("early.ply", "ply\nformat ascii 1.0\nproperty float x\nelement vertex 1\nend_header\n0\n");
  expect_error([&] { load_mesh(p); }, {p, "PLY header line 3: a property before any element"});
  expect_error([&] { read_ply(p); }, {p, "PLY header line 3: a property before any element"});
}

// Counts CGAL's PLY reader trusts, refused before it reads: an element count of -4 (2^64 - 4
// items, read for ever: found by fuzz_mesh_file), one larger than the file, a list counted in a
// float, and a list in the body longer than the rest of the file (allocated for before its
// entries are read: 2,000,000,000 entries, 8 GB here; a polygon's worth past the end is a file
// cut short, named as such by MeshFiles.PlyBinaryLittleEndianFloatUintIndices).
TEST_F(MeshFiles, PlyCountsBeyondTheFileAreRefusedBeforeCgalReadsThem) {
  const std::string head = "ply\nformat ascii 1.0\nelement vertex ";
  const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
  const std::string negative = write("negative.ply", head + "-4\n" + xyz + "end_header\n0 0 0\n");
  expect_error([&] { load_mesh(negative); }, {negative, "PLY header line 3: element 'vertex' has count '-4', not a whole number"});
  expect_error([&] { read_ply(negative); }, {negative, "element 'vertex' has count '-4'"});
  const std::string many = write("many.ply", head + "1000\n" + xyz + "end_header\n0 0 0\n");  // 109 bytes
  expect_error([&] { load_mesh(many); }, {many, "PLY header line 3: element 'vertex' declares 1000 items, more than a file of 109 bytes can hold"});
  const std::string tet = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  const std::string float_count = write("float.ply", head + "4\n" + xyz + "element face 1\nproperty list float int vertex_indices\nend_header\n" + tet + "3 0 1 2\n");
  expect_error([&] { load_mesh(float_count); }, {float_count, "PLY header line 8: a list counted in 'float', not an integer type"});
  const std::string long_ascii = write("long.ply", head + "4\n" + xyz + "element face 1\nproperty list int int vertex_indices\nend_header\n" + tet + "1000000 0 1 2\n");
  expect_error([&] { load_mesh(long_ascii); }, {long_ascii, "PLY element 'face' item 0: a list of 1000000 entries, more than the 7 bytes left in the file can hold"});
  std::string binary = "ply\nformat binary_little_endian 1.0\nelement vertex 4\n" + xyz +
                       "element face 1\nproperty list int uint vertex_indices\nend_header\n";
  for (float c : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f}) put_f32_le(binary, c);
  put_u32_le(binary, 2000000000u);
  for (uint32_t i : {0u, 1u, 2u}) put_u32_le(binary, i);
  const std::string long_binary = write("long_binary.ply", binary);
  expect_error([&] { load_mesh(long_binary); }, {long_binary, "PLY element 'face' item 0: a list of 2000000000 entries, more than the 12 bytes left"});
}
TEST_F(MeshFiles, PlyAsciiBox) {
  std::string s =
      "ply\nformat ascii 1.0\ncomment unit box\nelement vertex 8\n"
      "property float x\nproperty float y\nproperty float z\n"
      "element face 6\nproperty list uchar int vertex_indices\nend_header\n";
  const char* corners[8] = {"0 0 0", "1 0 0", "0 1 0", "1 1 0",
                            "0 0 1", "1 0 1", "0 1 1", "1 1 1"};
  for (const char* c : corners) s += std::string(c) + "\n";
  for (const auto& q : kBoxQuads) {
    s += "4";
    for (int k = 0; k < 4; ++k) s += " " + std::to_string(q[k] - 1);
    s += "\n";
  }
  expect_unit_box(load_mesh(write("box.ply", s)));
}

TEST_F(MeshFiles, PlyFacesBeforeVertices) {
  const std::string p = write("faces_first.ply",
                              "ply\nformat ascii 1.0\nelement face 2\n"
                              "property list uchar uint vertex_index\nelement vertex 4\n"
                              "property float x\nproperty float y\nproperty float z\nend_header\n"
                              "3 0 2 1\n3 0 1 3\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n");
  const TriangleMesh m = load_mesh(p);
  ASSERT_EQ(m.vertices.size(), 4u);
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[1], Eigen::Vector3i(0, 1, 3));
  EXPECT_EQ(m.vertices[3], Eigen::Vector3d(0, 0, 1));
}

TEST_F(MeshFiles, PlyBinaryLittleEndianFloatUintIndices) {
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\n"
      "property float x\nproperty float y\nproperty float z\n"
      "element face 4\nproperty list int uint vertex_indices\nend_header\n";
  const float v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const uint32_t f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  for (const auto& p : v) {
    for (float c : p) put_f32_le(s, c);
  }
  for (const auto& t : f) {
    put_u32_le(s, 3);
    for (uint32_t i : t) put_u32_le(s, i);
  }
  const TriangleMesh m = load_mesh(write("tet.ply", s));
  ASSERT_EQ(m.vertices.size(), 4u);
  ASSERT_EQ(m.triangles.size(), 4u);
  EXPECT_EQ(m.vertices[3], Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(m.triangles[3], Eigen::Vector3i(1, 2, 3));

  // The same file cut short is a truncated-binary error.
  s.resize(s.size() - 3);
  const std::string cut = write("cut.ply", s);
  expect_error([&] { load_mesh(cut); }, {cut, "truncated"});
}

TEST_F(MeshFiles, PlyBinaryBigEndianDoubleWithExtraProperties) {
  std::string s =
      "ply\nformat binary_big_endian 1.0\ncomment extras everywhere\n"
      "element vertex 4\n"
      "property uchar red\n"
      "property double x\nproperty double y\n"
      "property list uchar short junk\n"
      "property double z\nproperty float confidence\n"
      "element face 4\n"
      "property uchar flags\n"
      "property list uchar int vertex_indices\n"
      "property ushort material\n"
      "element edge 1\nproperty int vertex1\nproperty int vertex2\n"
      "end_header\n";
  const double v[4][3] = {{0.125, -2.5, 3.0}, {1.0, -2.5, 3.0}, {0.125, 1.0, 3.0},
                          {0.125, -2.5, 4.0 + 1e-9}};
  const int32_t f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  for (const auto& p : v) {
    s.push_back(static_cast<char>(200));
    put_be(s, &p[0], 8);
    put_be(s, &p[1], 8);
    s.push_back(2);  // list of 2 shorts
    const int16_t junk[2] = {-1, 7};
    put_be(s, &junk[0], 2);
    put_be(s, &junk[1], 2);
    put_be(s, &p[2], 8);
    const float conf = 0.5f;
    put_be(s, &conf, 4);
  }
  for (const auto& t : f) {
    s.push_back(1);
    s.push_back(3);
    for (int32_t i : t) put_be(s, &i, 4);
    const uint16_t mat = 9;
    put_be(s, &mat, 2);
  }
  const int32_t e[2] = {0, 1};
  put_be(s, &e[0], 4);
  put_be(s, &e[1], 4);
  const TriangleMesh m = load_mesh(write("tet_be.ply", s));
  ASSERT_EQ(m.vertices.size(), 4u);
  ASSERT_EQ(m.triangles.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(m.vertices[i], Eigen::Vector3d(v[i][0], v[i][1], v[i][2])) << i;  // exact doubles
    EXPECT_EQ(m.triangles[i], Eigen::Vector3i(f[i][0], f[i][1], f[i][2])) << i;
  }
}

// ---- errors ------------------------------------------------------------------------------
TEST_F(MeshFiles, Errors) {
  const std::string missing = path("nope.obj");
  expect_error([&] { load_mesh(missing); }, {missing, "does not exist"});

  const std::string unknown = write("mesh.xyz", "v 0 0 0\n");
  expect_error([&] { load_mesh(unknown); }, {unknown, "extension"});

  // CGAL's readers say only that they failed; where they stopped gives the line. (A number
  // like "1.0.0" is not one of these: CGAL reads it as 1.0 followed by .0.)
  const std::string malformed = write("bad_number.obj", "v 0 0 0\nv 1 0 0\nv 0 1 zero\nf 1 2 3\n");
  expect_error([&] { load_mesh(malformed); }, {malformed, "line 3", "'v 0 1 zero'"});

  const std::string stl_bad = write("bad_number.stl",
                                    "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"
                                    "vertex 1 0 zero\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n");
  // CGAL's STL reader tries binary after ASCII fails, so where it stopped says nothing.
  expect_error([&] { load_mesh(stl_bad); }, {stl_bad, "not a valid ASCII STL"});

  const std::string ply_bad = write("bad_number.ply",
                                    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                    "property float y\nproperty float z\nelement face 1\n"
                                    "property list uchar int vertex_indices\nend_header\n"
                                    "0 0 0\n1 0 0\n0 1 x\n3 0 1 2\n");
  expect_error([&] { load_mesh(ply_bad); }, {ply_bad, "line 12", "'0 1 x'"});

  const std::string range = write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n");
  // Indices are checked after reading: the face is named (counted from 0), not its line.
  expect_error([&] { load_mesh(range); }, {range, "face 1: vertex index 8 out of range (3 vertices"});

  const std::string neg = write("neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n");
  expect_error([&] { load_mesh(neg); }, {neg, "face 0: vertex index -1 out of range"});

  const std::string ply_range = write("range.ply",
                                      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                      "property float y\nproperty float z\nelement face 1\n"
                                      "property list uchar int vertex_indices\nend_header\n"
                                      "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  expect_error([&] { load_mesh(ply_range); }, {ply_range, "out of range"});

  // "nan", "inf" and numbers beyond a double are not numbers to CGAL's text readers; a binary
  // file can hold a non-finite coordinate, caught after reading.
  const std::string nan = write("nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n");
  expect_error([&] { load_mesh(nan); }, {nan, "line 2", "'v 1 nan 0'"});

  const std::string inf = write("inf.off", "OFF\n3 1 0\n0 0 0\n1 0 inf\n0 1 0\n3 0 1 2\n");
  expect_error([&] { load_mesh(inf); }, {inf, "line 4", "'1 0 inf'"});

  const std::string last = write("last.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nvv 1 2 3\n");
  expect_error([&] { load_mesh(last); }, {last, "line 7", "'vv 1 2 3'"});

  const std::string huge = write("huge.obj", "v 0 0 0\nv 1 1e999 0\nv 0 1 0\nf 1 2 3\n");
  expect_error([&] { load_mesh(huge); }, {huge, "line 2", "'v 1 1e999 0'"});
  std::string stl_inf = stl_binary_box("binary", 1.0f);
  put_f32_le_at(stl_inf, 84 + 12 + 4, std::numeric_limits<float>::infinity());  // first corner's y
  const std::string inf_stl = write("inf.stl", stl_inf);
  expect_error([&] { load_mesh(inf_stl); }, {inf_stl, "non-finite coordinate in vertex 0"});

  // CGAL 5.5's read_PLY would read an integer coordinate through a null pointer: the header is
  // checked first.
  const std::string int_xyz = write("int_xyz.ply",
                                    "ply\nformat ascii 1.0\nelement vertex 3\nproperty int x\n"
                                    "property int y\nproperty int z\nelement face 1\n"
                                    "property list uchar int vertex_indices\nend_header\n"
                                    "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  expect_error([&] { load_mesh(int_xyz); }, {int_xyz, "'x' is not float or double"});

  const std::string empty = write("empty.obj", "# nothing but vertices\nv 0 0 0\nv 1 0 0\n");
  expect_error([&] { load_mesh(empty); }, {empty, "no triangles"});

  const std::string blank = write("blank.ply", "");
  expect_error([&] { load_mesh(blank); }, {blank, "empty file"});

  const std::string all_degenerate = write("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
  expect_error([&] { load_mesh(all_degenerate); }, {all_degenerate, "degenerate"});

  const std::string planar = write("planar.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  expect_error([&] { load_mesh(planar); }, {planar, "zero-size bounding box"});

  EXPECT_THROW(parse_name<UpAxis>("w"), std::invalid_argument);
  EXPECT_EQ(parse_name<UpAxis>("x"), UpAxis::kX);
  EXPECT_EQ(parse_name<UpAxis>("y"), UpAxis::kY);
  EXPECT_EQ(parse_name<UpAxis>("z"), UpAxis::kZ);
}

// ---- writing -----------------------------------------------------------------------------
TEST_F(MeshFiles, WriteObjRoundTripsExactly) {
  TriangleMesh m = make_icosphere(0.37, 2);
  for (auto& v : m.vertices) v += Eigen::Vector3d(1e-3, -2.0 / 3.0, 1e5);
  const std::string p = path("ico.obj");
  write_obj(m, p);
  const TriangleMesh r = load_mesh(p);
  EXPECT_EQ(r.vertices, m.vertices);
  EXPECT_EQ(r.triangles, m.triangles);
}

// Rounds to float and back. Through a volatile: GCC 12.2 at -O2 (SLP vectoriser) folds a pair
// of adjacent double -> float -> double round trips into a plain copy.
double to_float(double x) {
  volatile float f = static_cast<float>(x);
  return f;
}

TEST_F(MeshFiles, WriteStlRoundTripsToFloatPrecision) {
  const TriangleMesh m = make_icosphere(0.37, 2);
  const std::string p = path("ico.stl");
  write_stl_binary(m, p);
  EXPECT_EQ(fs::file_size(p), 84u + 50u * m.triangles.size());
  const TriangleMesh r = load_mesh(p);
  ASSERT_EQ(r.vertices.size(), m.vertices.size());  // duplicates merged back
  ASSERT_EQ(r.triangles.size(), m.triangles.size());
  for (size_t i = 0; i < m.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& v = m.vertices[m.triangles[i][k]];
      const Eigen::Vector3d expected(to_float(v.x()), to_float(v.y()), to_float(v.z()));
      EXPECT_EQ(r.vertices[r.triangles[i][k]], expected);
    }
  }
  // Header must not claim to be ASCII.
  std::ifstream f(p, std::ios::binary);
  char head[5];
  f.read(head, 5);
  EXPECT_NE(std::string(head, 5), "solid");
}

// A sphere's normals are its radial directions: written as vn lines and v//vn faces, read back by
// the reader with the same vertices and faces; in millimetres every coordinate is 1000 times the
// metres', the normals unchanged, and the comments say which.
TEST_F(MeshFiles, ObjWithNormalsInMillimetres) {
  const TriangleMesh m = make_icosphere(0.25, 2);
  std::vector<Eigen::Vector3d> normals;
  for (const auto& v : m.vertices) normals.push_back(v.normalized());
  const std::string p = path("ico_mm.obj");
  write_obj(m, p, normals, LengthUnit::kMillimetre);
  const TriangleMesh r = load_mesh(p);
  ASSERT_EQ(r.vertices.size(), m.vertices.size());
  EXPECT_EQ(r.triangles, m.triangles);
  for (size_t i = 0; i < m.vertices.size(); ++i) EXPECT_LT((r.vertices[i] - 1000.0 * m.vertices[i]).norm(), 1e-9) << i;
  std::ifstream in(p);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("# units millimetres\n"), std::string::npos);
  EXPECT_NE(text.find("# written by pbnbv "), std::string::npos);
  std::size_t vn = 0;
  for (std::size_t at = text.find("\nvn "); at != std::string::npos; at = text.find("\nvn ", at + 1)) ++vn;
  EXPECT_EQ(vn, m.vertices.size());
  const auto& t = m.triangles.front();
  const std::string face = "\nf " + std::to_string(t[0] + 1) + "//" + std::to_string(t[0] + 1) + " " +
                           std::to_string(t[1] + 1) + "//" + std::to_string(t[1] + 1) + " " + std::to_string(t[2] + 1) +
                           "//" + std::to_string(t[2] + 1) + "\n";
  EXPECT_NE(text.find(face), std::string::npos) << face;
  EXPECT_THROW(write_obj(m, p, std::vector<Eigen::Vector3d>(3), LengthUnit::kMetre), std::invalid_argument);
  // The STL in millimetres: 1000 times, to float precision.
  const std::string q = path("ico_mm.stl");
  write_stl_binary(m, q, LengthUnit::kMillimetre);
  const TriangleMesh s = load_mesh(q);
  ASSERT_EQ(s.triangles.size(), m.triangles.size());
  const Eigen::Vector3d& a = m.vertices[m.triangles[0][0]];
  EXPECT_LT((s.vertices[s.triangles[0][0]] - 1000.0 * a).norm(), 1e-4);
  EXPECT_EQ(parse_length_unit("mm"), LengthUnit::kMillimetre);
  EXPECT_THROW(parse_length_unit("cm"), std::invalid_argument);
}

TEST_F(MeshFiles, WriteToMissingDirectoryThrowsWithPath) {
  const std::string p = path("no/such/dir/x.stl");
  expect_error([&] { write_stl_binary(make_box(Eigen::Vector3d(1, 1, 1)), p); }, {p});
  const std::string q = path("no/such/dir/x.obj");
  expect_error([&] { write_obj(make_box(Eigen::Vector3d(1, 1, 1)), q); }, {q});
}

// ---- normalisation -----------------------------------------------------------------------

}  // namespace
}  // namespace pbnbv
