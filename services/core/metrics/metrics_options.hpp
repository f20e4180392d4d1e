#pragma once
// The surface-metric settings, each defined once (core/base/setting.hpp): the threshold of
// precision / recall / F-score and the density of the samples taken on a mesh.
#include "core/base/setting.hpp"

namespace pbnbv {

inline constexpr Setting<double> kMetricThreshold{
    "threshold", 0.005, 1e-5, 1.0, "m",
    "precision / recall / F-score: a point counts when within this distance of the other surface"};
inline constexpr Setting<double> kMetricSampleDensity{
    "sample-density", 100.0, 0.01, 1e4, "per cm^2",
    "samples per cm^2 of surface, uniform by area, on the reference mesh (completeness, recall) and on a model mesh"};

}  // namespace pbnbv
