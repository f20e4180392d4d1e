// Mesh files. Reading is CGAL's: the polygon-soup readers CGAL::IO::read_polygon_soup picks by
// extension (read_OBJ, read_OFF, read_STL, read_PLY), called on a stream we hold so that, when
// one fails, the place where it stopped can be named. What CGAL does not check (indices in
// range, finite coordinates, polygons of at least 3 corners, something left to scan) is checked
// after reading; PLY headers are checked before (see check_ply_header). Writing (binary STL,
// OBJ) is our own: a few lines each, exact, and what the twin and the reports read.
//
// CGAL's readers are 7 to 12 times slower than the hand-written ones they replace
// (mesh_file_bench, CPU time, medians: armadillo.off, 52k triangles, 84-122 ms against 8-12 ms;
// the same as binary STL 48-90 ms against 7-8 ms; bunny.obj 4.9-5.2 ms against 0.6-0.8 ms), but
// a mesh is loaded once by each process that needs it: at most about a tenth of a second per
// scan for the largest default mesh, against 800 lines of parsers of our own.
#include "core/io/mesh_file.hpp"
#include "core/base/atomic_file.hpp"

#include <CGAL/IO/OBJ.h>
#include <CGAL/IO/OFF.h>
#include <CGAL/IO/PLY.h>
#include <CGAL/IO/STL.h>
#include <CGAL/Simple_cartesian.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/base/format.hpp"
#include "core/io/file_checks.hpp"

namespace pbnbv {

namespace {

using Point = CGAL::Simple_cartesian<double>::Point_3;
using Polygon = std::vector<std::size_t>;

constexpr const char* kLoad = "load_mesh";

// Throws "<ctx>: <path>: <what>".
[[noreturn]] void fail(const char* ctx, const std::string& path, const std::string& what) {
  throw std::runtime_error(fmt::format("{}: {}: {}", ctx, path, what));
}

// `s` in lower case (ASCII).
std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Checks what the readers leave to the caller and fans polygons into triangles: every index
// within the points, every coordinate finite, every polygon with at least 3 corners.
TriangleMesh to_mesh(const std::string& path, const std::vector<Point>& points,
                     const std::vector<Polygon>& polygons) {
  TriangleMesh m;
  m.vertices.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Point& p = points[i];
    if (!(std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()))) {
      fail(kLoad, path, fmt::format("non-finite coordinate in vertex {} ({} {} {})", i, p.x(), p.y(), p.z()));
    }
    m.vertices.emplace_back(p.x(), p.y(), p.z());
  }
  if (points.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) fail(kLoad, path, "too many vertices");
  for (std::size_t f = 0; f < polygons.size(); ++f) {
    const Polygon& poly = polygons[f];
    if (poly.size() < 3) fail(kLoad, path, fmt::format("face {} has {} vertices, fewer than 3", f, poly.size()));
    for (const std::size_t v : poly) {
      // A negative OBJ index wraps around to a huge one: shown as the signed value it was.
      if (v >= points.size()) {
        fail(kLoad, path, fmt::format("face {}: vertex index {} out of range ({} vertices, counted from 0)", f,
                                      static_cast<long long>(v), points.size()));
      }
    }
    for (std::size_t k = 1; k + 1 < poly.size(); ++k) {
      m.triangles.emplace_back(static_cast<int>(poly[0]), static_cast<int>(poly[k]), static_cast<int>(poly[k + 1]));
    }
  }
  return m;
}

// Whether triangle `t` has a repeated corner or (relative to its longest edge) no area.
bool degenerate(const TriangleMesh& m, const Eigen::Vector3i& t) {
  if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
  const Eigen::Vector3d& a = m.vertices[static_cast<std::size_t>(t[0])];
  const Eigen::Vector3d& b = m.vertices[static_cast<std::size_t>(t[1])];
  const Eigen::Vector3d& c = m.vertices[static_cast<std::size_t>(t[2])];
  const Eigen::Vector3d e0 = b - a, e1 = c - a, e2 = c - b;
  const double cross = e0.cross(e1).norm();
  const double longest2 = std::max({e0.squaredNorm(), e1.squaredNorm(), e2.squaredNorm()});
  return !(cross > 1e-12 * longest2);
}

