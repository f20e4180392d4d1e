// `pbnbv calibrate` against the twin, each case in its own network namespace: the twin alone
// (started as a rig's drivers would be) with a 5 mm / 1 deg camera mount error and a 0.5 deg
// turntable zero error, the calibration sphere on the platter mark; the calibration must find the
// twin's true mount within 0.5 mm / 0.05 deg and the true zero within 0.05 deg (the twin's
// --truth-rig-out is the judge). And the errors a user meets: no drivers, no sphere.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "core/base/pose.hpp"
#include "core/base/units.hpp"
#include "core/io/json.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace pbnbv;
using namespace pbnbv::testing;
using nlohmann::json;

namespace {

constexpr double kDeg = kPi / 180;

// The twin (in the background) and `pbnbv calibrate` in one namespace; the twin stopped after.
CommandResult calibrate_with_twin(const fs::path& dir, const std::string& twin_args, const std::string& calibrate_args) {
  const std::string twin = bin_dir() + "/pbnbv-twin --speed 8 --model-out " + (dir / "twin_model.xml").string() +
                           " --truth-rig-out " + (dir / "truth_rig.json").string() + " " + twin_args + " > " +
                           (dir / "twin.log").string() + " 2>&1";
  const std::string calibrate = bin_dir() + "/pbnbv calibrate --rig-model " + source_dir() +
                                "/models/rig_arm.xml --status-wait 60 --out " + (dir / "cal").string() + " " +
                                calibrate_args;
  return run_command(netns_run() + " sh -c '" + twin + " & t=$!; " + calibrate + "; s=$?; kill $t; wait $t; exit $s'");
}

TEST(CalibrationIntegration, RecoversTheTwinsTrueMountAndTurntableZero) {
  const fs::path dir = fresh_dir("calibrate");
  const CommandResult r = calibrate_with_twin(
      dir, "--hand-eye-error-mm 5 --hand-eye-error-deg 1 --turntable-error-deg 0.5 --calibration-sphere 0.05",
      "--sphere-radius 0.05");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json truth = read_json((dir / "truth_rig.json").string());
  const json cal = read_json((dir / "cal" / "calibration.json").string());
  const Pose true_mount = pose_from_json(truth["flange_T_camera"], "truth flange_T_camera");
  const Pose model_mount = pose_from_json(truth["model_flange_T_camera"], "model flange_T_camera");
  const Pose found = pose_from_json(cal["flange_T_camera"], "calibrated flange_T_camera");
  const double mm = (found.translation() - true_mount.translation()).norm() * 1e3;
  const double deg = rotation_angle_rad(found.linear(), true_mount.linear()) / kDeg;
  const double zero_deg = (cal["turntable_zero_rad"].get<double>() - truth["turntable_zero_rad"].get<double>()) / kDeg;
  std::cout << "twin: mount off the model's by " << (model_mount.translation() - true_mount.translation()).norm() * 1e3
            << " mm / " << rotation_angle_rad(model_mount.linear(), true_mount.linear()) / kDeg << " deg, zero by "
            << truth["turntable_error_rad"].get<double>() / kDeg << " deg\n"
            << "calibrated: mount within " << mm << " mm / " << deg << " deg of the truth, zero within " << zero_deg
            << " deg; residual rms " << cal["rms_before_mm"].get<double>() << " -> " << cal["rms_after_mm"].get<double>()
            << " mm over " << cal["frames_used"].get<int>() << " frames; axis tilt "
            << cal["turntable_axis"]["tilt_from_model_deg"].get<double>() << " deg\n"
            << r.output;
  EXPECT_LE(mm, 0.5);
  EXPECT_LE(deg, 0.05);
  EXPECT_LE(std::abs(zero_deg), 0.05);
  // The twin's axis is the model's: the estimate says so.
  EXPECT_LE(cal["turntable_axis"]["tilt_from_model_deg"].get<double>(), 0.05);
  // The error was there to be found, and the calibration explains the frames down to the fit.
  EXPECT_GT(cal["rms_before_mm"].get<double>(), 3.0);
  EXPECT_LT(cal["rms_after_mm"].get<double>(), 0.02);
  EXPECT_GE(cal["frames_used"].get<int>(), 18);
  // The calibrated file is the model's with the mount and the zero replaced.
  EXPECT_TRUE(fs::exists(dir / "cal" / "rig_calibrated.xml"));
  EXPECT_TRUE(fs::exists(dir / "cal" / "report.md"));
}

TEST(CalibrationIntegration, SilentDriversAreNamed) {
  const fs::path dir = fresh_dir("calibrate-silent");
  const CommandResult r = run_command(netns_run() + " " + bin_dir() + "/pbnbv calibrate --rig-model " + source_dir() +
                                      "/models/rig_arm.xml --sphere-radius 0.05 --status-wait 1 --out " + dir.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("no ARM_STATUS (the arm driver) and TURNTABLE_STATUS (the turntable driver) within 1.0 s"),
            std::string::npos)
      << r.output;
}

TEST(CalibrationIntegration, NoSphereOnThePlatterIsAnError) {
  const fs::path dir = fresh_dir("calibrate-nosphere");
  const CommandResult r = calibrate_with_twin(dir, "", "--sphere-radius 0.05 --views 6");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("the sphere was fitted in 0 of 6 views"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("view 0 skipped"), std::string::npos) << r.output;
}

}  // namespace
