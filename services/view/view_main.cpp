// pbnbv-view (`pbnbv view`): the scan in 3-D in a browser. A small HTTP server on 127.0.0.1 serves
// one page (web/) and its data as JSON (/api/scene?view=N, /api/views); the page draws it with
// three.js (served from build/web/three, fetched by scripts/setup from the npm registry).
//   live:   in:  SCAN_STATUS, REGISTERED_CLOUD, VOXEL_MAP, ELLIPSOIDS, PLAN_REQUEST, VIEW_PLAN
//           follows the scan given by --scan, else the latest scan heard on SCAN_STATUS.
//   DIR:    a finished scan folder (core/view load_scan_folder), no bus.
// The candidates' F is computed again here (core/view score_candidates) from the plan's request,
// map and ellipsoids: the scorer publishes only the chosen view and its alternatives.
#include <filesystem>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "bus/convert_planning.hpp"
#include "bus/reply_cache.hpp"
#include "cli/options.hpp"
#include "core/base/install_paths.hpp"
#include "core/base/log.hpp"
#include "core/base/signals.hpp"
#include "core/io/json.hpp"
#include "core/perception/cloud_filter.hpp"
#include "core/view/scene.hpp"
#include "core/view/view_options.hpp"
#include "pbnbv/ellipsoid_set_t.hpp"
#include "pbnbv/plan_request_t.hpp"
#include "pbnbv/registered_cloud_t.hpp"
#include "pbnbv/scan_status_t.hpp"
#include "pbnbv/view_plan_t.hpp"
#include "pbnbv/voxel_set_t.hpp"
// Last: it brings <resolv.h>, whose _res macro breaks Eigen's headers included after it.
#include <httplib.h>

using namespace pbnbv;
namespace fs = std::filesystem;

namespace {

const char* state_name(int8_t s) {
  static const char* names[] = {"starting", "moving", "capturing", "integrating", "planning", "done", "failed", "stopped"};
  return s >= 0 && s < 8 ? names[s] : "unknown";
}

// The scenes served: one per view number; live, the latest is updated as messages arrive.
class SceneStore {
 public:
  std::string scene(int view) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (scenes_.empty()) return scene_json(Scene{}).dump();
    auto it = view < 0 ? std::prev(scenes_.end()) : scenes_.find(view);
    if (it == scenes_.end()) return {};
    return scene_json(it->second).dump();
  }
  std::string views() {
    std::lock_guard<std::mutex> lock(mutex_);
    nlohmann::json j = {{"views", nlohmann::json::array()}, {"live", live_}};
    for (const auto& [v, s] : scenes_) j["views"].push_back(v);
    return j.dump();
  }
  void put(const Scene& s) {
    std::lock_guard<std::mutex> lock(mutex_);
    scenes_[s.view] = s;
  }
  void clear() {
    std::lock_guard<std::mutex> lock(mutex_);
    scenes_.clear();
  }
  bool live_ = false;

 private:
  std::mutex mutex_;
  std::map<int, Scene> scenes_;
};

// Live: the scene of the scan followed, from its messages.
class LiveScene {
 public:
  LiveScene(bus::Bus& bus, SceneStore& store, std::string scan, double voxel_m, std::size_t max_points)
      : store_(store), fixed_scan_(!scan.empty()), voxel_m_(voxel_m), max_points_(max_points) {
    scene_.scan_id = std::move(scan);
    bus.subscribe<scan_status_t>(channels::kScanStatus, [this](const scan_status_t& m) { on_status(m); });
    bus.subscribe<registered_cloud_t>(channels::kRegisteredCloud, [this](const registered_cloud_t& m) { on_cloud(m); });
    bus.subscribe<voxel_set_t>(channels::kVoxelMap, [this](const voxel_set_t& m) { on_map(m); });
    bus.subscribe<ellipsoid_set_t>(channels::kEllipsoids, [this](const ellipsoid_set_t& m) { on_ellipsoids(m); });
    bus.subscribe<plan_request_t>(channels::kPlanRequest, [this](const plan_request_t& m) {
      if (follows(m.scan_id)) requests_.put(m.request_id, m);
    });
    bus.subscribe<view_plan_t>(channels::kViewPlan, [this](const view_plan_t& m) { on_plan(m); });
  }