// Drops degenerate (zero-area) triangles, then checks that some are left and that the bounding
// box has a non-zero size along every axis.
void finish_mesh(TriangleMesh& m, const std::string& path) {
  if (m.triangles.empty()) fail(kLoad, path, "no triangles");
  const std::size_t before = m.triangles.size();
  m.triangles.erase(std::remove_if(m.triangles.begin(), m.triangles.end(),
                                   [&](const Eigen::Vector3i& t) { return degenerate(m, t); }),
                    m.triangles.end());
  if (m.triangles.empty()) {
    fail(kLoad, path, fmt::format("no triangles: all {} triangles are degenerate (zero area)", before));
  }
  Eigen::Vector3d lo, hi;
  mesh_bounds(m, lo, hi);
  const Eigen::Vector3d ext = hi - lo;
  for (int a = 0; a < 3; ++a) {
    if (!(ext[a] > 0.0)) {
      fail(kLoad, path, fmt::format("zero-size bounding box (extent {} x {} x {}, zero along {})", ext.x(),
                                    ext.y(), ext.z(), "xyz"[a]));
    }
  }
}

// Why an STL file gave nothing: a binary STL is 84 + 50 n bytes for the n triangles its header
// states; anything else that does not start with "solid" is a truncated or broken binary file.
std::string stl_failure(const std::string& path, std::uintmax_t size) {
  std::ifstream in(path, std::ios::binary);
  char head[84] = {};
  in.read(head, sizeof head);
  const std::size_t read = static_cast<std::size_t>(in.gcount());
  std::size_t i = 0;
  while (i < read && std::isspace(static_cast<unsigned char>(head[i]))) ++i;
  if (i + 5 <= read && std::strncmp(head + i, "solid", 5) == 0 && size < 84 + 50) {
    return "not a valid ASCII STL file (CGAL::IO::read_STL could not read it)";
  }
  if (size < 84) return fmt::format("truncated binary STL: {} bytes, shorter than the 84-byte header", size);
  std::uint32_t n = 0;
  for (int k = 3; k >= 0; --k) n = (n << 8) | static_cast<unsigned char>(head[80 + k]);
  const std::uint64_t expected = 84 + 50 * static_cast<std::uint64_t>(n);
  if (expected != size) {
    return fmt::format("truncated binary STL: header says {} triangles ({} bytes), file has {} bytes", n, expected,
                       size);
  }
  return "neither an ASCII nor a binary STL file CGAL::IO::read_STL can read";
}

