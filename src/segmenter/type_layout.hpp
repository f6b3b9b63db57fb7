// type_layout.hpp — sizes, alignments and a few member offsets of the core's
// types that hold fixed-size Eigen members, as seen by the code that includes
// this header.
//
// Why: the core is also built for x86-64-v3 (src/CMakeLists.txt), and the
// loader may pair that copy with programs compiled for plain x86-64. With AVX
// enabled, Eigen would align types such as Matrix4f and Isometry3f to 32
// bytes instead of 16, and a struct holding one (GroundPlane, PreparedFrame)
// would have another size and other member offsets in the library than in
// its callers. coreTypeLayouts() gives the library's view, typeLayoutsHere()
// the caller's; a test (TypeLayout.LibraryAndCallerAgree) compares them.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

#include "findmug/features/features.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/tables/tables.hpp"

namespace findmug::detail {

struct TypeLayout {
  const char* name;
  std::size_t size;
  std::size_t align;
  std::size_t offset;  // of the member named in `name` after "::", else 0

  bool operator==(const TypeLayout&) const = default;
};

// The layouts as compiled where this is called (inline: the caller's view).
inline std::vector<TypeLayout> typeLayoutsHere() {
  const auto of = [](const char* name, std::size_t size, std::size_t align,
                     std::size_t offset = 0) { return TypeLayout{name, size, align, offset}; };
  return {
      of("Eigen::Matrix4f", sizeof(Eigen::Matrix4f), alignof(Eigen::Matrix4f)),
      of("Eigen::Isometry3f", sizeof(Eigen::Isometry3f), alignof(Eigen::Isometry3f)),
      of("Eigen::Vector4d", sizeof(Eigen::Vector4d), alignof(Eigen::Vector4d)),
      of("Eigen::Matrix2d", sizeof(Eigen::Matrix2d), alignof(Eigen::Matrix2d)),
      of("Eigen::Isometry3d", sizeof(Eigen::Isometry3d), alignof(Eigen::Isometry3d)),
      of("GroundPlane::camera_to_ground", sizeof(GroundPlane), alignof(GroundPlane),
         offsetof(GroundPlane, camera_to_ground)),
      of("GroundPlane::support_points", sizeof(GroundPlane), alignof(GroundPlane),
         offsetof(GroundPlane, support_points)),
      of("SegmentMoments", sizeof(SegmentMoments), alignof(SegmentMoments)),
      of("SegmentFeatures", sizeof(SegmentFeatures), alignof(SegmentFeatures)),
      of("PreparedFrame", sizeof(PreparedFrame), alignof(PreparedFrame)),
      of("SegmentedFrame", sizeof(SegmentedFrame), alignof(SegmentedFrame)),
      of("LabelledFrame", sizeof(LabelledFrame), alignof(LabelledFrame)),
      of("TableCluster", sizeof(TableCluster), alignof(TableCluster)),
      of("TableDetection", sizeof(TableDetection), alignof(TableDetection)),
  };
}

// The same list as the library was compiled (out of line, in type_layout.cpp).
std::vector<TypeLayout> coreTypeLayouts();

}  // namespace findmug::detail
