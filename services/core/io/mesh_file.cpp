#include "core/io/mesh_file.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <thread>
#include <unordered_map>
#include <utility>

namespace pbnbv {

// ------------------------------------------------------------------------------------------
// Shared helpers (also used by cloud.cpp through the detail declarations below).
// ------------------------------------------------------------------------------------------
namespace detail {

// Reads a whole file into memory. `ctx` prefixes the error ("load_mesh", "read_ply").
std::string read_file_bytes(const std::string& path, const char* ctx);

// Reads the x y z of the "vertex" element of a PLY file (ascii, binary_little_endian,
// binary_big_endian) and, when `triangles` is not null, the faces of the "face" element fanned
// into triangles (indices checked against the vertex count). With `require_finite`, a non-finite
// coordinate is an error. Errors are std::runtime_error "<ctx>: <path>: ...".
void read_ply_file(const std::string& path, const char* ctx, bool require_finite,
                   std::vector<Eigen::Vector3d>& vertices, std::vector<Eigen::Vector3i>* triangles);

}  // namespace detail

namespace {

[[noreturn]] void fail(const char* ctx, const std::string& path, const std::string& what) {
  throw std::runtime_error(std::string(ctx) + ": " + path + ": " + what);
}

[[noreturn]] void fail_line(const char* ctx, const std::string& path, long line,
                            const std::string& what) {
  throw std::runtime_error(std::string(ctx) + ": " + path + ": line " + std::to_string(line) +
                           ": " + what);
}

constexpr const char* kLoad = "load_mesh";

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// Parses a whole token as a double (accepts a leading '+', "nan", "inf").
bool parse_double(std::string_view s, double& out) {
  if (s.empty()) return false;
  if (s.front() == '+') {
    s.remove_prefix(1);
    if (s.empty() || s.front() == '-' || s.front() == '+') return false;
  }
  const char* b = s.data();
  const char* e = b + s.size();
  auto r = std::from_chars(b, e, out, std::chars_format::general);
  if (r.ec == std::errc::result_out_of_range) {
    // Overflow: report as non-finite (caught by the finiteness check), underflow: zero-ish.
    double tmp = std::strtod(std::string(s).c_str(), nullptr);
    out = tmp;
    return r.ptr == e;
  }
  return r.ec == std::errc() && r.ptr == e;
}

bool parse_int(std::string_view s, long long& out) {
  if (s.empty()) return false;
  if (s.front() == '+') {
    s.remove_prefix(1);
    if (s.empty() || s.front() == '-') return false;
  }
  const char* b = s.data();
  const char* e = b + s.size();
  auto r = std::from_chars(b, e, out);
  return r.ec == std::errc() && r.ptr == e;
}

std::string quote(std::string_view s) {
  std::string t(s.substr(0, 40));
  return "'" + t + (s.size() > 40 ? "...'" : "'");
}

// Splits a buffer into lines (handles \n, \r\n), counting from 1.
class LineReader {
 public:
  explicit LineReader(std::string_view buf) : p_(buf.data()), end_(buf.data() + buf.size()) {}
  bool next(std::string_view& line) {
    if (p_ >= end_) return false;
    const char* nl = static_cast<const char*>(std::memchr(p_, '\n', static_cast<size_t>(end_ - p_)));
    const char* stop = nl ? nl : end_;
    line = std::string_view(p_, static_cast<size_t>(stop - p_));
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    p_ = nl ? nl + 1 : end_;
    ++line_no_;
    return true;
  }
  long line_no() const { return line_no_; }
  const char* position() const { return p_; }