// The counts an OFF header declares ("OFF" or a variant such as "COFF", then the vertex, face and
// edge counts, '#' comments allowed), checked against the file's size before CGAL reserves for
// them: a vertex takes at least 6 bytes ("0 0 0\n"), a face at least 8 ("3 0 1 2\n").
void check_off_counts(std::istream& in, const std::string& path) {
  struct Rewind {  // whatever is found, CGAL reads from the start
    std::istream& in;
    ~Rewind() {
      in.clear();
      in.seekg(0);
    }
  } rewind{in};
  std::vector<std::string> tokens;
  std::string line;
  std::uintmax_t line_number = 0;
  std::string rest;  // what follows the counts on their line: CGAL's scanner reads it as the next line
  while (tokens.size() < 4 && std::getline(in, line)) {
    ++line_number;
    std::istringstream words(line.substr(0, line.find('#')));
    for (std::string w; tokens.size() < 4 && words >> w;) tokens.push_back(w);
    if (tokens.size() == 4) std::getline(words, rest);
  }
  // Not an OFF header, or one with a dimension before the counts ("nOFF"): CGAL says what is wrong.
  if (tokens.size() < 4 || tokens[0].find("OFF") == std::string::npos || tokens[0].find("nOFF") != std::string::npos) return;
  const std::uintmax_t size = std::filesystem::file_size(path);
  auto count = [&](const std::string& t, const char* what, const char* plural, std::uintmax_t min_bytes) -> std::uintmax_t {
    std::uintmax_t n = 0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), n);
    if (ec != std::errc() || end != t.data() + t.size()) {
      fail(kLoad, path, fmt::format("the OFF header's {} count '{}' is not a whole number", what, t));
    }
    if (n > size / min_bytes) {
      fail(kLoad, path, fmt::format("the OFF header declares {} {}, more than a file of {} bytes can hold", n, plural, size));
    }
    return n;
  };
  const std::uintmax_t vertices = count(tokens[1], "vertex", "vertices", 6);
  const std::uintmax_t faces = count(tokens[2], "face", "faces", 8);
  // Each face's corner count, which CGAL reads as a double, casts and allocates for before reading
  // the corners: 0 to the vertex count (a polygon visits a vertex once) and to half the file's
  // size (an index takes two bytes). Lines as CGAL's scanner reads them after the header: one
  // vertex, then one face per line; blank and comment lines skipped.
  const double most = static_cast<double>(std::min<std::uintmax_t>(vertices, size / 2));
  std::uintmax_t vertex_lines = 0, face_lines = 0;
  bool from_rest = !rest.empty();  // the counts' line goes on: that first, then the next lines
  while (face_lines < faces && (from_rest || std::getline(in, line))) {
    if (from_rest) {
      line = rest;
      from_rest = false;
    } else {
      ++line_number;
    }
    const std::string text = line.substr(0, line.find('#'));
    if (text.find_first_not_of(" \t\r\v\f") == std::string::npos) continue;
    if (vertex_lines < vertices) {
      ++vertex_lines;
      continue;
    }
    ++face_lines;
    // The first number as CGAL's scanner reads it: a double, then cast to an unsigned count
    // (undefined for a negative or huge value).
    std::istringstream number(text);
    double corners = 0;
    if (!(number >> corners)) continue;
    if (!(corners >= 0 && corners <= most)) {
      fail(kLoad, path, fmt::format("line {}: face {} has {} corners; a face has 0 to {} (the vertices, and half the "
                                    "file's {} bytes)", line_number, face_lines, corners, most, size));
    }
    // Its corners, read the same way (a double cast to an unsigned index): each a vertex of the
    // file. A line with fewer numbers than it declares is CGAL's to name.
    // (Inside the loop corners >= 1, so vertices >= 1.)
    double index = 0;
    for (std::uintmax_t k = 0; k < static_cast<std::uintmax_t>(corners) && number >> index; ++k) {
      if (!(index >= 0 && index < static_cast<double>(vertices))) {
        fail(kLoad, path, fmt::format("line {}: corner {} of face {} is vertex {}; the file has vertices 0 to {}",
                                      line_number, k + 1, face_lines, index, vertices - 1));
      }
    }
  }
}

}  // namespace

