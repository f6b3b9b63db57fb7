// Tests for depth_holes.hpp: short gaps in a raw depth image get depth.
#include "findmug/frame/depth_holes.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "findmug/common/error.hpp"

namespace findmug {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

DepthHoleFillConfig fillUpTo(int max_run_px) {
  DepthHoleFillConfig config;
  config.max_run_px = max_run_px;
  return config;
}

TEST(DepthHoles, AGapOnOneSurfaceIsInterpolated) {
  // One row: a specular spot on a table top seen at a slant, 2000 -> 2040 mm.
  std::vector<std::uint16_t> depth = {2000, 0, 0, 0, 2040};
  EXPECT_EQ(fillDepthHoles(depth, 5, 1, fillUpTo(40)), 3u);
  EXPECT_THAT(depth, ElementsAre(2000, 2010, 2020, 2030, 2040));
}

TEST(DepthHoles, AGapAtAStepTakesTheFartherSide) {
  // A shadow between a chair back (1200 mm) and the wall behind it (3000 mm).
  std::vector<std::uint16_t> depth = {1200, 0, 0, 3000};
  EXPECT_EQ(fillDepthHoles(depth, 4, 1, fillUpTo(40)), 2u);
  EXPECT_THAT(depth, ElementsAre(1200, 3000, 3000, 3000));
  // The tolerance decides what a step is: 5 % apart is one surface at 0.06.
  std::vector<std::uint16_t> slanted = {1000, 0, 1050};
  DepthHoleFillConfig loose = fillUpTo(40);
  loose.smooth_tolerance = 0.06f;
  fillDepthHoles(slanted, 3, 1, loose);
  EXPECT_THAT(slanted, ElementsAre(1000, 1025, 1050));
  slanted = {1000, 0, 1050};
  fillDepthHoles(slanted, 3, 1, fillUpTo(40));  // 0.03: a step
  EXPECT_THAT(slanted, ElementsAre(1000, 1050, 1050));
}

TEST(DepthHoles, LongGapsBorderGapsAndOffStayEmpty) {
  std::vector<std::uint16_t> window = {2000, 0, 0, 0, 2000};
  EXPECT_EQ(fillDepthHoles(window, 5, 1, fillUpTo(2)), 0u);  // 3 > 2: a window stays empty
  EXPECT_THAT(window, ElementsAre(2000, 0, 0, 0, 2000));
  std::vector<std::uint16_t> border = {0, 0, 2000, 2000};
  EXPECT_EQ(fillDepthHoles(border, 4, 1, fillUpTo(40)), 0u);  // one side only: not guessed
  EXPECT_THAT(border, ElementsAre(0, 0, 2000, 2000));
  std::vector<std::uint16_t> off = {2000, 0, 2000};
  EXPECT_EQ(fillDepthHoles(off, 3, 1, DepthHoleFillConfig{}), 0u);  // the default is off
  EXPECT_THAT(off, ElementsAre(2000, 0, 2000));
}

TEST(DepthHoles, ColumnsThenRows) {
  // The centre's column is one surface (2000 above and below), its row a step
  // (1000 | 3000): the column pass, which runs first, fills it by interpolation;
  // rows first would have given it the farther 3000.
  std::vector<std::uint16_t> depth = {1000, 2000, 3000,  //
                                      1000, 0,    3000,  //
                                      1000, 2000, 3000};
  EXPECT_EQ(fillDepthHoles(depth, 3, 3, fillUpTo(40)), 1u);
  EXPECT_EQ(depth[4], 2000);
  // A gap the columns cannot close (it touches the top border) the rows fill.
  std::vector<std::uint16_t> top = {1000, 0, 1000,  //
                                    1000, 1000, 1000};
  EXPECT_EQ(fillDepthHoles(top, 3, 2, fillUpTo(40)), 1u);
  EXPECT_EQ(top[1], 1000);
}

TEST(DepthHoles, BadSizesAndSettingsAreRefused) {
  std::vector<std::uint16_t> depth(5, 1000);
  auto message = [&](int width, int height, DepthHoleFillConfig config) {
    try {
      fillDepthHoles(depth, width, height, config);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_THAT(message(2, 2, fillUpTo(40)), HasSubstr("5 pixels, not 2 x 2"));
  EXPECT_THAT(message(5, 1, fillUpTo(-1)), HasSubstr("cloud.fill_depth_max_run_px"));
  DepthHoleFillConfig bad = fillUpTo(40);
  bad.smooth_tolerance = 2.0f;
  EXPECT_THAT(message(5, 1, bad), HasSubstr("cloud.fill_depth_smooth_tolerance"));
}

}  // namespace
}  // namespace findmug
