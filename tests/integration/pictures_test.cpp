// clients/picture.hpp: table hulls and search positions land in the image where the
// camera sees them (checked against rays cast from chosen pixels through the daemon's own
// camera-to-ground transform), occluded positions become rings, and the top-down map and
// legend show what they claim.
#include <gtest/gtest.h>

#include <cmath>

#include "findmug/ground/ground.hpp"
#include "findmug/tables/tables.hpp"
#include "picture.hpp"

namespace findmug::clients {
namespace {

constexpr CameraIntrinsics kK{300.0, 300.0, 160.0, 120.0};
constexpr CameraExtrinsics kMount{1.2, 0.5, 0.0};  // 1.2 m up, tilted down
constexpr Rgb8 kGrey{100, 100, 100};

// The ground-frame point where the ray through pixel (u, v) meets the plane z = height.
Eigen::Vector3f groundPointAt(double u, double v, float height) {
  const Eigen::Isometry3f to_ground = groundFromExtrinsics(kMount).camera_to_ground;
  const Eigen::Vector3f ray((u - kK.cx) / kK.fx, (v - kK.cy) / kK.fy, 1.0);
  const Eigen::Vector3f origin = to_ground * Eigen::Vector3f::Zero();
  const Eigen::Vector3f direction = to_ground.linear() * ray;
  const float t = (height - origin.z()) / direction.z();
  return origin + t * direction;
}

Rgb8 at(const Canvas& c, int x, int y) {
  return c.image().pixels[static_cast<std::size_t>(y) * c.width() + x];
}

SearchPosition positionAt(double u, double v, bool reachable) {
  SearchPosition p;
  const Eigen::Vector3f g = groundPointAt(u, v, 0.0f);
  p.xy = g.head<2>();
  p.reachable = reachable;
  if (!reachable) p.reason = "obstacle within robot radius";
  return p;
}

io::TablesMessage oneTable() {
  io::TablesMessage m;
  m.seq = 5;
  TableCluster t;
  t.id = 3;
  t.top_height = 0.75f;
  // A quadrilateral seen at these four pixels (counter-clockwise in the ground frame).
  for (auto [u, v] : {std::pair{220.0, 150.0}, {100.0, 150.0}, {120.0, 90.0}, {200.0, 90.0}}) {
    t.hull.push_back(groundPointAt(u, v, t.top_height).head<2>());
  }
  t.hull = convexHull2d(t.hull);
  t.center = groundPointAt(160.0, 120.0, t.top_height).head<2>();
  t.search_positions = {positionAt(60.0, 200.0, true), positionAt(260.0, 200.0, false)};
  m.tables.push_back(t);
  return m;
}

TEST(Pictures, HullAndSearchPositionsAreDrawnWhereTheCameraSeesThem) {
  Canvas canvas(320, 240, kGrey);
  const io::TablesMessage tables = oneTable();
  EXPECT_EQ(drawTablesInImage(canvas, tables, kK, kMount), 1);
  // Hull corners and an edge midpoint: the white line (within a pixel of rounding).
  for (auto [u, v] : {std::pair{220, 150}, {100, 150}, {160, 150}, {200, 90}}) {
    bool white = false;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) white |= at(canvas, u + dx, v + dy) == Rgb8{255, 255, 255};
    }
    EXPECT_TRUE(white) << "hull not at " << u << "," << v;
  }
  // Inside the hull, away from lines and the id label: untouched.
  EXPECT_EQ(at(canvas, 130, 135), kGrey);
  // Reachable position: green disc (number 1 in its middle); unreachable: red disc.
  EXPECT_EQ(at(canvas, 60 + 8, 200), (Rgb8{40, 200, 60}));
  EXPECT_EQ(at(canvas, 260 + 8, 200), (Rgb8{220, 40, 40}));
  EXPECT_EQ(at(canvas, 60, 200 + 14), kGrey);  // outside the marker
}

TEST(Pictures, PositionsBehindASurfaceAreRings) {
  const io::TablesMessage tables = oneTable();
  // The camera saw something 1 m away at the reachable position's pixel: it is hidden.
  std::vector<std::uint16_t> depth(320 * 240, 0);
  depth[200 * 320 + 60] = 1000;
  Canvas canvas(320, 240, kGrey);
  drawTablesInImage(canvas, tables, kK, kMount, &depth);
  EXPECT_EQ(at(canvas, 60 + 6, 200), kGrey);                 // inside the ring: not filled
  EXPECT_NE(at(canvas, 60 + 10, 200), kGrey);                // the ring
  EXPECT_EQ(at(canvas, 260 + 8, 200), (Rgb8{220, 40, 40}));  // no depth there: drawn as usual
}

