#include "core/scan/scan_comparison.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "core/base/format.hpp"
#include "core/base/units.hpp"
#include "core/io/json.hpp"

using nlohmann::json;

namespace pbnbv {

namespace {

// The view the planner chose for a recorded view: its pose, "stop" or "failed" when it chose
// none, null when no plan was asked for (the initial view, a ring).
json planned_pose(const ViewRecord* v) {
  if (!v || !v->plan) return nullptr;
  const ViewPlan& p = v->plan->plan;
  if (p.outcome != PlanOutcome::kView) return to_string(p.outcome);
  return to_json(p.object_T_camera);
}

// {"original": a, "replay": b, "same": a == b}
json pair(const json& a, const json& b) { return {{"original", a}, {"replay", b}, {"same", a == b}}; }

// Distance and angle between two poses (JSON), and whether they are the same view.
json pose_difference(const json& a, const json& b, const std::string& what) {
  json d = {{"original", a}, {"replay", b}};
  if (a.is_object() && b.is_object()) {
    const Pose pa = pose_from_json(a, "original " + what), pb = pose_from_json(b, "replay " + what);
    const double position_m = (pa.translation() - pb.translation()).norm();
    const double angle_rad = rotation_angle_rad(pa.linear(), pb.linear());
    d["position_m"] = position_m;
    d["angle_deg"] = rad_to_deg(angle_rad);
    d["same"] = position_m <= kSameViewPositionM && angle_rad <= kSameViewAngleRad;
  } else {
    d["same"] = a == b;  // both none, or the same decision (stop, failed)
  }
  return d;
}

}  // namespace

json compare_scans(const RecordedScan& original, const RecordedScan& replay) {
  const std::vector<ViewRecord>& a = original.views;
  const std::vector<ViewRecord>& b = replay.views;
  json views = json::array();
  json differences = json::array();
  const std::size_t n = std::max(a.size(), b.size());
  // The registration's decision and what it did, the map's counts (null: not in this record).
  const auto registration = [](const ViewRecord* v) { return v && v->registration ? &*v->registration : nullptr; };
  const auto accepted = [&](const ViewRecord* v) { return registration(v) ? json(registration(v)->accepted) : json(nullptr); };
  const auto correction = [&](const ViewRecord* v) -> json {
    const RegisteredCloud* r = registration(v);
    if (!r) return nullptr;
    return {{"translation_mm", r->translation_m * 1e3}, {"rotation_deg", r->rotation_deg}};
  };
  const auto registered_pose = [&](const ViewRecord* v) {
    return registration(v) ? to_json(registration(v)->cloud.object_T_camera) : json(nullptr);
  };
  const auto voxels = [](const ViewRecord* v) -> json {
    if (!v || !v->map) return nullptr;
    const VoxelMapSummary& m = *v->map;
    return {{"none", m.num_none}, {"empty", m.num_empty}, {"occupied", m.num_occupied}, {"unknown", m.num_unknown},
            {"frontier", m.num_frontier}};
  };
  for (std::size_t i = 0; i < n; ++i) {
    const ViewRecord* va = i < a.size() ? &a[i] : nullptr;
    const ViewRecord* vb = i < b.size() ? &b[i] : nullptr;
    const std::string name = "view " + std::to_string(i + 1);
    json v = {{"view", i + 1}};
    v["accepted"] = pair(accepted(va), accepted(vb));
    v["merged"] = pair(accepted(va), accepted(vb));  // a view is merged into the model when accepted
    v["correction"] = {{"original", correction(va)}, {"replay", correction(vb)}};
    v["registered_pose"] = pose_difference(registered_pose(va), registered_pose(vb), name + " registered pose");
    json counts = {{"original", voxels(va)}, {"replay", voxels(vb)}};
    counts["same"] = counts["original"] == counts["replay"];
    v["voxels"] = counts;
    v["plan"] = pose_difference(planned_pose(va), planned_pose(vb), name + " plan");
    for (const char* k : {"accepted", "merged", "registered_pose", "voxels", "plan"}) {
      if (!v[k]["same"].get<bool>()) differences.push_back(name + ": " + k + " differs");
    }
    if (!va || !vb) differences.push_back(name + ": only in the " + (!va ? "replay" : "original"));
    views.push_back(v);
  }
  return {{"views", views}, {"differences", differences}, {"same_decisions", differences.empty()}};
}

std::string comparison_table(const json& c) {
  std::string t = fmt::format("{:<5} {:<11} {:<27} {:<19} {:<34} {}\n", "view", "accepted", "correction mm/deg",
                              "registered pose", "voxels occ/front/unk/empty", "planned view");
  const auto yes_no = [](const json& j) { return j.is_boolean() ? (j.get<bool>() ? "yes" : "no") : "-"; };
  const auto corr = [](const json& j) {
    return j.is_object() ? fixed(j["translation_mm"].get<double>(), 2) + "/" + fixed(j["rotation_deg"].get<double>(), 2)
                         : std::string("-");
  };
  const auto counts = [](const json& j) {
    if (!j.is_object()) return std::string("-");
    std::string s;
    for (const char* k : {"occupied", "frontier", "unknown", "empty"}) s += (s.empty() ? "" : "/") + std::to_string(j.value(k, 0));
    return s;
  };
  const auto diff = [](const json& d) -> std::string {
    if (d.contains("position_m")) {
      return (d["same"].get<bool>() ? "same" : "DIFFERS") + std::string(" (") +
             fmt::format("{:.2g} m, {:.2g} deg", d["position_m"].get<double>(), d["angle_deg"].get<double>()) + ")";
    }
    if (d["original"].is_null() && d["replay"].is_null()) return "-";
    const auto text = [](const json& j) { return j.is_string() ? j.get<std::string>() : j.is_null() ? "none" : "a view"; };
    return (d["same"].get<bool>() ? "same: " : "DIFFERS: ") + text(d["original"]) + " / " + text(d["replay"]);
  };
  for (const json& v : c["views"]) {
    const json& acc = v["accepted"];
    const std::string accepted = std::string(yes_no(acc["original"])) + "/" + yes_no(acc["replay"]) +
                                 (acc["same"].get<bool>() ? "" : " !");
    const std::string correction = corr(v["correction"]["original"]) + " -> " + corr(v["correction"]["replay"]);
    const json& vox = v["voxels"];
    const std::string voxels = vox["same"].get<bool>() ? counts(vox["original"]) + " same"
                                                       : counts(vox["original"]) + " vs " + counts(vox["replay"]);
    t += fmt::format("{:<5} {:<11} {:<27} {:<19} {:<34} {}\n", v["view"].get<int>(), accepted, correction,
                     diff(v["registered_pose"]), voxels, diff(v["plan"]));
  }
  t += c["same_decisions"].get<bool>() ? "same decisions in every view\n"
                                       : std::to_string(c["differences"].size()) + " differences\n";
  return t;
}

}  // namespace pbnbv