TriangleMesh load_mesh(const std::string& path) {
  check_input_file(path, kLoad);
  const std::string ext = lower(std::filesystem::path(path).extension().string());
  if (ext != ".obj" && ext != ".off" && ext != ".stl" && ext != ".ply") {
    fail(kLoad, path, "unknown mesh file extension '" + ext + "' (expected .obj .stl .off .ply)");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(kLoad, path, std::string("cannot open file: ") + std::strerror(errno));

  std::vector<Point> points;
  std::vector<Polygon> polygons;
  const auto quiet = CGAL::parameters::verbose(false);
  if (ext == ".obj") {
    CGAL::IO::set_mode(in, CGAL::IO::ASCII);
    if (!CGAL::IO::read_OBJ(in, points, polygons, quiet)) {
      // The OBJ reader reads line by line and checks indices and emptiness only once it has
      // read every line: stopped at the end of the file, our checks of those say why, or else
      // it could not read the last line.
      in.clear();
      if (in.tellg() >= static_cast<std::streamoff>(std::filesystem::file_size(path))) {
        to_mesh(path, points, polygons);  // throws for an index out of range
        if (polygons.empty()) fail(kLoad, path, "no triangles");
      }
      fail(kLoad, path, "cannot read it as OBJ: CGAL::IO::read_OBJ stopped " + stopped_at(path, in, true));
    }
  } else if (ext == ".off") {
    check_off_counts(in, path);
    CGAL::IO::set_mode(in, CGAL::IO::ASCII);
    if (!CGAL::IO::read_OFF(in, points, polygons, quiet)) {
      fail(kLoad, path, "cannot read it as OFF: CGAL::IO::read_OFF stopped " + stopped_at(path, in, true));
    }
  } else if (ext == ".stl") {
    CGAL::IO::set_mode(in, CGAL::IO::BINARY);
    if (!CGAL::IO::read_STL(in, points, polygons, quiet) || polygons.empty()) {
      fail(kLoad, path, stl_failure(path, std::filesystem::file_size(path)));
    }
  } else {
    const PlyHeader header = check_ply_header(in, path, kLoad, true);
    in.clear();
    in.seekg(0);
    CGAL::IO::set_mode(in, CGAL::IO::BINARY);
    if (!CGAL::IO::read_PLY(in, points, polygons, quiet)) fail(kLoad, path, ply_failure(header, path, in));
  }
  TriangleMesh m = to_mesh(path, points, polygons);
  finish_mesh(m, path);
  return m;
}

void write_stl_binary(const TriangleMesh& mesh, const std::string& path) {
  const char* ctx = "write_stl_binary";
  if (mesh.triangles.size() > 0xffffffffull) fail(ctx, path, "too many triangles for STL");
  std::string out;
  out.reserve(84 + 50 * mesh.triangles.size());
  std::string header = "binary STL written by pbnbv";
  header.resize(80, ' ');
  out += header;
  auto put_u32 = [&](uint32_t u) {
    for (int k = 0; k < 4; ++k) out.push_back(static_cast<char>((u >> (8 * k)) & 0xff));
  };
  auto put_f32 = [&](float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    put_u32(u);
  };
  put_u32(static_cast<uint32_t>(mesh.triangles.size()));
  const long long nv = static_cast<long long>(mesh.vertices.size());
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || t[k] >= nv) fail(ctx, path, "triangle index out of range");
    }
    const Eigen::Vector3d& a = mesh.vertices[static_cast<size_t>(t[0])];
    const Eigen::Vector3d& b = mesh.vertices[static_cast<size_t>(t[1])];
    const Eigen::Vector3d& c = mesh.vertices[static_cast<size_t>(t[2])];
    Eigen::Vector3d nrm = (b - a).cross(c - a);
    const double len = nrm.norm();
    if (len > 0.0) nrm /= len;
    for (int k = 0; k < 3; ++k) put_f32(static_cast<float>(nrm[k]));
    for (const Eigen::Vector3d* v : {&a, &b, &c}) {
      for (int k = 0; k < 3; ++k) put_f32(static_cast<float>((*v)[k]));
    }
    out.push_back(0);
    out.push_back(0);
  }
  try {
    write_file_atomic(path, out);
  } catch (const std::runtime_error& e) {
    fail(ctx, path, e.what());
  }
}

void write_obj(const TriangleMesh& mesh, const std::string& path) {
  const char* ctx = "write_obj";
  std::string out;
  out.reserve(40 * mesh.vertices.size() + 24 * mesh.triangles.size() + 64);
  out += "# written by pbnbv\n";
  char num[64];
  for (const auto& v : mesh.vertices) {
    out += 'v';
    for (int k = 0; k < 3; ++k) {
      out += ' ';
      auto r = std::to_chars(num, num + sizeof(num), v[k]);  // shortest round-trip form
      out.append(num, r.ptr);
    }
    out += '\n';
  }
  const long long nv = static_cast<long long>(mesh.vertices.size());
  for (const auto& t : mesh.triangles) {
    out += 'f';
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || t[k] >= nv) fail(ctx, path, "triangle index out of range");
      out += ' ';
      auto r = std::to_chars(num, num + sizeof(num), t[k] + 1);
      out.append(num, r.ptr);
    }
    out += '\n';
  }
  try {
    write_file_atomic(path, out);
  } catch (const std::runtime_error& e) {
    fail(ctx, path, e.what());
  }
}

}  // namespace pbnbv
