// How pbnbv view's page shades the drawn cloud. See cloud_look.hpp.
#include "core/view/cloud_look.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>


namespace pbnbv {

std::vector<Eigen::Vector3f> fitted_normals(const PointCloud& points) {
  if (points.size() < 3) return std::vector<Eigen::Vector3f>(points.size(), Eigen::Vector3f::Zero());
  SurfaceNormals s = estimate_normals(points, 12);
  for (std::size_t i = 0; i < points.size(); ++i) s.normals[i] = s.valid[i] ? Eigen::Vector3f(-s.normals[i]) : Eigen::Vector3f::Zero();
  return s.normals;
}

CloudLook look_from(const PointCloud& drawn, const PointCloud& from, const NeighbourIndex& index,
                    const std::vector<Eigen::Vector3f>& normals, const std::vector<Rgb>& colours, float max_m) {
  CloudLook look;
  const bool with_normals = !normals.empty() && normals.size() == from.size();
  const bool with_colours = !colours.empty() && colours.size() == from.size();
  if (with_normals) look.normals.assign(drawn.size(), Eigen::Vector3f::Zero());
  if (with_colours) look.colours.assign(drawn.size(), Rgb{128, 128, 128});
  if (!with_normals && !with_colours) return look;
  for (std::size_t i = 0; i < drawn.size(); ++i) {
    float d2 = 0;
    const int k = index.nearest(drawn[i], max_m * max_m, d2);
    if (k < 0) continue;
    if (with_normals) look.normals[i] = normals[static_cast<std::size_t>(k)];
    if (with_colours) look.colours[i] = colours[static_cast<std::size_t>(k)];
  }
  return look;
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