 private:
  bool follows(const std::string& id) const { return !id.empty() && id == scene_.scan_id; }
  // A scan has at most 1000 views (--views): what claims another is not kept.
  static bool view_in_range(int iteration) { return iteration >= 0 && iteration < 1000; }
  static constexpr std::size_t kRequestsKept = 16;

  void publish() { store_.put(scene_); }

  void on_status(const scan_status_t& m) {
    if (m.scan_id.empty()) return;
    if (m.scan_id != scene_.scan_id) {
      if (fixed_scan_) return;
      // A new scan: start over with it.
      log_info("following scan " + m.scan_id);
      scene_ = Scene{};
      scene_.scan_id = m.scan_id;
      merged_.clear();
      taken_.clear();
      maps_.clear();
      ellipsoids_.clear();
      requests_.clear();
      store_.clear();
    }
    scene_.status = std::string(state_name(m.state)) + (m.message.empty() ? "" : " - " + m.message) + " (" +
                    std::to_string(m.num_views_done) + " views done, " + std::to_string(m.num_points) + " points)";
    publish();
  }

  void on_cloud(const registered_cloud_t& m) {
    if (!follows(m.scan_id) || taken_.count(m.iteration) || !view_in_range(m.iteration)) return;  // a repeat from a cache
    taken_[m.iteration] = bus::from_msg(m.cloud.object_T_camera, "REGISTERED_CLOUD cloud.object_T_camera");
    // A new view: its scene is the one after it (the views taken so far counted), and its plan
    // (the next view's) is still to come; the plan made after the earlier view stays with that
    // view's scene.
    scene_.view = static_cast<int>(taken_.size());
    scene_.chosen.reset();
    scene_.chosen_quality = 0;
    scene_.candidates.clear();
    scene_.plan_candidates = 0;
    scene_.views_taken.clear();
    for (const auto& [i, p] : taken_) scene_.views_taken.push_back(p);
    if (m.accepted) {
      for (const auto& p : m.cloud.points_m) merged_.emplace_back(p[0], p[1], p[2]);
      scene_.cloud_points_total += m.cloud.points_m.size();
      merged_ = voxel_downsample(merged_, voxel_m_);
      scene_.cloud = decimate_cloud(merged_, voxel_m_, max_points_);
    }
    publish();
  }

  void on_map(const voxel_set_t& m) {
    if (!follows(m.scan_id) || !view_in_range(m.iteration)) return;
    maps_[m.iteration] = bus::bbox_of(m);
    scene_.resolution_m = m.resolution_m;
    scene_.frontier.clear();
    for (const auto& c : m.frontier_centres_m) scene_.frontier.emplace_back(c[0], c[1], c[2]);
    publish();
  }

  void on_ellipsoids(const ellipsoid_set_t& m) {
    if (!follows(m.scan_id) || !view_in_range(m.iteration)) return;
    std::vector<Ellipsoid>& e = ellipsoids_[m.iteration];
    e.clear();
    for (std::size_t i = 0; i < m.ellipsoids.size(); ++i) {
      e.push_back(bus::from_msg(m.ellipsoids[i], "ELLIPSOIDS ellipsoids[" + std::to_string(i) + "]"));
    }
    scene_.ellipsoids.clear();
    for (const Ellipsoid& x : e) scene_.ellipsoids.push_back(ellipsoid_mesh(x));
    publish();
  }

  void on_plan(const view_plan_t& m) {
    if (!follows(m.scan_id) || m.outcome != view_plan_t::kView || m.request_id == last_plan_) return;
    const plan_request_t* req = requests_.find(m.request_id);
    if (!req) return;  // its request was not heard (or is long gone): nothing to score with
    const auto map = maps_.find(req->map_iteration);
    const auto ell = ellipsoids_.find(req->map_iteration);
    last_plan_ = m.request_id;
    scene_.chosen = bus::from_msg(m.object_T_camera, "VIEW_PLAN object_T_camera");
    scene_.chosen_quality = m.view_quality;
    try {
      scene_.chosen_ranking = std::string(name_of(bus::ranking_from_msg(m.ranking, "VIEW_PLAN ranking")));
    } catch (const std::invalid_argument& e) {
      log_warn(e.what());
      scene_.chosen_ranking = std::string(name_of(Ranking::kF));
    }
    scene_.plan_candidates = m.num_candidates;
    if (map != maps_.end()) {
      const PlanInput in = bus::plan_input_from_msg(*req);
      scene_.candidates = score_candidates(ell != ellipsoids_.end() ? ell->second : std::vector<Ellipsoid>{}, map->second,
                                           in.candidates, in.camera);
    }
    publish();
  }

