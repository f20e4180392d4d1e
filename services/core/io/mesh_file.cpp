// Mesh files. Reading OBJ, STL and PLY is CGAL's: the polygon-soup readers (read_OBJ, read_STL,
// read_PLY), called on a stream we hold so that, when one fails, the place where it stopped can
// be named. OFF is read by our own reader (read_off says why). What CGAL does not check (indices in
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
#include "core/base/version.hpp"
#include "core/base/atomic_file.hpp"

#include <CGAL/IO/OBJ.h>
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
#include <string_view>
#include <vector>

#include "core/base/format.hpp"
#include "core/io/file_checks.hpp"

namespace pbnbv {

namespace {

using Point = CGAL::Simple_cartesian<double>::Point_3;
using Polygon = std::vector<std::size_t>;

constexpr const char* kLoad = "load_mesh";

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
      file_error(kLoad, path, fmt::format("non-finite coordinate in vertex {} ({} {} {})", i, p.x(), p.y(), p.z()));
    }
    m.vertices.emplace_back(p.x(), p.y(), p.z());
  }
  if (points.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) file_error(kLoad, path, "too many vertices");
  for (std::size_t f = 0; f < polygons.size(); ++f) {
    const Polygon& poly = polygons[f];
    if (poly.size() < 3) file_error(kLoad, path, fmt::format("face {} has {} vertices, fewer than 3", f, poly.size()));
    for (const std::size_t v : poly) {
      // A negative OBJ index wraps around to a huge one: shown as the signed value it was.
      if (v >= points.size()) {
        file_error(kLoad, path, fmt::format("face {}: vertex index {} out of range ({} vertices, counted from 0)", f,
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
  if (m.triangles.empty()) file_error(kLoad, path, "no triangles");
  const std::size_t before = m.triangles.size();
  m.triangles.erase(std::remove_if(m.triangles.begin(), m.triangles.end(),
                                   [&](const Eigen::Vector3i& t) { return degenerate(m, t); }),
                    m.triangles.end());
  if (m.triangles.empty()) {
    file_error(kLoad, path, fmt::format("no triangles: all {} triangles are degenerate (zero area)", before));
  }
  Eigen::Vector3d lo, hi;
  mesh_bounds(m, lo, hi);
  const Eigen::Vector3d ext = hi - lo;
  for (int a = 0; a < 3; ++a) {
    if (!(ext[a] > 0.0)) {
      file_error(kLoad, path, fmt::format("zero-size bounding box (extent {} x {} x {}, zero along {})", ext.x(),
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

// The whitespace-separated words of `line` before any '#'.
std::vector<std::string_view> words_of(std::string_view line) {
  line = line.substr(0, line.find('#'));
  std::vector<std::string_view> words;
  constexpr std::string_view kSpace = " \t\r\v\f";
  for (std::size_t at = line.find_first_not_of(kSpace); at != std::string_view::npos;) {
    const std::size_t end = std::min(line.find_first_of(kSpace, at), line.size());
    words.push_back(line.substr(at, end - at));
    at = line.find_first_not_of(kSpace, end);
  }
  return words;
}

// An ASCII OFF file (Geomview's format: "OFF", or with the prefixes ST, C and N for texture
// coordinates, colours and normals, which are read past; the vertex, face and optional edge
// counts on the keyword's line or the next; one vertex, then one face per line, each face its
// corner count and corners, counted from 0, then an optional colour; '#' comments anywhere).
//
// Ours, not CGAL's: CGAL's scanner reads every count and index as a double, casts it to an
// unsigned integer (undefined for a negative or huge one) and allocates for the counts before
// checking them; fuzz_mesh_file found five ways past the checks we had put in front of it (a
// corner count of 4e18 or -4e15, a corner index of 2e88, a face on the counts' line, a keyword
// with bytes after it). Every number here is read whole, checked and bounded before it is used.
void read_off(std::istream& in, const std::string& path, std::vector<Point>& points,
              std::vector<Polygon>& polygons) {
  const std::uintmax_t size = std::filesystem::file_size(path);
  std::string line;
  std::uintmax_t line_number = 0;
  // The next line that has words, or an empty list at the end of the file.
  auto next_words = [&]() {
    while (std::getline(in, line)) {
      ++line_number;
      auto words = words_of(line);
      if (!words.empty()) return words;
    }
    return std::vector<std::string_view>{};
  };
  std::vector<std::string_view> words = next_words();
  if (words.empty()) file_error(kLoad, path, "not an OFF file: nothing but blank and comment lines");
  std::string_view keyword = words[0];
  for (std::string_view prefix : {"ST", "C", "N"}) {
    if (keyword.substr(0, prefix.size()) == prefix && keyword.size() > 3) keyword.remove_prefix(prefix.size());
  }
  if (keyword == "4OFF" || keyword == "nOFF" || keyword == "4nOFF") {
    file_error(kLoad, path, fmt::format("line {}: '{}' is an OFF file of 4 or n dimensions; only 3-D meshes are read",
                                        line_number, shown(words[0])));
  }
  if (keyword != "OFF") {
    file_error(kLoad, path, fmt::format("line {}: not an OFF file: it starts with '{}', not OFF (or COFF, NOFF, STOFF)",
                                        line_number, shown(words[0])));
  }
  words.erase(words.begin());
  if (!words.empty() && words[0] == "BINARY") {
    file_error(kLoad, path, fmt::format("line {}: a binary OFF file; only ASCII OFF is read", line_number));
  }
  if (words.empty()) words = next_words();
  if (words.size() < 2 || words.size() > 3) {
    file_error(kLoad, path, fmt::format("line {}: the OFF counts line has {} words; expected the vertex, face and edge "
                                        "counts", line_number, words.size()));
  }
  auto count = [&](std::string_view word, const char* what, const char* plural, std::uintmax_t min_bytes) {
    std::uint64_t n = 0;
    if (!whole_number(word, n)) {
      file_error(kLoad, path, fmt::format("the OFF header's {} count '{}' is not a whole number", what, shown(word)));
    }
    // A vertex takes at least 6 bytes ("0 0 0\n"), a face at least 8 ("3 0 1 2\n").
    if (n > size / min_bytes) {
      file_error(kLoad, path, fmt::format("the OFF header declares {} {}, more than a file of {} bytes can hold", n,
                                          plural, size));
    }
    return static_cast<std::size_t>(n);
  };
  const std::size_t vertices = count(words[0], "vertex", "vertices", 6);
  const std::size_t faces = count(words[1], "face", "faces", 8);
  if (words.size() == 3) count(words[2], "edge", "edges", 1);

  points.reserve(vertices);
  for (std::size_t v = 0; v < vertices; ++v) {
    words = next_words();
    if (words.empty()) {
      file_error(kLoad, path, fmt::format("the file ends after {} of the {} vertices its header declares", v, vertices));
    }
    double xyz[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k) {
      const std::string_view w = k < static_cast<int>(words.size()) ? words[static_cast<std::size_t>(k)] : "";
      const auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), xyz[k]);
      if (w.empty() || ec != std::errc() || end != w.data() + w.size() || !std::isfinite(xyz[k])) {
        file_error(kLoad, path, fmt::format("line {}: vertex {} '{}' is not three finite numbers", line_number, v,
                                            shown(line)));
      }
    }
    points.emplace_back(xyz[0], xyz[1], xyz[2]);
  }
  polygons.reserve(faces);
  for (std::size_t f = 1; f <= faces; ++f) {
    words = next_words();
    if (words.empty()) {
      file_error(kLoad, path, fmt::format("the file ends after {} of the {} faces its header declares", f - 1, faces));
    }
    std::uint64_t corners = 0;
    if (!whole_number(words[0], corners)) {
      file_error(kLoad, path, fmt::format("line {}: face {}'s corner count '{}' is not a whole number", line_number, f,
                                          shown(words[0])));
    }
    if (corners < 3) {
      file_error(kLoad, path, fmt::format("line {}: face {} has {} corners, fewer than 3", line_number, f, corners));
    }
    if (corners > vertices) {
      file_error(kLoad, path, fmt::format("line {}: face {} has {} corners, more than the file's {} vertices", line_number,
                                          f, corners, vertices));
    }
    if (words.size() - 1 < corners) {
      file_error(kLoad, path, fmt::format("line {}: face {} declares {} corners and lists {}", line_number, f, corners,
                                          words.size() - 1));
    }
    Polygon& polygon = polygons.emplace_back(static_cast<std::size_t>(corners));
    for (std::size_t k = 1; k <= corners; ++k) {
      std::uint64_t index = 0;
      if (!whole_number(words[k], index) || index >= vertices) {
        file_error(kLoad, path, fmt::format("line {}: corner {} of face {} is vertex '{}'; the file has vertices 0 to {}",
                                            line_number, k, f, shown(words[k]), vertices - 1));
      }
      polygon[k - 1] = static_cast<std::size_t>(index);
    }
  }
}

}  // namespace

TriangleMesh load_mesh(const std::string& path) {
  check_input_file(path, kLoad);
  const std::string ext = lower(std::filesystem::path(path).extension().string());
  if (ext != ".obj" && ext != ".off" && ext != ".stl" && ext != ".ply") {
    file_error(kLoad, path, "unknown mesh file extension '" + ext + "' (expected .obj .stl .off .ply)");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) file_error(kLoad, path, std::string("cannot open file: ") + std::strerror(errno));

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
        if (polygons.empty()) file_error(kLoad, path, "no triangles");
      }
      file_error(kLoad, path, "cannot read it as OBJ: CGAL::IO::read_OBJ stopped " + stopped_at(path, in, true));
    }
  } else if (ext == ".off") {
    read_off(in, path, points, polygons);
  } else if (ext == ".stl") {
    CGAL::IO::set_mode(in, CGAL::IO::BINARY);
    if (!CGAL::IO::read_STL(in, points, polygons, quiet) || polygons.empty()) {
      file_error(kLoad, path, stl_failure(path, std::filesystem::file_size(path)));
    }
  } else {
    const PlyHeader header = check_ply_header(in, path, kLoad, true);
    in.clear();
    in.seekg(0);
    CGAL::IO::set_mode(in, CGAL::IO::BINARY);
    if (!CGAL::IO::read_PLY(in, points, polygons, quiet)) file_error(kLoad, path, ply_failure(header, path, in));
  }
  TriangleMesh m = to_mesh(path, points, polygons);
  finish_mesh(m, path);
  return m;
}

const char* unit_symbol(LengthUnit unit) { return unit == LengthUnit::kMillimetre ? "mm" : "m"; }

LengthUnit parse_length_unit(const std::string& text) {
  if (text == "m") return LengthUnit::kMetre;
  if (text == "mm") return LengthUnit::kMillimetre;
  throw std::invalid_argument("unknown length unit '" + text + "' (expected m or mm)");
}

namespace {
double scale_of(LengthUnit unit) { return unit == LengthUnit::kMillimetre ? 1000.0 : 1.0; }
const char* unit_name(LengthUnit unit) { return unit == LengthUnit::kMillimetre ? "millimetres" : "metres"; }

void append_number(std::string& out, double v) {
  char num[64];
  const auto r = std::to_chars(num, num + sizeof(num), v);  // shortest round-trip form
  out.append(num, r.ptr);
}
}  // namespace

void write_stl_binary(const TriangleMesh& mesh, const std::string& path, LengthUnit unit) {
  const char* ctx = "write_stl_binary";
  if (mesh.triangles.size() > 0xffffffffull) file_error(ctx, path, "too many triangles for STL");
  const double scale = scale_of(unit);
  std::string out;
  out.reserve(84 + 50 * mesh.triangles.size());
  std::string header = "binary STL written by pbnbv " + std::string(pbnbv_version()) + ", units " + unit_name(unit);
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
      if (t[k] < 0 || t[k] >= nv) file_error(ctx, path, "triangle index out of range");
    }
    const Eigen::Vector3d& a = mesh.vertices[static_cast<size_t>(t[0])];
    const Eigen::Vector3d& b = mesh.vertices[static_cast<size_t>(t[1])];
    const Eigen::Vector3d& c = mesh.vertices[static_cast<size_t>(t[2])];
    Eigen::Vector3d nrm = (b - a).cross(c - a);
    const double len = nrm.norm();
    if (len > 0.0) nrm /= len;
    for (int k = 0; k < 3; ++k) put_f32(static_cast<float>(nrm[k]));
    for (const Eigen::Vector3d* v : {&a, &b, &c}) {
      for (int k = 0; k < 3; ++k) put_f32(static_cast<float>((*v)[k] * scale));
    }
    out.push_back(0);
    out.push_back(0);
  }
  try {
    write_file_atomic(path, out);
  } catch (const std::runtime_error& e) {
    file_error(ctx, path, e.what());
  }
}

void write_obj(const TriangleMesh& mesh, const std::string& path, const std::vector<Eigen::Vector3d>& normals,
               LengthUnit unit) {
  const char* ctx = "write_obj";
  if (!normals.empty() && normals.size() != mesh.vertices.size()) {
    throw std::invalid_argument(std::string(ctx) + ": " + path + ": " + std::to_string(normals.size()) +
                                " normals for " + std::to_string(mesh.vertices.size()) + " vertices");
  }
  const double scale = scale_of(unit);
  std::string out;
  out.reserve(40 * mesh.vertices.size() * (normals.empty() ? 1 : 2) + 24 * mesh.triangles.size() + 128);
  out += "# written by pbnbv " + std::string(pbnbv_version()) + "\n# units " + unit_name(unit) + "\n";
  for (const auto& v : mesh.vertices) {
    out += 'v';
    for (int k = 0; k < 3; ++k) {
      out += ' ';
      append_number(out, v[k] * scale);
    }
    out += '\n';
  }
  for (const auto& n : normals) {
    out += "vn";
    for (int k = 0; k < 3; ++k) {
      out += ' ';
      append_number(out, n[k]);
    }
    out += '\n';
  }
  const long long nv = static_cast<long long>(mesh.vertices.size());
  char num[32];
  for (const auto& t : mesh.triangles) {
    out += 'f';
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || t[k] >= nv) file_error(ctx, path, "triangle index out of range");
      out += ' ';
      const auto r = std::to_chars(num, num + sizeof(num), t[k] + 1);
      out.append(num, r.ptr);
      if (!normals.empty()) {
        out += "//";
        out.append(num, r.ptr);
      }
    }
    out += '\n';
  }
  try {
    write_file_atomic(path, out);
  } catch (const std::runtime_error& e) {
    file_error(ctx, path, e.what());
  }
}

}  // namespace pbnbv