TEST(Pictures, VisitingOrderNumbersTheReachablePositionsOnly) {
  io::TablesMessage m;
  TableCluster t;
  for (float x : {3.0f, 1.0f, 2.0f}) {
    SearchPosition p;
    p.xy = {x, 0.0f};
    t.search_positions.push_back(p);
  }
  t.search_positions.push_back(SearchPosition{{0.5f, 0.0f}, 0.0f, false, "no observed floor"});
  m.tables.push_back(t);
  const auto numbered = numberedPositions(m, false);
  ASSERT_EQ(numbered.size(), 4u);
  // From the robot at the origin: 1 m, 2 m, 3 m; the unreachable one unnumbered, last.
  for (const auto& p : numbered) {
    if (!p.position.reachable) {
      EXPECT_EQ(p.order, 0);
    } else {
      EXPECT_EQ(p.order, static_cast<int>(std::lround(p.position.xy.x())));
    }
  }
  EXPECT_FALSE(numbered.back().position.reachable);
}

TEST(Pictures, TableMapShowsTablesPositionsAndTheRobotPose) {
  io::TablesMessage m = oneTable();
  m.content = io::TablesContent::Map;
  m.map_pose = io::RobotPose{0, {4.0, -2.0, 1.0}};
  io::MapFrameTable mt;
  mt.hull = {{5, -2}, {6, -2}, {6, -1}, {5, -1}};
  mt.center = {5.5, -1.5};
  mt.search_positions = m.tables[0].search_positions;
  mt.search_positions[0].xy = {5.5f, -2.6f};
  mt.search_positions[1].xy = {5.5f, -0.4f};
  m.map_tables = {mt};
  const std::string svg = tableMapSvg(m, 600);
  EXPECT_NE(svg.find("map frame, seq 5: 1 tables, 2 search positions"), std::string::npos) << svg;
  EXPECT_NE(svg.find("<polygon"), std::string::npos);
  EXPECT_NE(svg.find(">T3</text>"), std::string::npos);
  EXPECT_NE(svg.find(">1</text>"), std::string::npos);
  EXPECT_NE(svg.find("unreachable: obstacle within robot radius"), std::string::npos);
  EXPECT_NE(svg.find(">robot</text>"), std::string::npos);

  const Image<Rgb8> png = tableMapPng(m, 600);
  ASSERT_EQ(png.width, 600);
  ASSERT_EQ(png.height, 600);
  // The table's middle is filled; the robot (blue) is left of it and below (x right, y up).
  auto colour = [&](int x, int y) { return png.pixels[static_cast<std::size_t>(y) * 600 + x]; };
  int table_x = 0, table_y = 0, table_n = 0, robot_x = 0, robot_y = 0, robot_n = 0;
  for (int y = 0; y < 600; ++y) {
    for (int x = 0; x < 600; ++x) {
      if (colour(x, y) == Rgb8{150, 215, 150}) table_x += x, table_y += y, ++table_n;
      if (colour(x, y) == Rgb8{30, 110, 255}) robot_x += x, robot_y += y, ++robot_n;
    }
  }
  ASSERT_GT(table_n, 100);
  ASSERT_GT(robot_n, 100);
  EXPECT_LT(robot_x / robot_n, table_x / table_n);
  EXPECT_GT(robot_y / robot_n, table_y / table_n);
}

// An object candidate's marker sits where the camera sees its centroid, in its mean colour;
// one behind the camera is not drawn.
TEST(Pictures, ObjectMarkersAreDrawnWhereTheCameraSeesTheCentroid) {
  Canvas canvas(320, 240, kGrey);
  io::ObjectsMessage objects;
  TableObject mug;
  mug.id = 2;
  mug.centroid = groundPointAt(80.0, 60.0, 0.85f);
  mug.mean_rgb = Eigen::Vector3f(250.0f, 200.0f, 10.0f);
  TableObject behind = mug;
  behind.id = 3;
  behind.centroid = Eigen::Vector3f(-2.0f, 0.0f, 0.8f);  // the camera looks along +x
  objects.objects = {mug, behind};
  EXPECT_EQ(drawObjectsInImage(canvas, objects, kK, kMount), 1);
  EXPECT_EQ(at(canvas, 80, 60), (Rgb8{250, 200, 10}));
  EXPECT_EQ(at(canvas, 80 + 7, 60), (Rgb8{255, 255, 255}));  // the ring
  EXPECT_EQ(at(canvas, 80 - 30, 60), kGrey);                 // nothing beyond the marker
  int marked = 0;  // only the one marker in the mug's colour
  for (const Rgb8& p : canvas.image().pixels) marked += p == Rgb8{250, 200, 10};
  EXPECT_GT(marked, 50);
  EXPECT_LT(marked, 150);
}

TEST(Pictures, LegendPanelKeepsTheImageAndListsEveryClass) {
  Image<Rgb8> image{40, 30, std::vector<Rgb8>(1200, kGrey)};
  const Image<Rgb8> out = withLegend(image);
  EXPECT_EQ(out.width, 40 + 150);
  EXPECT_GE(out.height, 30);
  EXPECT_EQ(out.pixels[0], kGrey);
  for (int id = 0; id < kNumLabels; ++id) {
    EXPECT_EQ(out.pixels[static_cast<std::size_t>(34 + 22 * id + 7) * out.width + 40 + 18],
              kLabelColors[id])
        << id;
  }
}

}  // namespace
}  // namespace findmug::clients