  SceneStore& store_;
  bool fixed_scan_;
  double voxel_m_;
  std::size_t max_points_;
  Scene scene_;
  PointCloud merged_;
  std::map<int, Pose> taken_;
  std::map<int, Eigen::AlignedBox3d> maps_;
  std::map<int, std::vector<Ellipsoid>> ellipsoids_;
  bus::ReplyCache<int64_t, plan_request_t> requests_{kRequestsKept};  // the last few: a plan follows its request
  int64_t last_plan_ = -1;
};

std::string read_file(const fs::path& p) { return read_text(p.string()); }

constexpr std::size_t kViewMaxBodyBytes = 64 * 1024;
constexpr std::size_t kViewWorkers = 32;

// Whether a Host header names this machine's loopback: 127.0.0.1, localhost or [::1], with or
// without a port.
bool host_is_local(const std::string& host) {
  std::string name = host;
  if (!name.empty() && name.front() == '[') {
    name = name.substr(0, name.find(']') + 1);
  } else if (const std::size_t colon = name.find(':'); colon != std::string::npos) {
    name = name.substr(0, colon);
  }
  return name == "127.0.0.1" || name == "localhost" || name == "[::1]";
}

// The server's limits, so that no client can take the page from the user, and its Host check.
void harden(httplib::Server& server) {
  // SO_REUSEADDR only: httplib's default also sets SO_REUSEPORT, with which a second pbnbv view
  // on the same port would bind too instead of being told the port is in use.
  server.set_socket_options([](socket_t sock) {
    int yes = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  });
  // Limits, so that no client can take the page from the user: the page only reads (GET), so a
  // body beyond 64 kB is refused (413) before it is buffered; a client that sends or reads
  // nothing for 5 s is dropped; 32 workers serve at once, so ten slow clients leave room.
  server.set_payload_max_length(kViewMaxBodyBytes);
  server.set_read_timeout(5, 0);
  server.set_write_timeout(5, 0);
  server.set_keep_alive_timeout(5);
  server.set_keep_alive_max_count(100);
  server.new_task_queue = [] { return new httplib::ThreadPool(kViewWorkers); };
  // Only a page this machine opened by its own name: a browser led to 127.0.0.1 by another
  // site's DNS name (DNS rebinding) sends that name as Host and is refused.
  server.set_pre_routing_handler([](const httplib::Request& req, httplib::Response& res) {
    if (host_is_local(req.get_header_value("Host"))) return httplib::Server::HandlerResponse::Unhandled;
    res.status = 403;
    res.set_content("pbnbv view serves http://127.0.0.1 and http://localhost only, not Host '" +
                        req.get_header_value("Host").substr(0, 100) + "'",
                    "text/plain");
    return httplib::Server::HandlerResponse::Handled;
  });
}

