// pbnbv-ellipsoids: the ellipsoid fitter.
//   in:  VOXEL_MAP
//   out: ELLIPSOIDS, HEARTBEAT
// For every voxel map, clusters the Occupied and the Frontier voxel centres with a Gaussian
// mixture (T in [1, T_max] by BIC) and publishes the minimum-volume enclosing ellipsoid of each
// cluster, fitted to voxel corners (docs/method.md "Ellipsoids"; core fit_ellipsoids). Idempotent:
// a map already answered (same scan, iteration and request id) is answered again with the stored
// result. The answer carries the map's request id: the map of another request for the same view
// (a forgery with a guessed id) gets its own answer, never the real map's.
#include <chrono>
#include <map>
#include <sstream>
#include <tuple>

#include "bus/bus.hpp"
#include "bus/convert.hpp"
#include "bus/convert_planning.hpp"
#include "bus/reply_cache.hpp"
#include "bus/service.hpp"
#include "core/planning/ellipsoid_fit.hpp"
#include "core/base/log.hpp"
#include "pbnbv/ellipsoid_set_t.hpp"
#include "pbnbv/voxel_set_t.hpp"

using namespace pbnbv;

namespace {

constexpr std::size_t kAnswersKept = 64;

// The centres of one class ("occupied", "frontier") of a VOXEL_MAP's voxels; throws naming the
// class and the index of a centre that is not finite.
std::vector<Eigen::Vector3d> centres(const std::vector<std::vector<float>>& rows, const char* what) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Eigen::Vector3d p(rows[i][0], rows[i][1], rows[i][2]);
    if (!p.allFinite()) {
      throw std::invalid_argument(std::string("VOXEL_MAP ") + what + " centre " + std::to_string(i) + " is not finite");
    }
    out.push_back(p);
  }
  return out;
}

class EllipsoidService {
 public:
  EllipsoidService(bus::Bus& bus, int t_max, uint64_t seed) : bus_(bus), t_max_(t_max), seed_(seed) {
    bus_.subscribe<voxel_set_t>(channels::kVoxelMap, [this](const voxel_set_t& m) { on_map(m); });
  }

 private:
  void on_map(const voxel_set_t& m) {
    bus_.set_scan(m.scan_id, m.iteration);
    const auto key = std::make_tuple(m.scan_id, m.iteration, m.request_id);
    if (const ellipsoid_set_t* answer = answers_.find(key)) {
      bus_.publish(channels::kEllipsoids, *answer);
      return;
    }
    bus::require_range(m.resolution_m, 1e-4, 1.0, "VOXEL_MAP resolution_m");
    const std::vector<Eigen::Vector3d> occupied = centres(m.occupied_centres_m, "occupied");
    const std::vector<Eigen::Vector3d> frontier = centres(m.frontier_centres_m, "frontier");

    EllipsoidParams p;
    p.t_max = t_max_;
    p.seed = seed_;
    p.voxel_m = m.resolution_m;
    const auto t0 = std::chrono::steady_clock::now();
    int t_occ = 0, t_front = 0;
    const std::vector<Ellipsoid> all = fit_both_classes(occupied, frontier, p, &t_occ, &t_front);
    const double fit_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    ellipsoid_set_t out;
    out.scan_id = m.scan_id;
    out.iteration = m.iteration;
    out.request_id = m.request_id;
    out.occupied_components = t_occ;
    out.frontier_components = t_front;
    out.fit_s = fit_s;
    for (const auto& e : all) out.ellipsoids.push_back(bus::to_msg(e));
    out.num_ellipsoids = static_cast<int32_t>(out.ellipsoids.size());
    out.utime = bus::now_utime();
    bus_.publish(channels::kEllipsoids, out);
    answers_.put(key, out);
    std::ostringstream os;
    os << "view " << m.iteration << ": " << occupied.size() << " occupied voxels -> T = " << t_occ << ", "
       << frontier.size() << " frontier voxels -> T = " << t_front << " (" << fit_s * 1e3 << " ms)";
    log_info(os.str());
  }

  bus::Bus& bus_;
  int t_max_;
  uint64_t seed_;
  bus::ReplyCache<std::tuple<std::string, int32_t, int64_t>, ellipsoid_set_t> answers_{kAnswersKept};
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pbnbv-ellipsoids: fits the ellipsoids of every VOXEL_MAP (Gaussian mixture + BIC, MVEE)",
               "pbnbv-ellipsoids"};
  cli::init(app);
  int t_max = 0;
  int64_t seed = 0;
  cli::add(app, kTMax, &t_max);
  cli::add(app, kMixtureSeed, &seed);
  return bus::run_service("ellipsoids", app, argc, argv, 50, [&](bus::Bus& bus) -> std::function<void()> {
    auto service = std::make_shared<EllipsoidService>(bus, t_max, static_cast<uint64_t>(seed));
    log_info("ready: T_max " + std::to_string(t_max));
    return [service] {};
  });
}
