#pragma once
// One number formatter for every program (libfmt): numbers on command lines and in files that
// must read back as the same double, numbers in reports and logs with fixed decimals, and the
// numbered file names of a scan's folder.
#include <fmt/format.h>

#include <string>

namespace pbnbv {

// The shortest text that reads back as exactly the same double (fmt's "{}"): 0.1 -> "0.1",
// 1.0 / 3 -> "0.3333333333333333".
inline std::string exact(double x) { return fmt::format("{}", x); }

// x with `digits` decimals: fixed(2.345, 1) -> "2.3".
inline std::string fixed(double x, int digits = 1) { return fmt::format("{:.{}f}", x, digits); }

// A per-view file name of a scan's folder for the view with the 0-based iteration `view` (scan.json's
// "view" is view + 1): files count views from 1, as scan.json, the titles and progress lines do, so view_file(0, "ply")
// -> "view_001.ply" is the first view's file and view_file(3, "png") -> "view_004.png" the fourth's.
inline std::string view_file(int view, const char* extension) {
  return fmt::format("view_{:03d}.{}", view + 1, extension);
}

// A view's files in the scan's folder, as scan.json and REGISTERED_CLOUD name them: its cloud
// "frames/view_NNN.ply" and its depth image "depth/view_NNN.png". Every reader takes these names
// and no other path.
inline std::string frame_file_of(int view) { return "frames/" + view_file(view, "ply"); }
inline std::string depth_file_of(int view) { return "depth/" + view_file(view, "png"); }

}  // namespace pbnbv