// The page, its script, three.js and the two API routes (the views, a view's scene).
void add_routes(httplib::Server& server, const fs::path& web, SceneStore& store) {
  // Every handler keeps what it reads by value (the store by pointer: it outlives the server).
  const fs::path three = web / "three";
  SceneStore* const st = &store;
  const auto file = [](httplib::Response& res, const fs::path& p, const char* type) {
    if (!fs::is_regular_file(p)) {
      res.status = 404;
      return;
    }
    res.set_content(read_file(p), type);
  };
  server.Get("/", [file, web](const httplib::Request&, httplib::Response& res) { file(res, web / "index.html", "text/html"); });
  server.Get("/view.js", [file, web](const httplib::Request&, httplib::Response& res) { file(res, web / "view.js", "text/javascript"); });
  server.Get(R"(/three/([A-Za-z0-9_.]+\.js))", [file, three](const httplib::Request& req, httplib::Response& res) {
    file(res, three / req.matches[1].str(), "text/javascript");
  });
  server.Get("/api/views", [st](const httplib::Request&, httplib::Response& res) { res.set_content(st->views(), "application/json"); });
  server.Get("/api/scene", [st](const httplib::Request& req, httplib::Response& res) {
    int view = -1;
    if (req.has_param("view")) {
      try {
        view = std::stoi(req.get_param_value("view"));
      } catch (const std::exception&) {
        res.status = 400;
        res.set_content("view must be a whole number, got '" + req.get_param_value("view") + "'", "text/plain");
        return;
      }
    }
    std::string body = st->scene(view);
    if (body.empty()) {
      res.status = 404;
      res.set_content("no view " + std::to_string(view), "text/plain");
      return;
    }
    res.set_header("Cache-Control", "no-store");
    res.set_content(body, "application/json");
  });
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pbnbv-view: the scan in 3-D in a browser: a page on http://127.0.0.1:PORT/ showing the cloud, the "
               "frontier, the ellipsoids, the candidates coloured by F, the views taken and the chosen view, live from "
               "the bus or from a finished scan folder",
               "pbnbv-view"};
  cli::init(app);
  int port = kViewPort.value;
  double voxel_m = kViewVoxel.value;
  int max_points = kViewMaxPoints.value;
  std::string dir, scan;
  app.add_option("dir", dir, "a finished scan folder to show instead of the live bus")->type_name("DIR");
  cli::add(app, kViewPort, &port);
  cli::add(app, kViewVoxel, &voxel_m);
  cli::add(app, kViewMaxPoints, &max_points);
  cli::add_text(app, "scan", &scan, "follow this scan (its id) [the latest scan heard on SCAN_STATUS]", "ID");
  if (const std::optional<int> code = cli::parse(app, argc, argv, std::cout, std::cerr)) return *code;
  set_log_name("view");
  install_stop_handlers();
  try {
    // The page and three/ (install_paths.hpp): $PBNBV_WEB_DIR, else the installed share/pbnbv/web,
    // else the build tree's web folder.
    const fs::path web = resource_dir("PBNBV_WEB_DIR", "web", PBNBV_WEB_DIR);
    const fs::path three = web / "three";
    if (!fs::exists(three / "three.module.js")) {
      throw std::runtime_error("three.js is missing (" + (three / "three.module.js").string() +
                               "): run ./scripts/setup, which fetches it from the npm registry");
    }
    if (!fs::exists(web / "index.html")) {
      throw std::runtime_error("the page is missing (" + (web / "index.html").string() + "): build the pbnbv-view target");
    }
    SceneStore store;
    store.live_ = dir.empty();
    if (!dir.empty()) {
      for (const Scene& s : load_scan_folder(dir, voxel_m, static_cast<std::size_t>(max_points))) store.put(s);
    }
    httplib::Server server;
    harden(server);
    add_routes(server, web, store);
    if (!server.bind_to_port("127.0.0.1", port)) {
      throw std::runtime_error("cannot listen on 127.0.0.1:" + std::to_string(port) + " (in use? choose another with --port)");
    }
    // Live: subscribed before the page answers, so nothing published after that is missed.
    std::optional<bus::Bus> bus;
    std::optional<LiveScene> live;
    if (dir.empty()) {
      bus.emplace("view");
      bus->serve_scan(scan);
      live.emplace(*bus, store, scan, voxel_m, static_cast<std::size_t>(max_points));
    }
    std::thread http([&] { server.listen_after_bind(); });
    std::cout << "pbnbv view: http://127.0.0.1:" << port << "/  ("
              << (dir.empty() ? std::string("live from the bus") : "scan folder " + dir) << "; Ctrl-C stops)" << std::endl;
    while (!stop_requested()) {
      if (bus) {
        bus->spin_once(100);
      } else {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
    }
    server.stop();
    http.join();
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "pbnbv view: " << e.what() << std::endl;
    return 2;
  }
}
