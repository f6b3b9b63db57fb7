// DepthView (findmug/map/depth_view.hpp): a map point out of view, without depth, hidden
// behind something nearer, or shown by one depth frame.
#include "findmug/map/depth_view.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "findmug/common/error.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/map/semantic_map.hpp"
#include "table_scenes.hpp"

namespace findmug {
namespace {

using P = DepthView::Point;

TEST(DepthView, TellsShownHiddenNoDepthAndOutOfView) {
  const Eigen::Isometry3d camera = test::headCamera(Pose2D{0.0, 0.0, 0.0});
  const RgbdFrame floor = test::depthOfTops({}, camera);
  const DepthView view(floor, camera);
  const Eigen::Vector3d on_floor(2.0, 0.0, 0.0), above_floor(2.0, 0.0, 0.5);
  EXPECT_EQ(view.show(on_floor, 0.1, 0), P::Shown);
  // A point in the air in front of the floor: the depth passes it, nothing hides it.
  EXPECT_EQ(view.show(above_floor, 0.1, 0), P::Shown);
  // Below the floor: the floor is in front of it, hidden beyond the margin only.
  const Eigen::Vector3d under(2.0, 0.0, -0.3);
  EXPECT_EQ(view.show(under, 0.1, 0), P::Hidden);
  EXPECT_EQ(view.show(under, 5.0, 0), P::Shown);
  EXPECT_EQ(view.show(Eigen::Vector3d(-2.0, 0.0, 0.0), 0.1, 0), P::OutOfView);  // behind
  EXPECT_EQ(view.show(Eigen::Vector3d(2.0, 5.0, 0.0), 0.1, 0), P::OutOfView);   // aside
  EXPECT_EQ(view.cameraPosition().z(), camera.translation().z());

  RgbdFrame holes = floor;
  std::fill(holes.depth_mm.begin(), holes.depth_mm.end(), std::uint16_t{0});
  EXPECT_EQ(DepthView(holes, camera).show(on_floor, 0.1, 0), P::NoDepth);
}

TEST(DepthView, TheImageBorderCountsAsOutOfView) {
  const Eigen::Isometry3d camera = test::headCamera(Pose2D{0.0, 0.0, 0.0});
  const RgbdFrame floor = test::depthOfTops({}, camera);
  const DepthView view(floor, camera);
  // Walk sideways until the point leaves the image with no border, then ask with one.
  Eigen::Vector3d p(2.0, 0.0, 0.0);
  while (view.show(p, 0.1, 0) == P::Shown) p.y() += 0.01;
  p.y() -= 0.01;
  EXPECT_EQ(view.show(p, 0.1, 0), P::Shown);
  EXPECT_EQ(view.show(p, 0.1, 20), P::OutOfView);
}

TEST(DepthView, AFrameWithoutItsDepthImageIsRefused) {
  RgbdFrame frame;
  frame.width = 640;
  frame.height = 480;
  frame.source = "bad.png";
  try {
    DepthView view(frame, Eigen::Isometry3d::Identity());
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.png"), std::string::npos);
  }
}

}  // namespace
}  // namespace findmug
