#include "core/registration.hpp"

#include <pcl/common/centroid.h>
#include <pcl/features/normal_3d.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/correspondence_rejection.h>
#include <pcl/registration/icp.h>
#include <pcl/search/kdtree.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace pbnbv {

namespace {

using Clock = std::chrono::steady_clock;
// Point-to-plane ICP (linear least squares, double precision estimation); exposes the
// iteration count pcl keeps protected.
class Icp : public pcl::IterativeClosestPointWithNormals<pcl::PointNormal, pcl::PointNormal,
                                                          double> {
 public:
  int iterations() const { return nr_iterations_; }
};
using Criteria = pcl::registration::DefaultConvergenceCriteria<double>;

double knob(const char* name, double def) {
  const char* v = std::getenv(name);
  return v ? std::atof(v) : def;
}

// A static 3-d tree over the xyz of a cloud, answering the k-NN and radius queries of
// pcl::search with far less per-query overhead than the FLANN-backed pcl::search::KdTree (no
// allocation, no OpenMP region per query). Thread-safe for queries; used by the normal
// estimation, ICP's correspondence search and the overlap gate.
template <typename PointT>
class FastKdTree : public pcl::search::KdTree<PointT> {
 public:
  using Base = pcl::search::KdTree<PointT>;
  using typename Base::PointCloudConstPtr;
  using typename Base::IndicesConstPtr;
  using pcl::search::Search<PointT>::nearestKSearch;
  using pcl::search::Search<PointT>::radiusSearch;
  using Ptr = pcl::shared_ptr<FastKdTree<PointT>>;

  FastKdTree() : Base(true) {}

