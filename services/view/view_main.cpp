// pbnbv-view (`pbnbv view`): the scan in 3-D in a browser. A small HTTP server on 127.0.0.1 serves
// one page (web/) and its data as JSON (/api/scene?view=N, /api/views); the page draws it with
// three.js (served from build/web/three, fetched by scripts/setup from the npm registry). Views
// count from 1 live and from a folder alike, as the files and scan.json: view N's scene is the
// scan after its Nth view (live, view 0 is the scene before the first).
//   live:   in:  SCAN_STATUS, REGISTERED_CLOUD, VOXEL_MAP, ELLIPSOIDS, PLAN_REQUEST, VIEW_PLAN
//           follows the scan given by --scan, else the latest scan heard on SCAN_STATUS.
//   DIR:    a finished scan folder (core/view load_scan_folder), no bus.
// The candidates' F is computed again here (core/view score_candidates) from the plan's request,
// map and ellipsoids: the scorer publishes only the chosen view and its alternatives.
// Besides core/view's scene, the page gets the drawn cloud's normals (to shade it) and colours
// (when the cloud has any), where the grid goes (the turntable top), and a revision per scene;
// the page's HTML carries the scene it opens on, so it draws before its load event (a plain
// headless screenshot shows the scan).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
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
#include "core/io/cloud_file.hpp"
#include "core/io/json.hpp"
#include "core/perception/cloud_filter.hpp"
#include "core/perception/depth_cloud.hpp"
#include "core/perception/neighbours.hpp"
#include "core/scan/scan_record.hpp"
#include "core/view/cloud_look.hpp"
#include "core/view/scene.hpp"
#include "core/view/view_options.hpp"
#include "pbnbv/capture_request_t.hpp"
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

// Where the page lays its ground grid: an object-frame z and what is there.
struct Ground {
  double z_m = 0;
  std::string what;
  bool operator==(const Ground& o) const { return z_m == o.z_m && what == o.what; }
};

