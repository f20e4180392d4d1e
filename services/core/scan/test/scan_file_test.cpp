// scan.json's format: a record this pbnbv writes is read back; a record of another format, or of
// none, is refused naming both formats and the writer; the launcher's last word on a scan's state.
#include "core/scan/scan_file.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "core/base/version.hpp"
#include "core/io/json.hpp"
#include "core/scan/scan_record.hpp"
#include "error_message.hpp"
#include "file_test_util.hpp"

using namespace pbnbv;
using nlohmann::json;

namespace {

class ScanFileTest : public pbnbv::testing::TempDirTest {
 protected:
  std::string path() const { return (dir_ / "scan.json").string(); }

  // The message read_scan_json throws for the folder.
  std::string refusal() const {
    return pbnbv::testing::error_message([&] { read_scan_json(dir_); });
  }
};

TEST_F(ScanFileTest, ARecordOfThisVersionIsReadBack) {
  ScanSettings s;
  s.scan_id = "format";
  ScanRecord record(dir_, s);
  record.write("running", "", 0, 0.0);
  const json scan = read_scan_json(dir_);  // the folder or the file itself
  EXPECT_EQ(scan["format_version"], kScanFormatVersion);
  EXPECT_EQ(scan["pbnbv_version"], std::string(pbnbv_version()));
  EXPECT_EQ(scan["settings"]["scan_id"], "format");
  EXPECT_EQ(read_scan_json(path()), scan);
  EXPECT_EQ(recorded_state(dir_), "running");
}

TEST_F(ScanFileTest, AnotherFormatIsRefusedNamingBothFormatsAndTheWriter) {
  const std::string mine = std::string(pbnbv_version());
  write_json_atomic({{"format_version", 3}, {"pbnbv_version", "0.13.0"}, {"status", {{"state", "done"}}}}, path());
  EXPECT_EQ(refusal(), path() + ": format 3 (written by pbnbv 0.13.0); this pbnbv (" + mine + ") reads format 2 only");
  // Format 1 counted views from 0: refused, not read one view off.
  write_json_atomic({{"format_version", 1}, {"pbnbv_version", "0.11.0"}, {"views", {{{"view", 0}}}}}, path());
  EXPECT_EQ(refusal(), path() + ": format 1 (written by pbnbv 0.11.0); this pbnbv (" + mine + ") reads format 2 only");
  write_json_atomic({{"format_version", 0}}, path());
  EXPECT_EQ(refusal(), path() + ": format 0 (written by an unknown pbnbv); this pbnbv (" + mine + ") reads format 2 only");
  write_json_atomic({{"settings", json::object()}, {"status", {{"state", "done"}}}}, path());
  EXPECT_EQ(refusal(), path() + ": a record without format_version (written by pbnbv 0.10 or older); this pbnbv (" + mine +
                           ") reads format 2 only");
  // The state of a record of any format is still read (a bench rerun skips complete scans).
  EXPECT_EQ(recorded_state(dir_), "done");
  write_json_atomic({{"format_version", "2"}}, path());
  EXPECT_NE(refusal().find("format_version"), std::string::npos) << refusal();
  write_json_atomic(json::array({1, 2}), path());
  EXPECT_EQ(refusal(), path() + ": not a scan record (expected a JSON object)");
}

TEST_F(ScanFileTest, TheStateOfAFolderWithoutARecordIsEmpty) {
  EXPECT_EQ(recorded_state(dir_), "");
  std::ofstream(path()) << "{ not json";
  EXPECT_EQ(recorded_state(dir_), "");
  EXPECT_THROW(read_scan_status(dir_), std::exception);
}

TEST_F(ScanFileTest, TheLaunchersWordOnTheStateKeepsTheRecordAndStartsOneWhereNone) {
  write_scan_state(dir_, "failed", "the coordinator died (signal 9)");
  json scan = read_scan_json(dir_);
  EXPECT_EQ(scan["status"], json({{"state", "failed"}, {"message", "the coordinator died (signal 9)"}}));
  ScanSettings s;
  s.scan_id = "kept";
  ScanRecord record(dir_, s);
  record.write("running", "", 3, 12.5);
  write_scan_state(dir_, "stopped", "interrupted (SIGINT)");
  scan = read_scan_json(dir_);
  EXPECT_EQ(scan["status"]["state"], "stopped");
  EXPECT_EQ(scan["status"]["message"], "interrupted (SIGINT)");
  EXPECT_EQ(scan["status"]["views_done"], 3);  // the rest of the record stands
  EXPECT_EQ(scan["settings"]["scan_id"], "kept");
}

}  // namespace

namespace {

// A view entry names its own frame file or none: view N (counted from 1) is frames/view_NNN.ply.
// A planted path (another view's, outside the folder) is refused naming the file and the view,
// before anything opens it.
TEST(ViewFrameFile, IsTheViewsOwnOrNone) {
  const std::filesystem::path where = "/scans/a/scan.json";
  EXPECT_EQ(view_frame_file(nlohmann::json{{"view", 3}, {"frame_file", "frames/view_003.ply"}}, where), "frames/view_003.ply");
  EXPECT_EQ(view_frame_file(nlohmann::json{{"view", 1}, {"frame_file", "frames/view_001.ply"}}, where), "frames/view_001.ply");
  EXPECT_EQ(view_frame_file(nlohmann::json{{"view", 1000}, {"frame_file", "frames/view_1000.ply"}}, where), "frames/view_1000.ply");
  EXPECT_EQ(view_frame_file(nlohmann::json{{"view", 3}}, where), "");
  for (const char* planted : {"../../etc/passwd", "frames/view_002.ply", "/tmp/x.ply"}) {
    pbnbv::testing::expect_error([&] { view_frame_file(nlohmann::json{{"view", 3}, {"frame_file", planted}}, where); },
                                 "/scans/a/scan.json view 3: frame_file is not frames/view_003.ply");
  }
  for (const int outside : {0, -1, 1001}) {
    pbnbv::testing::expect_error(
        [&] { view_frame_file(nlohmann::json{{"view", outside}, {"frame_file", "frames/view_000.ply"}}, where); },
        "/scans/a/scan.json: a view entry with a frame_file has no view number 1..1000");
  }
  pbnbv::testing::expect_error([&] { view_frame_file(nlohmann::json{{"frame_file", "frames/view_001.ply"}}, where); },
                               "has no view number");
}

}  // namespace