  void setInputCloud(const PointCloudConstPtr& cloud,
                     const IndicesConstPtr& indices = IndicesConstPtr()) override {
    this->input_ = cloud;
    this->indices_ = indices;
    pts_.clear();
    ids_.clear();
    nodes_.clear();
    if (!cloud) return;
    auto add = [&](pcl::index_t i) {
      const auto& p = (*cloud)[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return;
      pts_.push_back(p.getVector3fMap());
      ids_.push_back(i);
    };
    if (indices) {
      for (pcl::index_t i : *indices) add(i);
    } else {
      for (pcl::index_t i = 0; i < static_cast<pcl::index_t>(cloud->size()); ++i) add(i);
    }
    nodes_.reserve(2 * pts_.size() / kLeaf + 2);
    if (!pts_.empty()) build(0, static_cast<int>(pts_.size()));
  }

  int nearestKSearch(const PointT& point, int k, pcl::Indices& k_indices,
                     std::vector<float>& k_sqr_distances) const override {
    if (k == 1) {  // ICP's correspondence search
      k_indices.resize(1);
      k_sqr_distances.resize(1);
      float d2;
      const pcl::index_t i = nearest(point.getVector3fMap(), k1_bound_d2_, d2);
      if (i < 0) {  // nothing within the bound: report a miss pcl's distance test drops
        k_indices[0] = ids_.empty() ? 0 : ids_[0];
        k_sqr_distances[0] = std::numeric_limits<float>::max();
        return ids_.empty() ? 0 : 1;
      }
      k_indices[0] = i;
      k_sqr_distances[0] = d2;
      return 1;
    }
    return knn(point.getVector3fMap(), k, std::numeric_limits<float>::infinity(), k_indices,
               k_sqr_distances);
  }

  int radiusSearch(const PointT& point, double radius, pcl::Indices& k_indices,
                   std::vector<float>& k_sqr_distances, unsigned int max_nn = 0) const override {
    k_indices.clear();
    k_sqr_distances.clear();
    if (nodes_.empty()) return 0;
    const float r2 = static_cast<float>(radius * radius);
    const Eigen::Vector3f q = point.getVector3fMap();
    std::vector<std::pair<float, pcl::index_t>> found;
    radius_rec(0, q, r2, found);
    std::sort(found.begin(), found.end());
    if (max_nn > 0 && found.size() > max_nn) found.resize(max_nn);
    for (const auto& f : found) {
      k_sqr_distances.push_back(f.first);
      k_indices.push_back(f.second);
    }
    return static_cast<int>(found.size());
  }

  // Single-neighbour queries (ICP's correspondences) only look this far (squared, m^2); a query
  // with nothing nearer gets a miss at distance FLT_MAX. Keeps far-off frames cheap.
  void set_k1_bound(double d) { k1_bound_d2_ = static_cast<float>(d * d); }

  // Nearest point within sqrt(max_d2): its original index, or -1.
  pcl::index_t nearest(const Eigen::Vector3f& q, float max_d2, float& d2) const {
    d2 = max_d2;
    int best = -1;
    if (!nodes_.empty()) nn_rec(0, q, d2, best);
    return best < 0 ? -1 : ids_[best];
  }

 private:
  static constexpr int kLeaf = 8;
  struct Node {
    float split;
    int dim;  // -1: leaf over [begin, end)
    int begin, end;
    int left, right;
  };

  int build(int begin, int end) {
    const int id = static_cast<int>(nodes_.size());
    nodes_.push_back({0.f, -1, begin, end, -1, -1});
    if (end - begin <= kLeaf) return id;
    Eigen::Vector3f lo = pts_[begin], hi = pts_[begin];
    for (int i = begin + 1; i < end; ++i) {
      lo = lo.cwiseMin(pts_[i]);
      hi = hi.cwiseMax(pts_[i]);
    }
    int dim;
    (hi - lo).maxCoeff(&dim);
    const int mid = (begin + end) / 2;
    // Sort the permutation of [begin, end) by the split coordinate around the median.
    std::vector<int> order(end - begin);
    for (int i = 0; i < end - begin; ++i) order[i] = begin + i;
    std::nth_element(order.begin(), order.begin() + (mid - begin), order.end(),
                     [&](int a, int b) { return pts_[a][dim] < pts_[b][dim]; });
    std::vector<Eigen::Vector3f> p2(end - begin);
    std::vector<pcl::index_t> i2(end - begin);
    for (int i = 0; i < end - begin; ++i) {
      p2[i] = pts_[order[i]];
      i2[i] = ids_[order[i]];
    }
    std::copy(p2.begin(), p2.end(), pts_.begin() + begin);
    std::copy(i2.begin(), i2.end(), ids_.begin() + begin);
    const float split = pts_[mid][dim];
    const int left = build(begin, mid);
    const int right = build(mid, end);
    nodes_[id].split = split;
    nodes_[id].dim = dim;
    nodes_[id].left = left;
    nodes_[id].right = right;
    return id;
  }

  void nn_rec(int n, const Eigen::Vector3f& q, float& d2, int& best) const {
    const Node& nd = nodes_[n];
    if (nd.dim < 0) {
      for (int i = nd.begin; i < nd.end; ++i) {
        const float d = (pts_[i] - q).squaredNorm();
        if (d < d2 || (d == d2 && best < 0)) {
          d2 = d;
          best = i;
        }
      }
      return;
    }
    const float diff = q[nd.dim] - nd.split;
    const int first = diff < 0 ? nd.left : nd.right;
    const int second = diff < 0 ? nd.right : nd.left;
    nn_rec(first, q, d2, best);
    if (diff * diff <= d2) nn_rec(second, q, d2, best);
  }

  // Sorted best-k lists in fixed arrays (k is small here); falls back to a heap for large k.
  int knn(const Eigen::Vector3f& q, int k, float max_d2, pcl::Indices& out_i,
          std::vector<float>& out_d) const {
    out_i.clear();
    out_d.clear();
    if (k <= 0 || nodes_.empty()) return 0;
    k = std::min<int>(k, static_cast<int>(pts_.size()));
    std::vector<std::pair<float, int>> best;
    best.reserve(k + 1);
    knn_rec(0, q, k, max_d2, best);
    for (const auto& b : best) {
      out_d.push_back(b.first);
      out_i.push_back(ids_[b.second]);
    }
    return static_cast<int>(best.size());
  }

  void knn_rec(int n, const Eigen::Vector3f& q, int k, float max_d2,
               std::vector<std::pair<float, int>>& best) const {
    const Node& nd = nodes_[n];
    if (nd.dim < 0) {
      for (int i = nd.begin; i < nd.end; ++i) {
        const float d = (pts_[i] - q).squaredNorm();
        if (static_cast<int>(best.size()) == k ? d >= best.back().first : d > max_d2) continue;
        auto it = std::upper_bound(best.begin(), best.end(), std::make_pair(d, i));
        best.insert(it, {d, i});
        if (static_cast<int>(best.size()) > k) best.pop_back();
      }
      return;
    }
    const float diff = q[nd.dim] - nd.split;
    const int first = diff < 0 ? nd.left : nd.right;
    const int second = diff < 0 ? nd.right : nd.left;
    knn_rec(first, q, k, max_d2, best);
    const float worst = static_cast<int>(best.size()) < k ? max_d2 : best.back().first;
    if (diff * diff <= worst) knn_rec(second, q, k, max_d2, best);
  }

  void radius_rec(int n, const Eigen::Vector3f& q, float r2,
                  std::vector<std::pair<float, pcl::index_t>>& found) const {
    const Node& nd = nodes_[n];
    if (nd.dim < 0) {
      for (int i = nd.begin; i < nd.end; ++i) {
        const float d = (pts_[i] - q).squaredNorm();
        if (d <= r2) found.emplace_back(d, ids_[i]);
      }
      return;
    }
    const float diff = q[nd.dim] - nd.split;
    const int first = diff < 0 ? nd.left : nd.right;
    const int second = diff < 0 ? nd.right : nd.left;
    radius_rec(first, q, r2, found);
    if (diff * diff <= r2) radius_rec(second, q, r2, found);
  }

  std::vector<Eigen::Vector3f> pts_;
  std::vector<pcl::index_t> ids_;
  std::vector<Node> nodes_;
  float k1_bound_d2_ = std::numeric_limits<float>::infinity();
};

// Drops correspondences whose surface normals disagree by more than an angle (unsigned: the
// normals are not oriented consistently). Uses the source normals as given at the start of the
// stage; the rotation within a stage is a few degrees at most, well inside the threshold.
class NormalCompatibilityRejector : public pcl::registration::CorrespondenceRejector {
 public:
  NormalCompatibilityRejector(pcl::PointCloud<pcl::PointNormal>::ConstPtr source,
                              pcl::PointCloud<pcl::PointNormal>::ConstPtr target, double max_deg)
      : source_(std::move(source)), target_(std::move(target)),
        min_cos_(static_cast<float>(std::cos(max_deg * 3.14159265358979323846 / 180.0))) {
    rejection_name_ = "NormalCompatibilityRejector";
  }
  void set_rotation(const Eigen::Matrix3f& r) { rotation_ = r; }
  void getRemainingCorrespondences(const pcl::Correspondences& in,
                                   pcl::Correspondences& out) override {
    out.clear();
    out.reserve(in.size());
    for (const auto& c : in) {
      const Eigen::Vector3f ns = rotation_ * (*source_)[c.index_query].getNormalVector3fMap();
      const float d = ns.dot((*target_)[c.index_match].getNormalVector3fMap());
      if (std::fabs(d) < min_cos_) continue;
      if ((*source_)[c.index_query].curvature > max_curv_ ||
          (*target_)[c.index_match].curvature > max_curv_) continue;
      out.push_back(c);
    }
  }