// The scenes served: one per view number; live, the latest is updated as messages arrive. Each
// has a revision (from one counter: a scene put again, or the ground moved, gets a new one), so
// that the page, which sends the revision it shows, is told "unchanged" (204) instead of sent the
// scene again.
class SceneStore {
 public:
  enum class Found { kScene, kUnchanged, kMissing };
  // The JSON of view `view` (< 0: the latest) into `body`, unless its revision is `since` (> 0).
  Found scene(int view, uint64_t since, std::string& body) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (scenes_.empty()) {
      body = json_of(Entry{}).dump();
      return Found::kScene;
    }
    auto it = view < 0 ? std::prev(scenes_.end()) : scenes_.find(view);
    if (it == scenes_.end()) return Found::kMissing;
    if (since > 0 && it->second.revision == since) return Found::kUnchanged;
    body = json_of(it->second).dump();
    return Found::kScene;
  }
  std::string views() {
    std::lock_guard<std::mutex> lock(mutex_);
    nlohmann::json j = {{"views", nlohmann::json::array()}, {"live", live_}};
    for (const auto& [v, s] : scenes_) j["views"].push_back(v);
    return j.dump();
  }
  void put(const Scene& s, const CloudLook& look) {
    std::lock_guard<std::mutex> lock(mutex_);
    scenes_[s.view] = Entry{s, look, ++revision_};
  }
  void set_ground(const std::optional<Ground>& g) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (g == ground_) return;
    ground_ = g;
    for (auto& [v, e] : scenes_) e.revision = ++revision_;
  }
  void clear() {
    std::lock_guard<std::mutex> lock(mutex_);
    scenes_.clear();
    ground_.reset();
  }
  bool live_ = false;

 private:
  struct Entry {
    Scene scene;
    CloudLook look;
    uint64_t revision = 0;
  };
  // core/view's scene JSON and what this server adds: `revision`; `cloud_normals`, flat nx, ny, nz
  // per drawn point as whole numbers -127..127 (127: 1; 0 0 0: none) or [] when there are none;
  // `cloud_colours`, flat r, g, b 0..255 per drawn point or [] when the cloud has none; `ground`,
  // {"z_m", "what"} or null while unknown.
  nlohmann::json json_of(const Entry& e) const {
    nlohmann::json j = scene_json(e.scene);
    j["revision"] = e.revision;
    const std::size_t n = e.scene.cloud.size();
    std::vector<int> normals, colours;
    if (e.look.normals.size() == n) {
      normals.reserve(3 * n);
      for (const Eigen::Vector3f& v : e.look.normals) {
        for (int c = 0; c < 3; ++c) {
          normals.push_back(std::isfinite(v[c]) ? static_cast<int>(std::lround(std::clamp(v[c], -1.0f, 1.0f) * 127.0f)) : 0);
        }
      }
    }
    if (e.look.colours.size() == n) {
      colours.reserve(3 * n);
      for (const Rgb& c : e.look.colours) colours.insert(colours.end(), {c[0], c[1], c[2]});
    }
    j["cloud_normals"] = normals;
    j["cloud_colours"] = colours;
    j["ground"] = ground_ ? nlohmann::json{{"z_m", ground_->z_m}, {"what", ground_->what}} : nlohmann::json(nullptr);
    return j;
  }

  std::mutex mutex_;
  std::map<int, Entry> scenes_;
  std::optional<Ground> ground_;
  uint64_t revision_ = 0;
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
    bus.subscribe<capture_request_t>(channels::kCaptureRequest, [this](const capture_request_t& m) { on_capture(m); });
  }

 private:
  bool follows(const std::string& id) const { return !id.empty() && id == scene_.scan_id; }
  // A scan has at most 1000 views (--views): what claims another is not kept.
  static bool view_in_range(int iteration) { return iteration >= 0 && iteration < 1000; }
  static constexpr std::size_t kRequestsKept = 16;

  void publish() { store_.put(scene_, look_); }

  // Where the grid goes, from the capture request: on the arm rig the object frame's origin is
  // object_z_m above the turntable top; on the free rig (object_z_m 0) there is no turntable and
  // the grid is the working volume's floor.
  void on_capture(const capture_request_t& m) {
    if (!follows(m.scan_id) || !std::isfinite(m.object_z_m) || !std::isfinite(m.crop_min_m[2])) return;
    store_.set_ground(m.object_z_m > 0 ? Ground{-m.object_z_m, "the turntable top"}
                                       : Ground{m.crop_min_m[2], "the working volume's floor (free rig)"});
  }

  void on_status(const scan_status_t& m) {
    if (m.scan_id.empty()) return;
    if (m.scan_id != scene_.scan_id) {
      if (fixed_scan_) return;
      // A new scan: start over with it.
      log_info("following scan " + m.scan_id);
      scene_ = Scene{};
      scene_.scan_id = m.scan_id;
      merged_.clear();
      merged_normals_.clear();
      look_ = CloudLook{};
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
      // REGISTERED_CLOUD carries no normals (the registration service writes them to its
      // frames/): fitted here to the view's own points, facing its camera, as the registration
      // service fits them when a CLOUD has none, and averaged per voxel as the model grows.
      PointCloud view;
      view.reserve(m.cloud.points_m.size());
      for (const auto& p : m.cloud.points_m) view.emplace_back(p[0], p[1], p[2]);
      std::vector<Eigen::Vector3f> normals =
          view.size() >= 3 ? neighbour_normals(view, taken_[m.iteration].translation(), 12)
                           : std::vector<Eigen::Vector3f>(view.size(), Eigen::Vector3f::Zero());
      merged_.insert(merged_.end(), view.begin(), view.end());
      merged_normals_.insert(merged_normals_.end(), normals.begin(), normals.end());
      scene_.cloud_points_total += m.cloud.points_m.size();
      const PointCloud all = std::move(merged_);
      merged_ = voxel_downsample(all, voxel_m_);
      merged_normals_ = voxel_normals(all, merged_normals_, merged_, voxel_m_);
      scene_.cloud = decimate_cloud(merged_, voxel_m_, max_points_);
      look_ = look_from(scene_.cloud, merged_, NeighbourIndex(merged_), merged_normals_, {}, std::max(0.02f, static_cast<float>(4 * voxel_m_)));
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
  CloudLook look_;  // of scene_.cloud
  PointCloud merged_;
  std::vector<Eigen::Vector3f> merged_normals_;  // one per point of merged_ (zero: none)
  std::map<int, Pose> taken_;
  std::map<int, Eigen::AlignedBox3d> maps_;
  std::map<int, std::vector<Ellipsoid>> ellipsoids_;
  bus::ReplyCache<int64_t, plan_request_t> requests_{kRequestsKept};  // the last few: a plan follows its request
  int64_t last_plan_ = -1;
};

// A finished scan folder's scenes, each with its cloud's look: the normals (and colours, when it
// has any) of DIR/cloud.ply, the merged model, nearest point by point; normals fitted to the drawn
// points where cloud.ply is missing or has none. The grid: on the arm rig the turntable top
// (settings.object_z_m below the origin), on the free rig the working volume's floor.
void load_folder(const std::string& dir, double voxel_m, std::size_t max_points, SceneStore& store) {
  const std::vector<Scene> scenes = load_scan_folder(dir, voxel_m, max_points);
  const fs::path model = fs::path(dir) / "cloud.ply";
  PointCloud from;
  CloudExtras extras;
  std::vector<Rgb> colours;
  if (fs::exists(model)) {
    try {
      from = read_ply(model.string(), extras);
      colours = read_ply_colours(model, from.size());
    } catch (const std::exception& e) {
      log_warn(std::string("pbnbv view: the normals of cloud.ply are not used: ") + e.what());
      from.clear();
      extras = CloudExtras{};
    }
  }
  // Zero normals ("none found") are as good as none when every one is zero.
  const bool file_normals = !extras.normals.empty() &&
                            std::any_of(extras.normals.begin(), extras.normals.end(), [](const Eigen::Vector3f& n) { return !n.isZero(); });
  std::optional<NeighbourIndex> index;
  if (file_normals || !colours.empty()) index.emplace(from);
  for (const Scene& s : scenes) {
    CloudLook look;
    if (index) {
      look = look_from(s.cloud, from, *index, file_normals ? extras.normals : std::vector<Eigen::Vector3f>{}, colours,
                       std::max(0.02f, static_cast<float>(4 * voxel_m)));
    }
    if (look.normals.empty()) look.normals = fitted_normals(s.cloud);
    store.put(s, look);
  }
  try {
    const ScanSettings settings = read_scan_record(dir).settings;
    if (settings.rig == RigKind::kArm && settings.object_z_m > 0) {
      store.set_ground(Ground{-settings.object_z_m, "the turntable top"});
    } else {
      store.set_ground(Ground{settings.crop_min_m.z(), "the working volume's floor (free rig)"});
    }
  } catch (const std::exception& e) {
    log_warn(std::string("pbnbv view: no ground from scan.json's settings: ") + e.what());
  }
}

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

// The view a request asks for (?view=N, counted from 1; -1: the latest, without), or nullopt after
// answering 400.
std::optional<int> view_param(const httplib::Request& req, httplib::Response& res) {
  if (!req.has_param("view")) return -1;
  const std::string text = req.get_param_value("view");
  try {
    std::size_t used = 0;
    const int view = std::stoi(text, &used);
    if (used == text.size() && view >= 0 && view <= 1000) return view;
  } catch (const std::exception&) {
  }
  res.status = 400;
  res.set_content("view must be a whole number in 1..1000 (0: before the first view, live), got '" + text.substr(0, 100) + "'",
                  "text/plain");
  return std::nullopt;
}

// The element of index.html that receives the page's first state.
constexpr const char* kInitialSlot = R"(<script type="application/json" id="initial">null</script>)";

// The page, its script, three.js and the two API routes (the views, a view's scene). The page
// comes with its first state in its HTML: {"views": /api/views, "scene": the scene of ?view=N (the
// latest without) or null, "view": N}, so that it draws before its load event; a scene that has
// not changed since the revision the page shows (?since=R) is answered 204, without a body.
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
  server.Get("/", [web, st](const httplib::Request& req, httplib::Response& res) {
    const fs::path page = web / "index.html";
    if (!fs::is_regular_file(page)) {
      res.status = 404;
      return;
    }
    const std::optional<int> view = view_param(req, res);
    if (!view) return;
    std::string html = read_file(page);
    std::string scene;
    const bool found = st->scene(*view, 0, scene) == SceneStore::Found::kScene;
    std::string state = R"({"views":)" + st->views() + R"(,"view":)" + std::to_string(*view) + R"(,"scene":)" +
                        (found ? scene : std::string("null")) + "}";
    // Inside <script> only "</script" or "<!--" could end or upset the element: JSON has '<' in
    // strings only, where \u003c means the same.
    std::string escaped;
    escaped.reserve(state.size());
    for (const char c : state) {
      if (c == '<') {
        escaped += "\\u003c";
      } else {
        escaped += c;
      }
    }
    const std::string slot = kInitialSlot;
    if (const std::size_t at = html.find(slot); at != std::string::npos) {
      html.replace(at, slot.size(), R"(<script type="application/json" id="initial">)" + escaped + "</script>");
    }
    res.set_header("Cache-Control", "no-store");
    res.set_content(html, "text/html");
  });
  server.Get("/view.js", [file, web](const httplib::Request&, httplib::Response& res) { file(res, web / "view.js", "text/javascript"); });
  server.Get(R"(/three/([A-Za-z0-9_.]+\.js))", [file, three](const httplib::Request& req, httplib::Response& res) {
    file(res, three / req.matches[1].str(), "text/javascript");
  });
  server.Get("/api/views", [st](const httplib::Request&, httplib::Response& res) { res.set_content(st->views(), "application/json"); });
  server.Get("/api/scene", [st](const httplib::Request& req, httplib::Response& res) {
    const std::optional<int> view = view_param(req, res);
    if (!view) return;
    uint64_t since = 0;
    if (req.has_param("since")) {
      try {
        since = std::stoull(req.get_param_value("since"));
      } catch (const std::exception&) {
        res.status = 400;
        res.set_content("since must be a revision number, got '" + req.get_param_value("since").substr(0, 100) + "'", "text/plain");
        return;
      }
    }
    std::string body;
    res.set_header("Cache-Control", "no-store");
    switch (st->scene(*view, since, body)) {
      case SceneStore::Found::kMissing:
        res.status = 404;
        res.set_content("no view " + std::to_string(*view), "text/plain");
        return;
      case SceneStore::Found::kUnchanged:
        res.status = 204;
        return;
      case SceneStore::Found::kScene:
        res.set_content(body, "application/json");
        return;
    }
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
      load_folder(dir, voxel_m, static_cast<std::size_t>(max_points), store);
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
