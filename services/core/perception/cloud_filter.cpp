#include "core/perception/cloud_filter.hpp"

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

namespace {

int bit_width(uint64_t v) {
  int b = 0;
  while (v) {
    ++b;
    v >>= 1;
  }
  return b;
}

struct KeyIndex {
  uint64_t key;
  uint32_t index;
};

// Stable LSD radix sort on the low `bits` bits of the key, digits of at most 12 bits.
void radix_sort(std::vector<KeyIndex>& a, int bits) {
  if (bits <= 0 || a.size() < 2) return;
  const int passes = (bits + 11) / 12;
  const int digit = (bits + passes - 1) / passes;
  const size_t buckets = size_t{1} << digit;
  const uint64_t mask = buckets - 1;
  std::vector<KeyIndex> tmp(a.size());
  std::vector<size_t> count(buckets);
  for (int pass = 0, shift = 0; pass < passes; ++pass, shift += digit) {
    std::fill(count.begin(), count.end(), 0);
    for (const auto& e : a) ++count[(e.key >> shift) & mask];
    size_t sum = 0;
    for (auto& c : count) {
      const size_t m = c;
      c = sum;
      sum += m;
    }
    for (const auto& e : a) tmp[count[(e.key >> shift) & mask]++] = e;
    a.swap(tmp);
  }
}

// Appends the centroid of a run of points [b, e) of `cloud`, all in one voxel, to `out`.
inline void emit_centroid(const PointCloud& cloud, const KeyIndex* b, const KeyIndex* e, PointCloud& out) {
  double sx = 0, sy = 0, sz = 0;
  for (const KeyIndex* it = b; it != e; ++it) {
    const Eigen::Vector3f& p = cloud[it->index];
    sx += p.x();
    sy += p.y();
    sz += p.z();
  }
  const double inv = 1.0 / static_cast<double>(e - b);
  out.emplace_back(static_cast<float>(sx * inv), static_cast<float>(sy * inv), static_cast<float>(sz * inv));
}

// The range [lo, hi] of the points' voxel indices; returns how many points have one.
std::size_t voxel_range(const PointCloud& cloud, double voxel_m, int64_t lo[3], int64_t hi[3]) {
  for (int k = 0; k < 3; ++k) {
    lo[k] = std::numeric_limits<int64_t>::max();
    hi[k] = std::numeric_limits<int64_t>::min();
  }
  std::size_t n = 0;
  for (const auto& p : cloud) {
    int64_t q[3];
    if (!voxel_index(p, voxel_m, q)) continue;
    ++n;
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], q[k]);
      hi[k] = std::max(hi[k], q[k]);
    }
  }
  return n;
}

// The centroids by packed key (x, then y, then z: lexicographic order, bits[k] bits each from
// lo), radix-sorted, one per run of equal keys.
void downsample_packed(const PointCloud& cloud, double voxel_m, std::size_t n, const int64_t lo[3], const int bits[3],
                       PointCloud& out) {
  std::vector<KeyIndex> ki;
  ki.reserve(n);
  for (size_t i = 0; i < cloud.size(); ++i) {
    int64_t q[3];
    if (!voxel_index(cloud[i], voxel_m, q)) continue;
    uint64_t key = static_cast<uint64_t>(q[0]) - static_cast<uint64_t>(lo[0]);
    for (int k = 1; k < 3; ++k) {
      key = bits[k] ? (key << bits[k]) : key;
      key |= static_cast<uint64_t>(q[k]) - static_cast<uint64_t>(lo[k]);
    }
    ki.push_back({key, static_cast<uint32_t>(i)});
  }
  radix_sort(ki, bits[0] + bits[1] + bits[2]);
  size_t j = 0;
  while (j < n) {
    size_t e = j + 1;
    while (e < n && ki[e].key == ki[j].key) ++e;
    emit_centroid(cloud, &ki[j], &ki[e], out);
    j = e;
  }
}

// Keys too wide to pack: index triples sorted (stable, so the summation order is fixed).
void downsample_wide(const PointCloud& cloud, double voxel_m, std::size_t n, PointCloud& out) {
  struct Wide {
    int64_t q[3];
    uint32_t index;
  };
  std::vector<Wide> w;
  w.reserve(n);
  for (size_t i = 0; i < cloud.size(); ++i) {
    Wide x;
    if (!voxel_index(cloud[i], voxel_m, x.q)) continue;
    x.index = static_cast<uint32_t>(i);
    w.push_back(x);
  }
  std::stable_sort(w.begin(), w.end(), [](const Wide& a, const Wide& b) {
    return std::lexicographical_compare(a.q, a.q + 3, b.q, b.q + 3);
  });
  std::vector<KeyIndex> run;
  size_t j = 0;
  while (j < n) {
    size_t e = j;
    run.clear();
    while (e < n && std::equal(w[e].q, w[e].q + 3, w[j].q)) run.push_back({0, w[e++].index});
    emit_centroid(cloud, run.data(), run.data() + run.size(), out);
    j = e;
  }
}

}  // namespace

PointCloud voxel_downsample(const PointCloud& cloud, double voxel_m) {
  if (!(voxel_m > 0.0) || !std::isfinite(voxel_m)) return cloud;
  if (cloud.size() > std::numeric_limits<uint32_t>::max()) {
    throw std::invalid_argument("voxel_downsample: too many points");
  }
  int64_t lo[3], hi[3];
  const std::size_t n = voxel_range(cloud, voxel_m, lo, hi);
  PointCloud out;
  if (n == 0) return out;
  int bits[3];
  for (int k = 0; k < 3; ++k) bits[k] = bit_width(static_cast<uint64_t>(hi[k]) - static_cast<uint64_t>(lo[k]));
  if (bits[0] + bits[1] + bits[2] <= 64) {
    downsample_packed(cloud, voxel_m, n, lo, bits, out);
  } else {
    downsample_wide(cloud, voxel_m, n, out);
  }
  return out;
}

}  // namespace pbnbv
