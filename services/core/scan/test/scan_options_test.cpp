// The table of scan options: each default is the paper's (or the README's) figure, lies in its
// own range, and is the one every struct starts from; the kinds (planner, candidate area,
// when-done, rig, up axis, registration switch) are named once, every name round-trips, an
// unknown one is named with the choices; settings.json keeps the same text values.
#include <gtest/gtest.h>

#include <string>

#include "error_message.hpp"
#include "core/geometry/camera_options.hpp"
#include "core/mapping/map_options.hpp"
#include "core/mapping/voxel_map.hpp"
#include "core/perception/perception_options.hpp"
#include "core/planning/ellipsoid_fit.hpp"
#include "core/planning/planner.hpp"
#include "core/planning/planning_options.hpp"
#include "core/scan/scan_options.hpp"
#include "core/scan/scan_settings.hpp"

namespace pbnbv {
namespace {

using testing::error_message;

template <typename T>
void expect_default_in_range(const Setting<T>& s) {
  EXPECT_TRUE(s.allows(s.value)) << s.name;
  EXPECT_LE(s.min, s.max) << s.name;
  EXPECT_FALSE(s.help.empty()) << s.name;
}

TEST(ScanOptions, TheDefaultsAreThePapersFigures) {
  // The paper's simulation setup (N = 800 candidates on alpha = 24 parallels, beta = 4 sectors,
  // T_max = 10, 0.03 m voxels, d_c = 0.6 m; a RealSense D435 at 1280 x 720, f = 696 px, 0.1 to
  // 3 m) and the README's scan defaults (10 views, 2 mm cloud voxel, twin at 4 x real time).
  EXPECT_EQ(kCandidates.value, 800);
  EXPECT_EQ(kParallels.value, 24);
  EXPECT_EQ(kSectors.value, 4);
  EXPECT_EQ(kTMax.value, 10);
  EXPECT_DOUBLE_EQ(kMapResolution.value, 0.03);
  EXPECT_DOUBLE_EQ(kWorkingDistance.value, 0.6);
  EXPECT_EQ(kImageWidth.value, 1280);
  EXPECT_EQ(kImageHeight.value, 720);
  EXPECT_DOUBLE_EQ(kFocalX.value, 696.0);
  EXPECT_DOUBLE_EQ(kFocalY.value, 696.0);
  EXPECT_DOUBLE_EQ(kPrincipalX.value, kImageWidth.value / 2.0);
  EXPECT_DOUBLE_EQ(kPrincipalY.value, kImageHeight.value / 2.0);
  EXPECT_DOUBLE_EQ(kDepthMin.value, 0.1);
  EXPECT_DOUBLE_EQ(kDepthMax.value, 3.0);
  EXPECT_EQ(kViews.value, 10);
  EXPECT_DOUBLE_EQ(kCloudVoxel.value, 0.002);
  EXPECT_DOUBLE_EQ(kSimSpeed.value, 4.0);
  EXPECT_DOUBLE_EQ(kStopFraction.value, 0.0);
  EXPECT_DOUBLE_EQ(kRingElevation.value, 30.0);
  EXPECT_EQ(kPlanner.value, PlannerKind::kPbnbv);
  EXPECT_EQ(kArea.value, CandidateArea::kHemisphere);
  EXPECT_EQ(kWhenDone.value, WhenDone::kSpread);  // ours: the stop rule ends a scan, not the map
  EXPECT_EQ(kRig.value, RigKind::kArm);
}

TEST(ScanOptions, EveryDefaultLiesInItsOwnRange) {
  expect_default_in_range(kCandidates);
  expect_default_in_range(kParallels);
  expect_default_in_range(kSectors);
  expect_default_in_range(kTMax);
  expect_default_in_range(kWorkingDistance);
  expect_default_in_range(kStopFraction);
  expect_default_in_range(kStopWindow);
  expect_default_in_range(kStopNewSurface);
  expect_default_in_range(kStopMinViews);
  expect_default_in_range(kStopRadius);
  expect_default_in_range(kAlternatives);
  expect_default_in_range(kPlannerSeed);
  expect_default_in_range(kMixtureSeed);
  expect_default_in_range(kMapResolution);
  expect_default_in_range(kFrontierMargin);
  expect_default_in_range(kCloudVoxel);
  expect_default_in_range(kImageWidth);
  expect_default_in_range(kImageHeight);
  expect_default_in_range(kFocalX);
  expect_default_in_range(kFocalY);
  expect_default_in_range(kPrincipalX);
  expect_default_in_range(kPrincipalY);
  expect_default_in_range(kDepthMin);
  expect_default_in_range(kDepthMax);
  expect_default_in_range(kObjectSize);
  expect_default_in_range(kViews);
  expect_default_in_range(kRingElevation);
  EXPECT_TRUE(kRingElevation.allows(kRingElevationFreeDeg));
  expect_default_in_range(kSpeedScale);
  expect_default_in_range(kSimSpeed);
  expect_default_in_range(kDepthNoise);
  expect_default_in_range(kDropout);
  expect_default_in_range(kHandEyeErrorMm);
  expect_default_in_range(kHandEyeErrorDeg);
  expect_default_in_range(kTurntableErrorDeg);
  expect_default_in_range(kJointErrorDeg);
  expect_default_in_range(kErrorSeed);
  EXPECT_LE(kParallels.value, kCandidates.value);
  EXPECT_LT(kDepthMin.value, kDepthMax.value);
}

TEST(ScanOptions, EveryStructStartsFromTheTable) {
  const ScanSettings s;
  EXPECT_EQ(s.views, kViews.value);
  EXPECT_EQ(s.candidates, kCandidates.value);
  EXPECT_EQ(s.parallels, kParallels.value);
  EXPECT_EQ(s.sectors, kSectors.value);
  EXPECT_EQ(s.t_max, kTMax.value);
  EXPECT_EQ(s.map_resolution_m, kMapResolution.value);
  EXPECT_EQ(s.voxel_m, kCloudVoxel.value);
  EXPECT_EQ(s.working_distance_m, kWorkingDistance.value);
  EXPECT_EQ(s.stop_fraction, kStopFraction.value);
  EXPECT_EQ(s.alternatives, kAlternatives.value);
  EXPECT_EQ(s.seed, kPlannerSeed.value);
  EXPECT_EQ(s.sim_speed, kSimSpeed.value);
  EXPECT_EQ(s.speed_scale, kSpeedScale.value);
  EXPECT_EQ(s.planner, kPlanner.value);
  EXPECT_EQ(s.area, kArea.value);
  EXPECT_EQ(s.when_done, kWhenDone.value);
  EXPECT_EQ(s.rig, kRig.value);
  EXPECT_EQ(s.camera.width, kImageWidth.value);
  EXPECT_EQ(s.camera.fx, kFocalX.value);
  EXPECT_EQ(s.depth_range.max_m, kDepthMax.value);
  EXPECT_NO_THROW(s.validate());

  const PlanInput in;
  EXPECT_EQ(in.candidates.num_views, kCandidates.value);
  EXPECT_EQ(in.candidates.num_parallels, kParallels.value);
  EXPECT_EQ(in.candidates.working_distance_m, kWorkingDistance.value);
  EXPECT_EQ(in.candidates.area, kArea.value);
  EXPECT_EQ(in.beta, kSectors.value);
  EXPECT_EQ(in.num_alternatives, kAlternatives.value);
  EXPECT_EQ(in.when_done, kWhenDone.value);
  EXPECT_EQ(EllipsoidParams{}.t_max, kTMax.value);
  EXPECT_EQ(EllipsoidParams{}.voxel_m, kMapResolution.value);
  EXPECT_EQ(VoxelMapParams{}.resolution_m, kMapResolution.value);
  EXPECT_EQ(VoxelMapParams{}.gamma_m, kFrontierMargin.value);
}

template <typename E>
void expect_names_round_trip(const std::string& what, const std::string& choices) {
  for (const auto& n : EnumNames<E>::names) {
    EXPECT_EQ(name_of(n.value), n.name);
    EXPECT_EQ(parse_name<E>(n.name), n.value);
  }
  EXPECT_EQ(choices_of<E>(), choices);
  EXPECT_EQ(error_message([] { parse_name<E>("nonsense"); }),
            "unknown " + what + " 'nonsense' (expected " + choices + ")");
}

TEST(ScanKinds, EveryNameRoundTripsAndAnUnknownOneIsNamedWithTheChoices) {
  expect_names_round_trip<PlannerKind>("planner", "pbnbv, pbnbv-paper, raycast, random, ring or oracle");
  expect_names_round_trip<CandidateArea>("candidate area", "hemi or full");
  expect_names_round_trip<WhenDone>("when-done rule", "stop or spread");
  expect_names_round_trip<RigKind>("rig kind", "arm or free");
  expect_names_round_trip<UpAxis>("up axis", "z, y or x");
  expect_names_round_trip<OnOff>("switch", "on or off");
  expect_names_round_trip<StopRule>("stop rule", "surface, seconds or off");
  EXPECT_EQ(to_string(RigKind::kFree), "free");
  EXPECT_EQ(parse_rig_kind("arm"), RigKind::kArm);
  EXPECT_THROW(parse_name<PlannerKind>("Ring"), std::invalid_argument);  // exact names only
  EXPECT_TRUE(uses_view_scorer(PlannerKind::kRaycast));
  EXPECT_FALSE(uses_view_scorer(PlannerKind::kRing));
  EXPECT_TRUE(uses_ellipsoids(PlannerKind::kPbnbv));
  EXPECT_TRUE(uses_ellipsoids(PlannerKind::kPbnbvPaper));
  EXPECT_FALSE(uses_ellipsoids(PlannerKind::kRandom));
}

TEST(ScanSettingsJson, KindsAreWrittenAsTheSameTextAndReadBack) {
  ScanSettings s;
  s.scan_id = "x";
  s.planner = PlannerKind::kRing;
  s.area = CandidateArea::kFullSphere;
  s.when_done = WhenDone::kSpread;
  s.rig = RigKind::kFree;
  s.normalisation.up = UpAxis::kY;
  const nlohmann::json j = to_json(s);
  EXPECT_EQ(j["planner"], "ring");
  EXPECT_EQ(j["rig"], "free");
  EXPECT_EQ(j["planning"]["area"], "full");
  EXPECT_EQ(j["planning"]["when_done"], "spread");
  EXPECT_EQ(j["object"]["normalisation"]["up"], "y");
  const ScanSettings back = scan_settings_from_json(j);
  EXPECT_EQ(back.planner, PlannerKind::kRing);
  EXPECT_EQ(back.area, CandidateArea::kFullSphere);
  EXPECT_EQ(back.when_done, WhenDone::kSpread);
  EXPECT_EQ(back.rig, RigKind::kFree);
  EXPECT_EQ(back.normalisation.up, UpAxis::kY);
  EXPECT_EQ(to_json(back), j);
  EXPECT_EQ(j["stop_rule"]["rule"], "surface");  // the default
  EXPECT_EQ(back.surface_rule.window, kStopWindow.value);

  nlohmann::json bad = j;
  bad.erase("stop_rule");  // a scan recorded before the rule existed ran without it
  EXPECT_EQ(scan_settings_from_json(bad).stop_rule, StopRule::kOff);
  bad = j;
  bad["stop_rule"]["window"] = 0;
  EXPECT_EQ(error_message([&] { scan_settings_from_json(bad); }), "scan settings: --stop-window 0 is outside its range [1, 100]");
  bad = j;
  bad["planner"] = "greedy";
  EXPECT_EQ(error_message([&] { scan_settings_from_json(bad); }),
            "scan settings: unknown planner 'greedy' (expected pbnbv, pbnbv-paper, raycast, random, ring or oracle)");
  bad = j;
  bad["planning"]["candidates"] = 0;
  EXPECT_EQ(error_message([&] { scan_settings_from_json(bad); }),
            "scan settings: --candidates 0 is outside its range [1, 100000]");
  bad = j;
  bad["planning"]["parallels"] = 900;
  bad["planning"]["candidates"] = 100;
  EXPECT_EQ(error_message([&] { scan_settings_from_json(bad); }),
            "scan settings: --parallels 900 must not exceed --candidates 100");
}

}  // namespace
}  // namespace pbnbv