 protected:
  void applyRejection(pcl::Correspondences& out) override {
    getRemainingCorrespondences(*input_correspondences_, out);
  }

 private:
  pcl::PointCloud<pcl::PointNormal>::ConstPtr source_, target_;
  Eigen::Matrix3f rotation_ = Eigen::Matrix3f::Identity();
  float min_cos_;
 public:
  float max_curv_ = 1.0f;
};

constexpr double kPi = 3.14159265358979323846;
const int kNormalNeighbours = static_cast<int>(knob("REG_K", 12));  // k-NN for the normals of the downsampled clouds

std::string fmt(const char* f, double a) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, a);
  return buf;
}

// One point per occupied voxel of edge `voxel`: the input point nearest to the centroid of the
// voxel's points. Unlike the centroid itself it lies on the measured surface (a centroid at an
// edge or a corner sits inside the object), which keeps ICP free of the grid's bias.
PointCloud pick_downsample(const PointCloud& cloud, double voxel) {
  if (!(voxel > 0) || cloud.empty()) return cloud;
  struct Item {
    int64_t x, y, z;
    uint32_t i;
  };
  std::vector<Item> items;
  items.reserve(cloud.size());
  for (uint32_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d q = (cloud[i].cast<double>() / voxel).array().floor();
    if (!(q.cwiseAbs().maxCoeff() < 1e15)) continue;
    items.push_back({static_cast<int64_t>(q.x()), static_cast<int64_t>(q.y()),
                     static_cast<int64_t>(q.z()), i});
  }
  std::sort(items.begin(), items.end(), [](const Item& a, const Item& b) {
    return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z != b.z ? a.z < b.z : a.i < b.i;
  });
  PointCloud out;
  for (size_t b = 0; b < items.size();) {
    size_t e = b + 1;
    while (e < items.size() && items[e].x == items[b].x && items[e].y == items[b].y &&
           items[e].z == items[b].z) {
      ++e;
    }
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (size_t k = b; k < e; ++k) c += cloud[items[k].i].cast<double>();
    c /= static_cast<double>(e - b);
    size_t best = b;
    double best_d = std::numeric_limits<double>::infinity();
    for (size_t k = b; k < e; ++k) {
      const double d = (cloud[items[k].i].cast<double>() - c).squaredNorm();
      if (d < best_d) {
        best_d = d;
        best = k;
      }
    }
    out.push_back(cloud[items[best].i]);
    b = e;
  }
  return out;
}

