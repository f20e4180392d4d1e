#include "core/base/version.hpp"

namespace pbnbv {

std::string_view pbnbv_version() { return PBNBV_VERSION; }

}  // namespace pbnbv