 private:
  const char* p_;
  const char* end_;
  long line_no_ = 0;
};

void split(std::string_view line, std::vector<std::string_view>& toks) {
  toks.clear();
  size_t i = 0;
  const size_t n = line.size();
  while (i < n) {
    while (i < n && is_space(line[i])) ++i;
    if (i >= n) break;
    size_t j = i;
    while (j < n && !is_space(line[j])) ++j;
    toks.push_back(line.substr(i, j - i));
    i = j;
  }
}

std::string_view strip_comment(std::string_view line) {
  const size_t h = line.find('#');
  return h == std::string_view::npos ? line : line.substr(0, h);
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

double read_coord(const std::string& path, long line, std::string_view tok) {
  double v = 0.0;
  if (!parse_double(tok, v)) fail_line(kLoad, path, line, "malformed number " + quote(tok));
  if (!std::isfinite(v)) fail_line(kLoad, path, line, "non-finite coordinate " + quote(tok));
  return v;
}

// Fans polygon `poly` (0-based indices) into triangles.
void fan(const std::vector<int>& poly, std::vector<Eigen::Vector3i>& tris) {
  for (size_t k = 1; k + 1 < poly.size(); ++k) tris.emplace_back(poly[0], poly[k], poly[k + 1]);
}

bool degenerate(const TriangleMesh& m, const Eigen::Vector3i& t) {
  if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
  const Eigen::Vector3d& a = m.vertices[static_cast<size_t>(t[0])];
  const Eigen::Vector3d& b = m.vertices[static_cast<size_t>(t[1])];
  const Eigen::Vector3d& c = m.vertices[static_cast<size_t>(t[2])];
  const Eigen::Vector3d e0 = b - a, e1 = c - a, e2 = c - b;
  const double cross = e0.cross(e1).norm();
  const double longest2 = std::max({e0.squaredNorm(), e1.squaredNorm(), e2.squaredNorm()});
  return !(cross > 1e-12 * longest2);
}

// Common post-processing: drop degenerate triangles, check that something is left and that
// the bounding box has a non-zero size along every axis.
void finish_mesh(TriangleMesh& m, const std::string& path) {
  if (m.triangles.empty()) fail(kLoad, path, "no triangles");
  const size_t before = m.triangles.size();
  m.triangles.erase(std::remove_if(m.triangles.begin(), m.triangles.end(),
                                   [&](const Eigen::Vector3i& t) { return degenerate(m, t); }),
                    m.triangles.end());
  if (m.triangles.empty()) {
    fail(kLoad, path, "no triangles: all " + std::to_string(before) +
                          " triangles are degenerate (zero area)");
  }
  Eigen::Vector3d lo, hi;
  mesh_bounds(m, lo, hi);
  const Eigen::Vector3d ext = hi - lo;
  for (int a = 0; a < 3; ++a) {
    if (!(ext[a] > 0.0)) {
      std::ostringstream os;
      os << "zero-size bounding box (extent " << ext.x() << " x " << ext.y() << " x " << ext.z()
         << ", zero along " << "xyz"[a] << ")";
      fail(kLoad, path, os.str());
    }
  }
}

// ---- OBJ ---------------------------------------------------------------------------------
TriangleMesh load_obj(const std::string& path, const std::string& buf) {
  TriangleMesh m;
  std::vector<long> tri_line;  // source line of each triangle, for the range check
  LineReader lr(buf);
  std::string_view line;
  std::vector<std::string_view> toks;
  std::vector<int> poly;
  std::vector<long long> raw;
  while (lr.next(line)) {
    line = strip_comment(line);
    split(line, toks);
    if (toks.empty()) continue;
    const long ln = lr.line_no();
    if (toks[0] == "v") {
      if (toks.size() < 4) fail_line(kLoad, path, ln, "vertex needs 3 coordinates");
      m.vertices.emplace_back(read_coord(path, ln, toks[1]), read_coord(path, ln, toks[2]),
                              read_coord(path, ln, toks[3]));
    } else if (toks[0] == "f") {
      if (toks.size() < 4) fail_line(kLoad, path, ln, "face needs at least 3 vertices");
      poly.clear();
      for (size_t i = 1; i < toks.size(); ++i) {
        std::string_view t = toks[i];
        const size_t slash = t.find('/');
        std::string_view idx = slash == std::string_view::npos ? t : t.substr(0, slash);
        long long v = 0;
        if (!parse_int(idx, v)) fail_line(kLoad, path, ln, "malformed vertex index " + quote(t));
        long long zero_based;
        if (v > 0) {
          zero_based = v - 1;
        } else if (v < 0) {
          zero_based = static_cast<long long>(m.vertices.size()) + v;
          if (zero_based < 0) {
            fail_line(kLoad, path, ln,
                      "vertex index " + std::to_string(v) + " out of range (" +
                          std::to_string(m.vertices.size()) + " vertices defined so far)");
          }
        } else {
          fail_line(kLoad, path, ln, "vertex index 0 out of range (OBJ indices start at 1)");
        }
        if (zero_based > std::numeric_limits<int>::max()) {
          fail_line(kLoad, path, ln, "vertex index " + std::to_string(v) + " out of range");
        }
        poly.push_back(static_cast<int>(zero_based));
      }
      fan(poly, m.triangles);
      tri_line.resize(m.triangles.size(), ln);
    }
    // vt, vn, g, o, s, usemtl, mtllib, l, p ... are ignored.
  }
  const long long nv = static_cast<long long>(m.vertices.size());
  for (size_t i = 0; i < m.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (m.triangles[i][k] >= nv) {
        fail_line(kLoad, path, tri_line[i],
                  "vertex index " + std::to_string(m.triangles[i][k] + 1) + " out of range (" +
                      std::to_string(nv) + " vertices)");
      }
    }
  }
  return m;
}

// ---- STL ---------------------------------------------------------------------------------
struct VertexKeyHash {
  size_t operator()(const std::array<double, 3>& k) const {
    uint64_t h = 1469598103934665603ull;
    for (double d : k) {
      uint64_t b;
      std::memcpy(&b, &d, 8);
      h ^= b + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    }
    return static_cast<size_t>(h);
  }
};

class VertexMerger {
 public:
  explicit VertexMerger(TriangleMesh& m) : m_(m) {}
  int add(double x, double y, double z) {
    // +0.0 turns -0.0 into +0.0 so that exact-equal coordinates hash equally.
    const std::array<double, 3> key{x + 0.0, y + 0.0, z + 0.0};
    auto it = map_.find(key);
    if (it != map_.end()) return it->second;
    const int id = static_cast<int>(m_.vertices.size());
    m_.vertices.emplace_back(key[0], key[1], key[2]);
    map_.emplace(key, id);
    return id;
  }
  void reserve(size_t n) { map_.reserve(n); }

