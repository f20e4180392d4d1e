#pragma once
// The depth camera's settings, each defined once (core/base/setting.hpp): the paper's simulated
// RealSense D435. CameraIntrinsics and DepthRange take their defaults from here; so do the
// launcher's and the twin's options.
#include "core/base/setting.hpp"

namespace pbnbv {

inline constexpr Setting<int> kImageWidth{"width", 1280, 1, 16384, "px", "depth image width"};
inline constexpr Setting<int> kImageHeight{"height", 720, 1, 16384, "px", "depth image height"};
// The largest image, pixels: a 4096 x 4096 sensor (the twin's 1280 x 720 is 0.9 M; depth sensors
// on the market stay under 5 M). Each side may reach 16384, the two together not: a DEPTH_FRAME,
// a cloud and the bus's message limits are bounded by it (CameraIntrinsics::validate).
inline constexpr long long kMaxImagePixels = 4096LL * 4096;
inline constexpr Setting<double> kFocalX{"fx", 696.0, 1.0, 1e5, "px", "focal length along u"};
inline constexpr Setting<double> kFocalY{"fy", 696.0, 1.0, 1e5, "px", "focal length along v"};
// The principal point's default is the image centre (width / 2, height / 2); it must lie in the
// image (CameraIntrinsics::validate).
inline constexpr Setting<double> kPrincipalX{"cx", 640.0, 0.0, 16384.0, "px", "principal point u"};
inline constexpr Setting<double> kPrincipalY{"cy", 360.0, 0.0, 16384.0, "px", "principal point v"};
inline constexpr Setting<double> kDepthMin{"depth-min", 0.1, 0.001, 10.0, "m", "nearest valid depth"};
inline constexpr Setting<double> kDepthMax{"depth-max", 3.0, 0.01, 6.5, "m", "farthest valid depth"};

}  // namespace pbnbv
