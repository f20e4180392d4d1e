// pbnbv-registration: the registration service.
//   in:  CLOUD (a view placed by the rig's kinematic pose), CAPTURE_REQUEST (a CLOUD is taken only
//        when it answers a capture request heard: bus/asked_captures.hpp)
//   out: REGISTERED_CLOUD, HEARTBEAT
// Refines each view's pose against the accumulated model of its scan with point-to-plane ICP
// (core register_frame), starting from the kinematic pose; an implausible alignment is
// rejected with the reason and the kinematic pose kept, and a rejected view is not merged.
// The model is rebuilt from the messages of the scan (a restarted service starts a new model
// at the next scan); answers are idempotent by (scan_id, request_id).
#include <deque>
#include <iostream>
#include <sstream>

#include <filesystem>

#include "bus/asked_captures.hpp"
#include "bus/bus.hpp"
#include "bus/state_file.hpp"
#include "core/io/cloud_file.hpp"
#include "bus/reply_cache.hpp"
#include "bus/service.hpp"
#include "bus/convert.hpp"
#include "core/perception/perception_options.hpp"
#include "core/geometry/point_cloud.hpp"
#include "core/base/log.hpp"
#include "core/perception/cloud_filter.hpp"
#include "core/perception/registration.hpp"
#include "pbnbv/capture_request_t.hpp"
#include "pbnbv/point_cloud_t.hpp"
#include "pbnbv/registered_cloud_t.hpp"

using namespace pbnbv;

namespace {

constexpr std::size_t kAnswersKept = 4;

class RegistrationService {
 public:
  RegistrationService(bus::Bus& bus, const RegistrationParams& params, double model_voxel_m, bool off,
                      std::filesystem::path out)
      : bus_(bus), params_(params), model_voxel_m_(model_voxel_m), off_(off), out_(std::move(out)) {
    restore();
    bus_.subscribe<capture_request_t>(channels::kCaptureRequest,
                                      [this](const capture_request_t& c) { asked_.heard(c.scan_id, c.request_id); });
    bus_.subscribe<point_cloud_t>(channels::kCloud, [this](const point_cloud_t& c) { on_cloud(c); });
  }

 private:
  void on_cloud(const point_cloud_t& c) {
    asked_.require("CLOUD", c.scan_id, c.request_id);  // a cloud nobody asked for is not merged
    bus_.set_scan(c.scan_id, c.iteration);
    if (const registered_cloud_t* answer = answers_.find({c.scan_id, c.request_id})) {
      bus_.publish(channels::kRegisteredCloud, *answer);  // a repeat: answer again
      return;
    }
    if (c.scan_id != scan_id_) {  // a new scan: a new model
      scan_id_ = c.scan_id;
      model_.clear();
    }
    registered_cloud_t out;
    out.scan_id = c.scan_id;
    out.iteration = c.iteration;
    out.request_id = c.request_id;
    out.cloud = c;
    out.kinematic_object_T_camera = c.object_T_camera;
    out.correction = bus::to_msg(Pose::Identity());
    out.translation_m = out.rotation_deg = out.overlap = out.rmse_m = out.register_s = out.constraint = 0;
    out.refined = false;
    out.iterations = 0;
    if (c.status != point_cloud_t::kOk) {
      out.accepted = false;
      out.reason = "no cloud to register: " + c.message;
    } else {
      PointCloud frame;
      frame.reserve(c.points_m.size());
      for (const auto& p : c.points_m) frame.emplace_back(p[0], p[1], p[2]);
      const Pose kinematic = bus::from_msg(c.object_T_camera, "CLOUD object_T_camera");
      RegistrationResult r;
      if (off_) {  // for comparisons: every view kept where the kinematics put it
        r.accepted = true;
        r.reason = "registration off: kinematic pose kept";
      } else {
        r = register_frame(model_, frame, params_);
      }
      out.accepted = r.accepted;
      out.refined = r.refined;
      out.constraint = r.constraint;
      out.reason = r.reason;
      out.correction = bus::to_msg(r.correction);
      out.translation_m = r.translation_m;
      out.rotation_deg = r.rotation_deg;
      out.overlap = r.overlap;
      out.rmse_m = r.rmse_m;
      out.iterations = r.iterations;
      out.register_s = r.time_s;
      if (r.accepted) {
        const PointCloud registered = transform_cloud(frame, r.correction);
        out.cloud.object_T_camera = bus::to_msg(r.correction * kinematic);
        for (std::size_t i = 0; i < registered.size(); ++i) {
          out.cloud.points_m[i] = {registered[i].x(), registered[i].y(), registered[i].z()};
        }
        model_.insert(model_.end(), registered.begin(), registered.end());
        model_ = voxel_downsample(model_, model_voxel_m_);
      }
      std::ostringstream os;
      os << "view " << c.iteration << ": " << r.reason << " (" << r.time_s * 1e3 << " ms)";
      log_info(os.str());
    }
    out.model_points = static_cast<int32_t>(model_.size());
    out.utime = bus::now_utime();
    bus_.publish(channels::kRegisteredCloud, out);
    answers_.put({out.scan_id, out.request_id}, out);
    save(out);
  }

