// libFuzzer target: a rig file (MJCF) as --rig-model reads it (load_rig: MuJoCo's parser, then our
// checks of the joints, sites and camera the pipeline needs). The input is the file, written
// beside nothing else: an include of another file names a file that is not there. A rig load_rig
// accepts must be one the pipeline can use: finite, ordered joint limits, positive joint speeds,
// and a camera (when it states one) the contract allows.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "core/rig/rig.hpp"
#include "fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = pbnbv::fuzz::write_input(pbnbv::fuzz::as_text(data, size), "rig.xml");
  pbnbv::RigModel rig;
  try {
    rig = pbnbv::load_rig(path);
  } catch (const std::exception&) {  // refused, naming the file
    return 0;
  }
  const bool limits_ok = rig.q_lower.allFinite() && rig.q_upper.allFinite() && (rig.q_lower.array() <= rig.q_upper.array()).all() &&
                         rig.qd_max.allFinite() && (rig.qd_max.array() > 0).all();
  if (!limits_ok) {
    std::fprintf(stderr, "load_rig accepted joint limits or speeds the pipeline cannot use\n");
    std::abort();
  }
  if (rig.camera) {
    try {
      rig.camera->intrinsics.validate();
      rig.camera->range.validate();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "load_rig accepted a camera the contract refuses: %s\n", e.what());
      std::abort();
    }
  }
  return 0;
}
