#pragma once
// The version of this pbnbv (CMake's PROJECT_VERSION): printed by --version and written into the
// files a scan leaves (scan.json's pbnbv_version) so that a reader can name the writer.
#include <string_view>

namespace pbnbv {

std::string_view pbnbv_version();

}  // namespace pbnbv