  // The state a restarted service continues from: DIR/state/registration.ply (the model) and
  // DIR/state/registration.answer (the last REGISTERED_CLOUD), written after every view.
  std::filesystem::path state_path(const char* name) const { return out_ / "state" / name; }

  void save(const registered_cloud_t& answer) {
    if (out_.empty() || bus_.scope().empty()) return;  // only a service started for one scan
    std::filesystem::create_directories(out_ / "state");
    write_ply(model_, state_path("registration.ply").string());
    bus::save_message(answer, state_path("registration.answer").string());
  }

  // Continues the model of the scan this service serves when the folder holds it (a restart).
  void restore() {
    if (out_.empty() || bus_.scope().empty()) return;
    const auto last = bus::load_message<registered_cloud_t>(state_path("registration.answer").string());
    if (!last || last->scan_id != bus_.scope()) return;
    model_ = read_ply(state_path("registration.ply").string());
    scan_id_ = last->scan_id;
    answers_.put({last->scan_id, last->request_id}, *last);
    log_info("continuing the model of scan " + scan_id_ + " (" + std::to_string(model_.size()) + " points) after view " +
             std::to_string(last->iteration) + " from " + state_path("registration.ply").string());
  }

  bus::AskedCaptures asked_;
  bus::Bus& bus_;
  RegistrationParams params_;
  double model_voxel_m_;
  bool off_;
  std::filesystem::path out_;
  std::string scan_id_;
  PointCloud model_;
  bus::ReplyCache<std::pair<std::string, int64_t>, registered_cloud_t> answers_{kAnswersKept};
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pbnbv-registration: refines every captured view's pose by ICP against the model", "pbnbv-registration"};
  cli::init(app);
  // The registration's own settings (this program is their only user): defaults from
  // RegistrationParams, ranges here.
  RegistrationParams p;
  const RegistrationParams d;
  cli::add(app, Setting<double>{"icp-voxel", d.voxel_m, 0.0005, 0.05, "m", "both clouds downsampled to this for ICP"},
           &p.voxel_m);
  cli::add(app, Setting<double>{"max-correspondence", d.max_correspondence_m, 0.001, 0.5, "m",
                                "ICP correspondence distance (coarse-to-fine from here)"},
           &p.max_correspondence_m);
  cli::add(app, Setting<int>{"max-iterations", d.max_iterations, 1, 1000, "", "ICP iterations at most"},
           &p.max_iterations);
  cli::add(app, Setting<double>{"min-overlap", d.min_overlap, 0.0, 1.0, "", "accept: at least this share of the view's points lies near the model after alignment"},
           &p.min_overlap);
  cli::add(app, Setting<double>{"max-rmse", d.max_rmse_m, 1e-5, 0.1, "m", "accept: RMS distance of the overlapping points at most this"},
           &p.max_rmse_m);
  cli::add(app, Setting<double>{"max-correction", d.max_translation_m, 1e-4, 1.0, "m",
                                "accept: the correction moves the camera at most this far"},
           &p.max_translation_m);
  cli::add(app, Setting<double>{"max-correction-deg", d.max_rotation_deg, 0.01, 45.0, "deg",
                                "accept: the correction turns the camera at most this much"},
           &p.max_rotation_deg);
  double model_voxel_m = 0;
  cli::add(app, kCloudVoxel.renamed("model-voxel", "the model cloud's downsampling voxel (0: off)"), &model_voxel_m);
  bool off = false;
  cli::add_flag(app, "off", &off, "pass every view through with its kinematic pose (no ICP)");
  std::string out;
  cli::add_text(app, "out", &out,
                "the scan's folder: with --scan, the model is kept in DIR/state and continued after a restart", "DIR");
  return bus::run_service("registration", app, argc, argv, 20, [&](bus::Bus& bus) -> std::function<void()> {
    auto service = std::make_shared<RegistrationService>(bus, p, model_voxel_m, off, out);
    log_info("ready");
    return [service] {};
  });
}