PointCloud finite_points(const PointCloud& in) {
  PointCloud out;
  out.reserve(in.size());
  for (const auto& p : in) {
    if (p.allFinite()) out.push_back(p);
  }
  return out;
}

// Surface points with normals: for every point a plane is fitted to its k nearest neighbours
// (pcl's covariance + eigen plane fit, as in pcl::NormalEstimation, on two threads with the
// fast tree), and the point is moved onto that plane. The projection removes the sensor noise
// across the surface and, more importantly, the "double layer" a voxel grid leaves where a
// noisy surface runs along a grid plane (points on either side of the boundary average into
// two sheets ~0.5 mm apart), which otherwise pins ICP at a few tenths of a degree off.
pcl::PointCloud<pcl::PointNormal>::Ptr with_normals(const PointCloud& pts, bool project) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr xyz(new pcl::PointCloud<pcl::PointXYZ>);
  xyz->resize(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    (*xyz)[i].getVector3fMap() = pts[i];
  }
  pcl::PointCloud<pcl::PointNormal> all;
  all.resize(pts.size());
  std::vector<char> ok(pts.size(), 0);
  if (pts.size() >= 3) {
    FastKdTree<pcl::PointXYZ> tree;
    tree.setInputCloud(xyz);
    const int k = std::min<int>(kNormalNeighbours, static_cast<int>(pts.size()));
    auto work = [&](size_t begin, size_t end) {
      pcl::Indices nn;
      std::vector<float> d2;
      Eigen::Matrix3f cov;
      Eigen::Vector4f centroid;
      for (size_t i = begin; i < end; ++i) {
        if (tree.nearestKSearch((*xyz)[i], k, nn, d2) < 3) continue;
        if (pcl::computeMeanAndCovarianceMatrix(*xyz, nn, cov, centroid) < 3) continue;
        float nx, ny, nz, curvature;
        pcl::solvePlaneParameters(cov, nx, ny, nz, curvature);
        const Eigen::Vector3f n(nx, ny, nz);
        if (!n.allFinite() || !(n.norm() > 0.5f)) continue;
        Eigen::Vector3f p = pts[i];
        if (project) p -= (p - centroid.head<3>()).dot(n) * n;
        auto& o = all[i];
        o.getVector3fMap() = p;
        o.getNormalVector3fMap() = n;
        o.curvature = curvature;
        ok[i] = 1;
      }
    };
    const size_t threads = std::max<size_t>(
        1, std::min<size_t>({std::thread::hardware_concurrency(), 4, pts.size() / 2000 + 1}));
    std::vector<std::thread> pool;
    const size_t chunk = (pts.size() + threads - 1) / threads;
    for (size_t t = 1; t < threads; ++t) {
      pool.emplace_back(work, std::min(pts.size(), t * chunk), std::min(pts.size(), (t + 1) * chunk));
    }
    work(0, std::min(pts.size(), chunk));
    for (auto& th : pool) th.join();
  }
  pcl::PointCloud<pcl::PointNormal>::Ptr out(new pcl::PointCloud<pcl::PointNormal>);
  out->reserve(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    if (ok[i]) out->push_back(all[i]);
  }
  out->width = static_cast<uint32_t>(out->size());
  out->height = 1;
  out->is_dense = true;
  return out;
}

}  // namespace

