#pragma once
// An order of points in which neighbours in space are mostly neighbours in the order (a Morton,
// or Z-order, curve): a batch of nearest-point queries taken in it walks the same part of a
// tree many times in a row, so the tree's nodes come from the cache rather than from memory.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace pbnbv {

// The indices 0 .. n-1 of `points` sorted by their Morton code (ties by index): the points'
// bounding box cut into 1024 cells along its longest edge (cells of that size along the others
// too, at most 1024), and the bits of a point's three cell indices interleaved, x lowest (a
// 30-bit code; finer cells would not change which tree nodes neighbours in the order share);
// the codes are computed on the workers of core/base/parallel.hpp. Throws std::invalid_argument
// "<what>: points[i] is not finite" for the first non-finite point, and for more than 2^32 - 1
// points.
std::vector<std::uint32_t> morton_order(const std::vector<Eigen::Vector3d>& points, const std::string& what);

}  // namespace pbnbv