 private:
  TriangleMesh& m_;
  std::unordered_map<std::array<double, 3>, int, VertexKeyHash> map_;
};

uint32_t get_u32_le(const unsigned char* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
         (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}
float get_f32_le(const unsigned char* p) {
  const uint32_t u = get_u32_le(p);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

TriangleMesh load_stl_binary(const std::string& path, const std::string& buf, uint32_t n) {
  TriangleMesh m;
  VertexMerger merge(m);
  merge.reserve(static_cast<size_t>(n) / 2 + 8);
  m.vertices.reserve(static_cast<size_t>(n) / 2 + 8);
  m.triangles.reserve(n);
  const auto* base = reinterpret_cast<const unsigned char*>(buf.data());
  for (uint32_t i = 0; i < n; ++i) {
    const unsigned char* rec = base + 84 + static_cast<size_t>(i) * 50;
    int id[3];
    for (int k = 0; k < 3; ++k) {
      const unsigned char* v = rec + 12 + 12 * k;
      const double x = get_f32_le(v), y = get_f32_le(v + 4), z = get_f32_le(v + 8);
      if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
        fail(kLoad, path, "non-finite coordinate in triangle " + std::to_string(i));
      }
      id[k] = merge.add(x, y, z);
    }
    m.triangles.emplace_back(id[0], id[1], id[2]);
  }
  return m;
}

TriangleMesh load_stl_ascii(const std::string& path, const std::string& buf) {
  TriangleMesh m;
  VertexMerger merge(m);
  LineReader lr(buf);
  std::string_view line;
  std::vector<std::string_view> toks;
  std::vector<int> poly;
  bool in_loop = false;
  while (lr.next(line)) {
    split(line, toks);
    if (toks.empty()) continue;
    const long ln = lr.line_no();
    const std::string_view kw = toks[0];
    if (kw == "vertex") {
      if (!in_loop) fail_line(kLoad, path, ln, "'vertex' outside 'outer loop'");
      if (toks.size() < 4) fail_line(kLoad, path, ln, "vertex needs 3 coordinates");
      const double x = read_coord(path, ln, toks[1]);
      const double y = read_coord(path, ln, toks[2]);
      const double z = read_coord(path, ln, toks[3]);
      poly.push_back(merge.add(x, y, z));
    } else if (kw == "outer") {
      in_loop = true;
      poly.clear();
    } else if (kw == "endloop") {
      if (!in_loop) fail_line(kLoad, path, ln, "'endloop' without 'outer loop'");
      if (poly.size() < 3) fail_line(kLoad, path, ln, "facet with fewer than 3 vertices");
      fan(poly, m.triangles);
      in_loop = false;
    } else if (kw == "facet") {
      for (size_t i = 2; i < toks.size(); ++i) {
        double d;
        if (!parse_double(toks[i], d)) {
          fail_line(kLoad, path, ln, "malformed number " + quote(toks[i]));
        }
      }
    } else if (kw == "endfacet" || kw == "solid" || kw == "endsolid") {
      // nothing to do
    } else {
      fail_line(kLoad, path, ln, "unexpected keyword " + quote(kw));
    }
  }
  if (in_loop) fail(kLoad, path, "unexpected end of file inside a facet");
  return m;
}

TriangleMesh load_stl(const std::string& path, const std::string& buf) {
  const size_t size = buf.size();
  uint32_t n = 0;
  if (size >= 84) {
    n = get_u32_le(reinterpret_cast<const unsigned char*>(buf.data()) + 80);
    if (84 + 50 * static_cast<uint64_t>(n) == size) return load_stl_binary(path, buf, n);
  }
  // Not a well-sized binary file: ASCII if it starts with "solid" and looks like text.
  size_t i = 0;
  while (i < size && std::isspace(static_cast<unsigned char>(buf[i]))) ++i;
  const bool solid = buf.compare(i, 5, "solid") == 0;
  bool text = true;
  for (size_t k = 0; k < std::min<size_t>(size, 1024); ++k) {
    const auto c = static_cast<unsigned char>(buf[k]);
    if (c < 0x20 && c != '\n' && c != '\r' && c != '\t' && c != '\f' && c != '\v') {
      text = false;
      break;
    }
  }
  if (solid && text) return load_stl_ascii(path, buf);
  if (size < 84) {
    fail(kLoad, path, "truncated binary STL: " + std::to_string(size) +
                          " bytes, shorter than the 84-byte header");
  }
  fail(kLoad, path, "truncated binary STL: header says " + std::to_string(n) + " triangles (" +
                        std::to_string(84 + 50 * static_cast<uint64_t>(n)) +
                        " bytes), file has " + std::to_string(size) + " bytes");
}

// ---- OFF ---------------------------------------------------------------------------------
TriangleMesh load_off(const std::string& path, const std::string& buf) {
  TriangleMesh m;
  LineReader lr(buf);
  std::string_view line;
  std::vector<std::string_view> toks;
  auto next_tokens = [&]() -> bool {
    while (lr.next(line)) {
      split(strip_comment(line), toks);
      if (!toks.empty()) return true;
    }
    return false;
  };
  if (!next_tokens()) fail(kLoad, path, "empty OFF file");
  size_t first = 0;
  // Optional header keyword: [ST][C][N][4][n]OFF.
  {
    std::string_view kw = toks[0];
    if (kw.size() >= 3 && kw.substr(kw.size() - 3) == "OFF") {
      std::string_view prefix = kw.substr(0, kw.size() - 3);
      if (prefix.substr(0, 2) == "ST") prefix.remove_prefix(2);
      if (!prefix.empty() && prefix.front() == 'C') prefix.remove_prefix(1);
      if (!prefix.empty() && prefix.front() == 'N') prefix.remove_prefix(1);
      if (!prefix.empty() && (prefix.front() == '4' || prefix.front() == 'n')) {
        fail_line(kLoad, path, lr.line_no(), "unsupported OFF dimension in " + quote(kw));
      }
      if (!prefix.empty()) fail_line(kLoad, path, lr.line_no(), "unknown OFF header " + quote(kw));
      if (toks.size() > 1 && toks[1] == "BINARY") {
        fail_line(kLoad, path, lr.line_no(), "binary OFF is not supported");
      }
      first = 1;
    } else {
      double d;
      if (!parse_double(kw, d)) fail_line(kLoad, path, lr.line_no(), "missing OFF header");
    }
  }
  if (first >= toks.size()) {
    if (!next_tokens()) fail(kLoad, path, "missing vertex/face counts");
    first = 0;
  }
  if (toks.size() - first < 2) fail_line(kLoad, path, lr.line_no(), "missing vertex/face counts");
  long long nv = 0, nf = 0;
  if (!parse_int(toks[first], nv) || nv < 0) {
    fail_line(kLoad, path, lr.line_no(), "malformed vertex count " + quote(toks[first]));
  }
  if (!parse_int(toks[first + 1], nf) || nf < 0) {
    fail_line(kLoad, path, lr.line_no(), "malformed face count " + quote(toks[first + 1]));
  }
  if (nv > std::numeric_limits<int>::max()) fail_line(kLoad, path, lr.line_no(), "too many vertices");
  m.vertices.reserve(static_cast<size_t>(std::min<long long>(nv, 1 << 24)));
  for (long long i = 0; i < nv; ++i) {
    if (!next_tokens()) {
      fail(kLoad, path, "unexpected end of file: read " + std::to_string(i) + " of " +
                            std::to_string(nv) + " vertices");
    }
    const long ln = lr.line_no();
    if (toks.size() < 3) fail_line(kLoad, path, ln, "vertex needs 3 coordinates");
    m.vertices.emplace_back(read_coord(path, ln, toks[0]), read_coord(path, ln, toks[1]),
                            read_coord(path, ln, toks[2]));
  }
  std::vector<int> poly;
  for (long long f = 0; f < nf; ++f) {
    if (!next_tokens()) {
      fail(kLoad, path, "unexpected end of file: read " + std::to_string(f) + " of " +
                            std::to_string(nf) + " faces");
    }
    const long ln = lr.line_no();
    long long k = 0;
    if (!parse_int(toks[0], k) || k < 0) {
      fail_line(kLoad, path, ln, "malformed face size " + quote(toks[0]));
    }
    if (k < 3) fail_line(kLoad, path, ln, "face with fewer than 3 vertices");
    if (static_cast<long long>(toks.size()) < k + 1) {
      fail_line(kLoad, path, ln, "face lists fewer indices than its size " + std::to_string(k));
    }
    poly.clear();
    for (long long j = 1; j <= k; ++j) {
      long long v = 0;
      if (!parse_int(toks[static_cast<size_t>(j)], v)) {
        fail_line(kLoad, path, ln, "malformed vertex index " + quote(toks[static_cast<size_t>(j)]));
      }
      if (v < 0 || v >= nv) {
        fail_line(kLoad, path, ln, "vertex index " + std::to_string(v) + " out of range (" +
                                       std::to_string(nv) + " vertices)");
      }
      poly.push_back(static_cast<int>(v));
    }
    fan(poly, m.triangles);
  }
  return m;
}

// ---- PLY ---------------------------------------------------------------------------------
enum class PlyType { kI8, kU8, kI16, kU16, kI32, kU32, kF32, kF64 };

bool ply_type(std::string_view s, PlyType& t) {
  if (s == "char" || s == "int8") t = PlyType::kI8;
  else if (s == "uchar" || s == "uint8") t = PlyType::kU8;
  else if (s == "short" || s == "int16") t = PlyType::kI16;
  else if (s == "ushort" || s == "uint16") t = PlyType::kU16;
  else if (s == "int" || s == "int32") t = PlyType::kI32;
  else if (s == "uint" || s == "uint32") t = PlyType::kU32;
  else if (s == "float" || s == "float32") t = PlyType::kF32;
  else if (s == "double" || s == "float64") t = PlyType::kF64;
  else return false;
  return true;
}

size_t ply_size(PlyType t) {
  switch (t) {
    case PlyType::kI8:
    case PlyType::kU8: return 1;
    case PlyType::kI16:
    case PlyType::kU16: return 2;
    case PlyType::kI32:
    case PlyType::kU32:
    case PlyType::kF32: return 4;
    case PlyType::kF64: return 8;
  }
  return 0;
}

bool ply_integral(PlyType t) { return t != PlyType::kF32 && t != PlyType::kF64; }

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kF32;
  bool is_list = false;
  PlyType count_type = PlyType::kU8;
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> props;
};

enum class PlyFormat { kAscii, kBinaryLE, kBinaryBE };

// Reads values from the body of a PLY file, ascii or binary.
class PlyBody {
 public:
  PlyBody(const std::string& path, const char* ctx, const std::string& buf, size_t start,
          long first_line, PlyFormat fmt)
      : path_(path), ctx_(ctx), p_(buf.data() + start), end_(buf.data() + buf.size()),
        line_(first_line), fmt_(fmt) {}

