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

const json kNull = nullptr;

// j[a][b]... or null.
const json& at(const json& j, std::initializer_list<const char*> path) {
  const json* p = &j;
  for (const char* k : path) {
    if (!p->is_object() || !p->contains(k)) return kNull;
    p = &(*p)[k];
  }
  return *p;
}

// The view the planner chose for a recorded view (null: none asked for, or no view chosen): the
// plan's pose, or, in records written before it was kept, the pose reached as the plan's option 0.
json planned_pose(const json& view) {
  const json& plan = at(view, {"plan"});
  if (!plan.contains("outcome")) return nullptr;  // the initial view
  if (plan.value("outcome", "") != "view") return plan.value("outcome", "");
  if (plan.contains("object_T_camera")) return plan["object_T_camera"];
  if (view.value("option", -1) == 0) return view["requested_object_T_camera"];
  return nullptr;
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

std::vector<std::vector<Pose>> recorded_attempts(const json& scan, const std::string& file) {
  std::vector<std::vector<Pose>> attempts;
  for (const json& v : scan.value("views", json::array())) {
    const std::string at_view = file + " view " + std::to_string(v.value("view", 0) + 1);
    std::vector<Pose> poses;
    for (const json& f : v.value("failed_moves", json::array())) {
      poses.push_back(pose_from_json(f.at("object_T_camera"), at_view + " failed move"));
    }
    if (v.contains("option")) poses.push_back(pose_from_json(v.at("requested_object_T_camera"), at_view + " requested pose"));
    attempts.push_back(std::move(poses));
  }
  return attempts;
}

json compare_scans(const json& original, const json& replay) {
  const json& a = at(original, {"views"});
  const json& b = at(replay, {"views"});
  json views = json::array();
  json differences = json::array();
  const std::size_t n = std::max(a.is_array() ? a.size() : 0, b.is_array() ? b.size() : 0);
  for (std::size_t i = 0; i < n; ++i) {
    const json& va = a.is_array() && i < a.size() ? a[i] : kNull;
    const json& vb = b.is_array() && i < b.size() ? b[i] : kNull;
    const std::string name = "view " + std::to_string(i + 1);
    json v = {{"view", i}};
    v["accepted"] = pair(at(va, {"registration", "accepted"}), at(vb, {"registration", "accepted"}));
    v["merged"] = pair(at(va, {"merged"}), at(vb, {"merged"}));
    const auto correction = [](const json& view) -> json {
      if (!at(view, {"registration"}).is_object()) return nullptr;
      return {{"translation_mm", view["registration"].value("translation_mm", 0.0)},
              {"rotation_deg", view["registration"].value("rotation_deg", 0.0)}};
    };
    v["correction"] = {{"original", correction(va)}, {"replay", correction(vb)}};
    v["registered_pose"] = pose_difference(at(va, {"registration", "registered_object_T_camera"}),
                                           at(vb, {"registration", "registered_object_T_camera"}), name + " registered pose");
    json voxels = {{"original", at(va, {"map", "voxels"})}, {"replay", at(vb, {"map", "voxels"})}};
    voxels["same"] = voxels["original"] == voxels["replay"];
    v["voxels"] = voxels;
    v["plan"] = pose_difference(planned_pose(va), planned_pose(vb), name + " plan");
    for (const char* k : {"accepted", "merged", "registered_pose", "voxels", "plan"}) {
      if (!v[k]["same"].get<bool>()) differences.push_back(name + ": " + k + " differs");
    }
    if (va.is_null() || vb.is_null()) differences.push_back(name + ": only in the " + (va.is_null() ? "replay" : "original"));
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
    t += fmt::format("{:<5} {:<11} {:<27} {:<19} {:<34} {}\n", v["view"].get<int>() + 1, accepted, correction,
                     diff(v["registered_pose"]), voxels, diff(v["plan"]));
  }
  t += c["same_decisions"].get<bool>() ? "same decisions in every view\n"
                                       : std::to_string(c["differences"].size()) + " differences\n";
  return t;
}

}  // namespace pbnbv
