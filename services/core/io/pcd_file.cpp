// PCD reading: our own header parser and body reader (PCL's io library would bring VTK along).
#include "core/io/pcd_file.hpp"

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include "core/io/file_checks.hpp"

namespace pbnbv {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw std::runtime_error(fmt::format("read_pcd: {}: {}", path, what));
}

struct Field {
  std::string name;
  int size = 4;
  char type = 'F';
  int count = 1;
};

std::vector<std::string> words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> w;
  for (std::string s; in >> s;) w.push_back(s);
  return w;
}

}  // namespace

PointCloud read_pcd(const std::string& path) {
  check_input_file(path, "read_pcd");
  std::ifstream in(path, std::ios::binary);
  std::vector<Field> fields;
  long long points = -1;
  std::string data;
  for (std::string line; data.empty() && std::getline(in, line);) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::vector<std::string> w = words(line);
    if (w.empty() || w[0][0] == '#') continue;
    const std::string& key = w[0];
    const std::size_t n = w.size() - 1;
    try {
      if (key == "FIELDS") {
        fields.assign(n, Field{});
        for (std::size_t i = 0; i < n; ++i) fields[i].name = w[i + 1];
      } else if (key == "SIZE" || key == "TYPE" || key == "COUNT") {
        if (n != fields.size()) fail(path, fmt::format("{} has {} entries for {} FIELDS", key, n, fields.size()));
        for (std::size_t i = 0; i < n; ++i) {
          if (key == "SIZE") fields[i].size = std::stoi(w[i + 1]);
          if (key == "TYPE") fields[i].type = w[i + 1][0];
          if (key == "COUNT") fields[i].count = std::stoi(w[i + 1]);
        }
      } else if (key == "POINTS" && n == 1) {
        points = std::stoll(w[1]);
      } else if (key == "DATA" && n == 1) {
        data = w[1];
      }
    } catch (const std::logic_error&) {  // stoi / stoll
      fail(path, "header line '" + line + "' is not a number where one is expected");
    }
  }
  if (fields.empty()) fail(path, "no FIELDS line: not a PCD file");
  if (points < 0) fail(path, "no POINTS line in the header");
  if (data.empty()) fail(path, "no DATA line in the header");
  int ix = -1, iy = -1, iz = -1;
  std::size_t stride = 0;
  std::vector<std::size_t> offset(fields.size());
  std::vector<std::size_t> column(fields.size());
  std::size_t columns = 0;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const Field& f = fields[i];
    if (f.size <= 0 || f.count <= 0) fail(path, "field " + f.name + " has a size or count below 1");
    if (f.size > 8) fail(path, fmt::format("field {} has SIZE {}; a PCD value takes 1, 2, 4 or 8 bytes", f.name, f.size));
    offset[i] = stride;
    column[i] = columns;
    stride += static_cast<std::size_t>(f.size) * f.count;
    columns += f.count;
    int* slot = f.name == "x" ? &ix : f.name == "y" ? &iy : f.name == "z" ? &iz : nullptr;
    if (!slot) continue;
    if (f.type != 'F' || (f.size != 4 && f.size != 8) || f.count != 1) {
      fail(path, "field " + f.name + " must be TYPE F, SIZE 4 or 8, COUNT 1");
    }
    *slot = static_cast<int>(i);
  }
  if (ix < 0 || iy < 0 || iz < 0) fail(path, "the FIELDS have no x, y and z");
  const int xyz[3] = {ix, iy, iz};

  // What the header declares, bounded by the file before anything is allocated for it (found by
  // fuzz_cloud_file: POINTS 4999...9, a reservation of 60 TB): a point of an ASCII body takes at
  // least two bytes a value ("0 "), one of a binary body its stride.
  const std::uintmax_t file_bytes = std::filesystem::file_size(path);
  const std::uintmax_t point_bytes = data == "ascii" ? 2 * static_cast<std::uintmax_t>(columns) : stride;
  if (stride > file_bytes) {
    fail(path, fmt::format("the FIELDS take {} bytes a point, more than the file's {} bytes", stride, file_bytes));
  }
  if (static_cast<std::uintmax_t>(points) > file_bytes / point_bytes) {
    fail(path, fmt::format("POINTS {}: more points than a file of {} bytes can hold ({} bytes a point at least)", points,
                           file_bytes, point_bytes));
  }
  PointCloud cloud;
  cloud.reserve(static_cast<std::size_t>(points));
  if (data == "ascii") {
    std::string line;
    for (long long k = 0; k < points; ++k) {
      if (!std::getline(in, line)) fail(path, fmt::format("the body ends after {} of {} points", k, points));
      const std::vector<std::string> w = words(line);
      if (w.size() < columns) fail(path, fmt::format("point {} has {} values, expected {}", k, w.size(), columns));
      Eigen::Vector3f p;
      for (int a = 0; a < 3; ++a) {
        try {
          p[a] = std::stof(w[column[xyz[a]]]);
        } catch (const std::out_of_range&) {
          p[a] = std::numeric_limits<float>::quiet_NaN();
        } catch (const std::logic_error&) {
          fail(path, fmt::format("point {}: '{}' is not a number", k, w[column[xyz[a]]]));
        }
      }
      cloud.push_back(p);
    }
  } else if (data == "binary") {
    std::vector<char> body(stride * static_cast<std::size_t>(points));
    in.read(body.data(), static_cast<std::streamsize>(body.size()));
    if (static_cast<std::size_t>(in.gcount()) != body.size()) {
      fail(path, fmt::format("the binary body has {} bytes, {} points of {} bytes need {}", in.gcount(), points, stride,
                             body.size()));
    }
    for (long long k = 0; k < points; ++k) {
      const char* row = body.data() + stride * static_cast<std::size_t>(k);
      Eigen::Vector3f p;
      for (int a = 0; a < 3; ++a) {
        const char* at = row + offset[xyz[a]];
        if (fields[xyz[a]].size == 4) {
          std::memcpy(&p[a], at, 4);
        } else {
          double d;
          std::memcpy(&d, at, 8);
          p[a] = static_cast<float>(d);
        }
      }
      cloud.push_back(p);
    }
  } else if (data == "binary_compressed") {
    fail(path, "DATA binary_compressed is not supported: save the cloud as binary or ascii PCD (or PLY)");
  } else {
    fail(path, "DATA '" + data + "' is not ascii, binary or binary_compressed");
  }
  return cloud;
}

}  // namespace pbnbv