  // Reads one scalar; `what` describes where, for the truncation error.
  double read(PlyType t, const std::string& what) {
    if (fmt_ == PlyFormat::kAscii) return read_ascii(t, what);
    const size_t n = ply_size(t);
    if (static_cast<size_t>(end_ - p_) < n) {
      fail(ctx_, path_, "truncated binary PLY: unexpected end of file in " + what);
    }
    unsigned char b[8];
    std::memcpy(b, p_, n);
    p_ += n;
    const bool swap = (fmt_ == PlyFormat::kBinaryBE) != host_big_endian();
    if (swap) std::reverse(b, b + n);
    switch (t) {
      case PlyType::kI8: { int8_t v; std::memcpy(&v, b, 1); return v; }
      case PlyType::kU8: { uint8_t v; std::memcpy(&v, b, 1); return v; }
      case PlyType::kI16: { int16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::kU16: { uint16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::kI32: { int32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::kU32: { uint32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::kF32: { float v; std::memcpy(&v, b, 4); return v; }
      case PlyType::kF64: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0.0;
  }

  // Reads a list count (integral, non-negative).
  uint64_t read_count(PlyType t, const std::string& what) {
    const double c = read(t, what);
    if (!(c >= 0.0) || c != std::floor(c) || c > 4.0e9) {
      fail_here("invalid list count in " + what);
    }
    return static_cast<uint64_t>(c);
  }

  void skip(PlyType t, uint64_t n, const std::string& what) {
    if (fmt_ == PlyFormat::kAscii) {
      for (uint64_t i = 0; i < n; ++i) read_ascii(t, what);
      return;
    }
    const uint64_t bytes = n * ply_size(t);
    if (static_cast<uint64_t>(end_ - p_) < bytes) {
      fail(ctx_, path_, "truncated binary PLY: unexpected end of file in " + what);
    }
    p_ += bytes;
  }

  long line() const { return line_; }
  bool ascii() const { return fmt_ == PlyFormat::kAscii; }

  [[noreturn]] void fail_here(const std::string& what) const {
    if (fmt_ == PlyFormat::kAscii) fail_line(ctx_, path_, tok_line_, what);
    fail(ctx_, path_, what);
  }

 private:
  static bool host_big_endian() {
    const uint16_t one = 1;
    unsigned char c;
    std::memcpy(&c, &one, 1);
    return c == 0;
  }

  double read_ascii(PlyType t, const std::string& what) {
    // Skip whitespace, counting lines.
    while (p_ < end_ && (is_space(*p_) || *p_ == '\n')) {
      if (*p_ == '\n') ++line_;
      ++p_;
    }
    if (p_ >= end_) fail(ctx_, path_, "unexpected end of file in " + what);
    const char* b = p_;
    while (p_ < end_ && !is_space(*p_) && *p_ != '\n') ++p_;
    tok_line_ = line_;
    const std::string_view tok(b, static_cast<size_t>(p_ - b));
    double v = 0.0;
    if (!parse_double(tok, v)) fail_line(ctx_, path_, line_, "malformed number " + quote(tok));
    if (ply_integral(t) && std::isfinite(v) && v != std::floor(v)) {
      fail_line(ctx_, path_, line_, "malformed integer " + quote(tok));
    }
    return v;
  }

  const std::string& path_;
  const char* ctx_;
  const char* p_;
  const char* end_;
  long line_;
  long tok_line_ = 0;
  PlyFormat fmt_;
};

}  // namespace

namespace detail {

std::string read_file_bytes(const std::string& path, const char* ctx) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  if (st.type() == std::filesystem::file_type::not_found) fail(ctx, path, "file does not exist");
  if (ec) fail(ctx, path, "cannot access file: " + ec.message());
  if (std::filesystem::is_directory(st)) fail(ctx, path, "is a directory, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(ctx, path, std::string("cannot open file: ") + std::strerror(errno));
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) fail(ctx, path, "cannot read file");
  in.seekg(0, std::ios::beg);
  std::string buf(static_cast<size_t>(size), '\0');
  if (size > 0 && !in.read(&buf[0], size)) fail(ctx, path, "cannot read file");
  return buf;
}

void read_ply_file(const std::string& path, const char* ctx, bool require_finite,
                   std::vector<Eigen::Vector3d>& vertices,
                   std::vector<Eigen::Vector3i>* triangles) {
  const std::string buf = read_file_bytes(path, ctx);
  vertices.clear();
  if (triangles) triangles->clear();

  // ---- header
  LineReader lr(buf);
  std::string_view line;
  std::vector<std::string_view> toks;
  if (!lr.next(line) || line != "ply") fail(ctx, path, "not a PLY file (missing 'ply' magic)");
  PlyFormat fmt = PlyFormat::kAscii;
  bool have_format = false, have_end = false;
  std::vector<PlyElement> elements;
  while (lr.next(line)) {
    const long ln = lr.line_no();
    split(line, toks);
    if (toks.empty()) continue;
    const std::string_view kw = toks[0];
    if (kw == "end_header") {
      have_end = true;
      break;
    } else if (kw == "comment" || kw == "obj_info") {
      continue;
    } else if (kw == "format") {
      if (toks.size() < 2) fail_line(ctx, path, ln, "malformed format line");
      if (toks[1] == "ascii") fmt = PlyFormat::kAscii;
      else if (toks[1] == "binary_little_endian") fmt = PlyFormat::kBinaryLE;
      else if (toks[1] == "binary_big_endian") fmt = PlyFormat::kBinaryBE;
      else fail_line(ctx, path, ln, "unknown PLY format " + quote(toks[1]));
      have_format = true;
    } else if (kw == "element") {
      if (toks.size() < 3) fail_line(ctx, path, ln, "malformed element line");
      long long c = 0;
      if (!parse_int(toks[2], c) || c < 0) {
        fail_line(ctx, path, ln, "malformed element count " + quote(toks[2]));
      }
      PlyElement e;
      e.name = std::string(toks[1]);
      e.count = static_cast<uint64_t>(c);
      elements.push_back(std::move(e));
    } else if (kw == "property") {
      if (elements.empty()) fail_line(ctx, path, ln, "property before any element");
      PlyProperty p;
      if (toks.size() >= 2 && toks[1] == "list") {
        if (toks.size() < 5) fail_line(ctx, path, ln, "malformed list property");
        if (!ply_type(toks[2], p.count_type) || !ply_integral(p.count_type)) {
          fail_line(ctx, path, ln, "bad list count type " + quote(toks[2]));
        }
        if (!ply_type(toks[3], p.type)) fail_line(ctx, path, ln, "unknown type " + quote(toks[3]));
        p.is_list = true;
        p.name = std::string(toks[4]);
      } else {
        if (toks.size() < 3) fail_line(ctx, path, ln, "malformed property");
        if (!ply_type(toks[1], p.type)) fail_line(ctx, path, ln, "unknown type " + quote(toks[1]));
        p.name = std::string(toks[2]);
      }
      elements.back().props.push_back(std::move(p));
    } else {
      fail_line(ctx, path, ln, "unexpected header line " + quote(line));
    }
  }
  if (!have_format) fail(ctx, path, "PLY header has no format line");
  if (!have_end) fail(ctx, path, "PLY header has no end_header");

  const PlyElement* vertex_el = nullptr;
  for (const auto& e : elements) {
    if (e.name == "vertex") vertex_el = &e;
  }
  if (!vertex_el) fail(ctx, path, "PLY has no 'vertex' element");
  int ix = -1, iy = -1, iz = -1;
  for (size_t i = 0; i < vertex_el->props.size(); ++i) {
    const auto& p = vertex_el->props[i];
    const int ii = static_cast<int>(i);
    if (p.name == "x" && !p.is_list) ix = ii;
    if (p.name == "y" && !p.is_list) iy = ii;
    if (p.name == "z" && !p.is_list) iz = ii;
  }
  if (ix < 0 || iy < 0 || iz < 0) fail(ctx, path, "PLY vertex element lacks x, y or z");
  if (vertex_el->count > static_cast<uint64_t>(std::numeric_limits<int>::max())) {
    fail(ctx, path, "too many vertices");
  }

  // ---- body
  const size_t body_start = static_cast<size_t>(lr.position() - buf.data());
  PlyBody body(path, ctx, buf, body_start, lr.line_no() + 1, fmt);
  bool vertices_done = false;
  std::vector<int> poly;
  for (const auto& e : elements) {
    const bool is_vertex = &e == vertex_el;
    const bool is_face = triangles && e.name == "face";
    if (!triangles && vertices_done) break;  // a point cloud needs nothing after the vertices
    if (is_vertex) {
      vertices.reserve(static_cast<size_t>(e.count));
      const std::string what = "element 'vertex'";
      double xyz[3] = {0, 0, 0};
      for (uint64_t i = 0; i < e.count; ++i) {
        for (size_t j = 0; j < e.props.size(); ++j) {
          const auto& p = e.props[j];
          if (p.is_list) {
            body.skip(p.type, body.read_count(p.count_type, what), what);
            continue;
          }
          const double v = body.read(p.type, what);
          const int jj = static_cast<int>(j);
          if (jj == ix) xyz[0] = v;
          else if (jj == iy) xyz[1] = v;
          else if (jj == iz) xyz[2] = v;
        }
        if (require_finite &&
            !(std::isfinite(xyz[0]) && std::isfinite(xyz[1]) && std::isfinite(xyz[2]))) {
          body.fail_here("non-finite coordinate in vertex " + std::to_string(i));
        }
        vertices.emplace_back(xyz[0], xyz[1], xyz[2]);
      }
      vertices_done = true;
    } else if (is_face) {
      int iv = -1;
      for (size_t j = 0; j < e.props.size(); ++j) {
        const auto& p = e.props[j];
        if (p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index")) {
          iv = static_cast<int>(j);
        }
      }
      if (iv < 0) fail(ctx, path, "PLY face element has no vertex_indices list");
      const std::string what = "element 'face'";
      const long long nv = static_cast<long long>(vertex_el->count);  // faces may come first
      triangles->reserve(static_cast<size_t>(std::min<uint64_t>(e.count, 1u << 26)));
      for (uint64_t f = 0; f < e.count; ++f) {
        for (size_t j = 0; j < e.props.size(); ++j) {
          const auto& p = e.props[j];
          if (static_cast<int>(j) != iv) {
            if (p.is_list) body.skip(p.type, body.read_count(p.count_type, what), what);
            else body.skip(p.type, 1, what);
            continue;
          }
          const uint64_t k = body.read_count(p.count_type, what);
          if (k < 3) body.fail_here("face " + std::to_string(f) + " has fewer than 3 vertices");
          poly.clear();
          for (uint64_t q = 0; q < k; ++q) {
            const double v = body.read(p.type, what);
            if (!(v >= 0.0) || v >= static_cast<double>(nv) || v != std::floor(v)) {
              std::ostringstream os;
              os << "face " << f << ": vertex index " << v << " out of range (" << nv
                 << " vertices)";
              body.fail_here(os.str());
            }
            poly.push_back(static_cast<int>(v));
          }
          fan(poly, *triangles);
        }
      }
    } else {
      const std::string what = "element '" + e.name + "'";
      for (uint64_t i = 0; i < e.count; ++i) {
        for (const auto& p : e.props) {
          if (p.is_list) body.skip(p.type, body.read_count(p.count_type, what), what);
          else body.skip(p.type, 1, what);
        }
      }
    }
  }
}

}  // namespace detail

// ------------------------------------------------------------------------------------------
// Public API
// ------------------------------------------------------------------------------------------
TriangleMesh load_mesh(const std::string& path) {
  const std::string ext = lower(std::filesystem::path(path).extension().string());
  // Existence first, so a missing file is reported as such whatever its name.
  if (ext == ".ply") {
    TriangleMesh m;
    detail::read_ply_file(path, kLoad, true, m.vertices, &m.triangles);
    finish_mesh(m, path);
    return m;
  }
  const std::string buf = detail::read_file_bytes(path, kLoad);
  TriangleMesh m;
  if (ext == ".obj") m = load_obj(path, buf);
  else if (ext == ".stl") m = load_stl(path, buf);
  else if (ext == ".off") m = load_off(path, buf);
  else fail(kLoad, path, "unknown mesh file extension '" + ext + "' (expected .obj .stl .off .ply)");
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
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) fail(ctx, path, std::string("cannot open for writing: ") + std::strerror(errno));
  f.write(out.data(), static_cast<std::streamsize>(out.size()));
  f.close();
  if (!f) fail(ctx, path, "write failed");
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
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) fail(ctx, path, std::string("cannot open for writing: ") + std::strerror(errno));
  f.write(out.data(), static_cast<std::streamsize>(out.size()));
  f.close();
  if (!f) fail(ctx, path, "write failed");
}

}  // namespace pbnbv