PointCloud transform_cloud(const PointCloud& cloud, const Pose& transform) {
  PointCloud out;
  out.reserve(cloud.size());
  const Eigen::Matrix3d r = transform.linear();
  const Eigen::Vector3d t = transform.translation();
  for (const auto& p : cloud) {
    out.push_back((r * p.cast<double>() + t).cast<float>());
  }
  return out;
}

RegistrationResult register_frame(const PointCloud& model, const PointCloud& frame,
                                  const RegistrationParams& params) {
  const auto t0 = Clock::now();
  RegistrationResult res;
  auto finish = [&]() -> RegistrationResult {
    res.time_s = std::chrono::duration<double>(Clock::now() - t0).count();
    return res;
  };

  try {
    const PointCloud model_f = finite_points(model);
    const PointCloud frame_f = finite_points(frame);
    const size_t dropped = (model.size() - model_f.size()) + (frame.size() - frame_f.size());
    const std::string dropped_note =
        dropped ? " (" + std::to_string(dropped) + " non-finite points dropped)" : "";

    if (model_f.empty()) {
      res.accepted = true;
      res.converged = true;
      res.reason = "first frame: defines the model" + dropped_note;
      return finish();
    }

    const double voxel = knob("REG_VOXEL", params.voxel_m);
    const float goff = static_cast<float>(knob("REG_GOFF", 0.0) * voxel);
    auto ds = [&](const PointCloud& c) {
      if (goff == 0.0f) return voxel_downsample(c, voxel);
      PointCloud sh = c;
      for (auto& p : sh) p.array() += goff;
      PointCloud out = voxel_downsample(sh, voxel);
      for (auto& p : out) p.array() -= goff;
      return out;
    };
    const PointCloud model_ds = ds(model_f);
    const PointCloud frame_ds = ds(frame_f);
    const size_t min_points = static_cast<size_t>(std::max(params.min_points, 3));
    if (frame_ds.size() < min_points || model_ds.size() < min_points) {
      res.reason = "rejected: too few points: frame " + std::to_string(frame_ds.size()) +
                   ", model " + std::to_string(model_ds.size()) + " after " +
                   fmt("%.1f", voxel * 1e3) + " mm downsampling (of " +
                   std::to_string(frame_f.size()) + " and " + std::to_string(model_f.size()) +
                   " finite points), need " + std::to_string(min_points) + dropped_note;
      return finish();
    }

    // Only the part of the model the frame can reach matters: crop it to the frame's box grown
    // by the largest correspondence distance plus room for the normals.
    Eigen::Vector3f lo = frame_ds.front(), hi = frame_ds.front();
    for (const auto& p : frame_ds) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const float margin = static_cast<float>(
        std::max(params.max_correspondence_m, params.overlap_distance_m) + 4.0 * voxel);
    lo.array() -= margin;
    hi.array() += margin;
    PointCloud model_crop;
    model_crop.reserve(model_ds.size());
    for (const auto& p : model_ds) {
      if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all()) {
        model_crop.push_back(p);
      }
    }

    const auto tn = Clock::now();
    const bool project = knob("REG_PROJ", 1) > 0;
    const auto target = with_normals(model_crop, project);
    const auto source = with_normals(frame_ds, project);

    if (std::getenv("PBNBV_REG_DEBUG")) {
      std::fprintf(stderr, "prep %.1f ms normals %.1f ms\n",
                   std::chrono::duration<double>(tn - t0).count() * 1e3,
                   std::chrono::duration<double>(Clock::now() - tn).count() * 1e3);
    }
    FastKdTree<pcl::PointNormal>::Ptr tree(new FastKdTree<pcl::PointNormal>);
    Eigen::Matrix4d t_final = Eigen::Matrix4d::Identity();
    std::string icp_note;
    if (target->size() >= 3) tree->setInputCloud(target);

    if (target->size() >= 10 && source->size() >= 10) {
      Icp icp;
      icp.setInputSource(source);
      icp.setInputTarget(target);
      icp.setSearchMethodTarget(tree, true);
      icp.setMaximumIterations(std::max(params.max_iterations, 1));
      const double teps = knob("REG_TEPS", 1e-5), reps = knob("REG_REPS", 1e-3);
      icp.setTransformationEpsilon(teps * teps);          // squared step
      icp.setTransformationRotationEpsilon(std::cos(reps * kPi / 180.0));
      icp.getConvergeCriteria()->setMaximumIterationsSimilarTransforms(static_cast<int>(knob("REG_SIM", 0)));
      icp.setEuclideanFitnessEpsilon(1e-9);
      // Coarse to fine: each stage halves the correspondence distance, ending near the
      // overlap distance so the frame's unseen-by-the-model part does not pull.
      auto rejector = std::make_shared<NormalCompatibilityRejector>(
          source, target, knob("REG_NANGLE", 30.0));
      rejector->max_curv_ = static_cast<float>(knob("REG_CURV", 1.0));
      if (knob("REG_NANGLE", 30.0) < 90) icp.addCorrespondenceRejector(rejector);
      if (knob("REG_SYMM", 0) > 0) icp.setUseSymmetricObjective(true);
      std::vector<double> stages;
      const double finest = knob("REG_FINAL", std::max(params.overlap_distance_m, 1.5 * voxel));
      for (double d = params.max_correspondence_m; d > finest * 1.0001; d *= 0.5) {
        stages.push_back(d);
      }
      stages.push_back(std::min(finest, params.max_correspondence_m));
      pcl::PointCloud<pcl::PointNormal> aligned;
      bool converged = false;
      int state = Criteria::CONVERGENCE_CRITERIA_NOT_CONVERGED;
      for (double d : stages) {
        icp.setMaxCorrespondenceDistance(d);
        tree->set_k1_bound(d * 1.001);
        const auto ts = Clock::now();
        rejector->set_rotation(t_final.topLeftCorner<3, 3>().cast<float>());
        icp.align(aligned, t_final);
        if (std::getenv("PBNBV_REG_DEBUG")) {
          std::fprintf(stderr, "stage %.4f: %d it, %.1f ms, state %d, src %zu tgt %zu\n", d,
                       icp.iterations(),
                       std::chrono::duration<double>(Clock::now() - ts).count() * 1e3,
                       static_cast<int>(icp.getConvergeCriteria()->getConvergenceState()),
                       source->size(), target->size());
        }
        res.iterations += icp.iterations();
        state = icp.getConvergeCriteria()->getConvergenceState();
        converged = icp.hasConverged();
        if (state == Criteria::CONVERGENCE_CRITERIA_NO_CORRESPONDENCES) {
          icp_note = fmt("no correspondences within %.1f mm", d * 1e3);
          break;
        }
        t_final = icp.getFinalTransformation();
      }
      res.converged = converged && state != Criteria::CONVERGENCE_CRITERIA_ITERATIONS &&
                      state != Criteria::CONVERGENCE_CRITERIA_FAILURE_AFTER_MAX_ITERATIONS;
      if (!res.converged && icp_note.empty()) {
        icp_note = "ICP did not converge in " + std::to_string(params.max_iterations) +
                   " iterations";
      }
    } else {
      icp_note = "no model points near the frame";
    }

    // Orthonormalise the correction (the estimate is a product of small rigid steps).
    Pose correction = Pose::Identity();
    {
      const Eigen::Matrix3d r = t_final.topLeftCorner<3, 3>();
      Eigen::Quaterniond q(r);
      q.normalize();
      correction.linear() = q.toRotationMatrix();
      correction.translation() = t_final.topRightCorner<3, 1>();
    }
    if (!correction.matrix().allFinite()) {
      correction = Pose::Identity();
      res.converged = false;
      icp_note = "ICP produced a non-finite transform";
    }
    res.correction = correction;
    res.translation_m = correction.translation().norm();
    res.rotation_deg =
        Eigen::AngleAxisd(correction.linear()).angle() * 180.0 / kPi;

    // Gates, on the downsampled frame after alignment against the cropped model.
    size_t n_overlap = 0;
    double sum_sq = 0;
    if (target->size() >= 3) {
      const float r2 = static_cast<float>(params.overlap_distance_m * params.overlap_distance_m);
      const Eigen::Matrix3f r = correction.linear().cast<float>();
      const Eigen::Vector3f t = correction.translation().cast<float>();
      pcl::PointNormal q;
      for (const auto& p : frame_ds) {
        q.getVector3fMap() = r * p + t;
        float d2;
        const pcl::index_t i = tree->nearest(q.getVector3fMap(), r2, d2);
        if (i < 0) continue;
        ++n_overlap;
        // Point-to-plane distance to the model's local surface.
        const auto& m = (*target)[i];
        const double e = (q.getVector3fMap() - m.getVector3fMap())
                             .cast<double>()
                             .dot(m.getNormalVector3fMap().cast<double>());
        sum_sq += e * e;
      }
    }
    res.overlap = static_cast<double>(n_overlap) / static_cast<double>(frame_ds.size());
    res.rmse_m = n_overlap ? std::sqrt(sum_sq / static_cast<double>(n_overlap)) : 0.0;

    std::vector<std::string> fails;
    if (res.overlap < params.min_overlap) {
      fails.push_back(fmt("overlap %.2f", res.overlap) + fmt(" below %.2f", params.min_overlap));
    }
    if (n_overlap == 0 || res.rmse_m > params.max_rmse_m) {
      fails.push_back(n_overlap == 0 ? std::string("rmse undefined (no overlapping points)")
                                     : fmt("rmse %.2f mm", res.rmse_m * 1e3) +
                                           fmt(" exceeds %.2f mm", params.max_rmse_m * 1e3));
    }
    if (res.translation_m > params.max_translation_m) {
      fails.push_back(fmt("correction %.3f m", res.translation_m) +
                      fmt(" exceeds %.3f m", params.max_translation_m));
    }
    if (res.rotation_deg > params.max_rotation_deg) {
      fails.push_back(fmt("correction %.2f deg", res.rotation_deg) +
                      fmt(" exceeds %.2f deg", params.max_rotation_deg));
    }
    if (!res.converged) fails.push_back("not converged: " + icp_note);

    if (fails.empty()) {
      res.accepted = true;
      res.reason = "accepted: " + fmt("%.2f mm, ", res.translation_m * 1e3) +
                   fmt("%.3f deg, ", res.rotation_deg) + fmt("overlap %.2f, ", res.overlap) +
                   fmt("rmse %.2f mm", res.rmse_m * 1e3) + dropped_note;
    } else {
      res.accepted = false;
      res.reason = "rejected: ";
      for (size_t i = 0; i < fails.size(); ++i) res.reason += (i ? "; " : "") + fails[i];
      res.reason += dropped_note;
    }
    return finish();
  } catch (const std::exception& e) {
    res = RegistrationResult{};
    res.reason = std::string("rejected: registration failed: ") + e.what();
    return finish();
  } catch (...) {
    res = RegistrationResult{};
    res.reason = "rejected: registration failed";
    return finish();
  }
}

}  // namespace pbnbv
