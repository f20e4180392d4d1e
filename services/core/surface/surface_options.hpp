#pragma once
// The surface-mesh settings, each defined once (core/base/setting.hpp): the method and the TSDF's
// voxel and truncation, Poisson's octree depth.
#include "core/base/enum_names.hpp"
#include "core/base/setting.hpp"
#include "core/io/mesh_file.hpp"

namespace pbnbv {

enum class MeshMethod { kTsdf, kPoisson };
template <>
struct EnumNames<MeshMethod> {
  static constexpr std::string_view what = "mesh method";
  static constexpr std::array<NamedValue<MeshMethod>, 2> names{
      {{MeshMethod::kTsdf, "tsdf"}, {MeshMethod::kPoisson, "poisson"}}};
};

template <>
struct EnumNames<LengthUnit> {
  static constexpr std::string_view what = "length unit";
  static constexpr std::array<NamedValue<LengthUnit>, 2> names{{{LengthUnit::kMetre, "m"}, {LengthUnit::kMillimetre, "mm"}}};
};

inline constexpr ChoiceSetting<LengthUnit> kMeshUnits{
    "units", LengthUnit::kMetre, "length unit of mesh.obj and mesh.stl: m (the scan's) or mm (CAD tools')"};

inline constexpr ChoiceSetting<MeshMethod> kMeshMethod{
    "mesh-method", MeshMethod::kTsdf,
    "surface mesh: tsdf (fusion of the frames + marching cubes, holes left open) or poisson (closed)"};
inline constexpr Setting<double> kMeshVoxel{"mesh-voxel", 0.002, 0.0002, 0.05, "m", "TSDF voxel edge"};
inline constexpr Setting<double> kMeshTruncation{"mesh-truncation", 4.0, 1.5, 20.0, "voxels",
                                                 "TSDF truncation distance, in voxels"};
inline constexpr Setting<int> kPoissonDepth{"poisson-depth", 9, 5, 12, "", "Poisson octree depth"};
inline constexpr Setting<double> kMeshFillHoles{"mesh-fill-holes", 0.02, 0.0, 1.0, "m",
                                                "close the mesh's holes whose rim is at most this long (0: none)"};
inline constexpr Setting<int> kMeshNormalNeighbours{"mesh-normal-neighbours", 12, 4, 64, "",
                                                    "Poisson: neighbours a point's normal is fitted to"};

}  // namespace pbnbv
