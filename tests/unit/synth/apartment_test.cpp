// Multi-room apartments (synth.hpp, src/synth/apartment.cpp): rooms of a kind joined by
// doorways, furniture inside its room, the target mug where its prior puts it, and all of
// it a pure function of the seeds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "findmug/common/error.hpp"
#include "findmug/synth/synth.hpp"

namespace findmug::synth {
namespace {

bool insidePolygon(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& p) {
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Eigen::Vector2d e = poly[(i + 1) % poly.size()] - poly[i];
    const Eigen::Vector2d q = p - poly[i];
    if (e.x() * q.y() - e.y() * q.x() < -1e-9) return false;
  }
  return true;
}

TEST(MultiRoomApartment, SameSeedSameApartmentOtherSeedOther) {
  const MultiRoomApartment a = makeMultiRoomApartment(5);
  const MultiRoomApartment b = makeMultiRoomApartment(5);
  const MultiRoomApartment c = makeMultiRoomApartment(6);
  ASSERT_EQ(a.scene.primitives.size(), b.scene.primitives.size());
  for (std::size_t i = 0; i < a.scene.primitives.size(); ++i)
    EXPECT_EQ(a.scene.primitives[i].center, b.scene.primitives[i].center);
  EXPECT_EQ(a.rooms.size(), b.rooms.size());
  EXPECT_TRUE(a.scene.room_size != c.scene.room_size ||
              a.scene.primitives.size() != c.scene.primitives.size());
}

TEST(MultiRoomApartment, RoomsDoorwaysAndFurnitureHangTogether) {
  std::set<std::string> kinds_seen;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const MultiRoomApartment apt = makeMultiRoomApartment(seed);
    const int n = static_cast<int>(apt.rooms.size());
    ASSERT_GE(n, 3);
    ASSERT_LE(n, 6);
    // Guillotine splits: one interior wall, and one doorway in it, per split.
    EXPECT_EQ(static_cast<int>(apt.doorways.size()), n - 1);
    for (const RoomTruth& r : apt.rooms) {
      EXPECT_GE(r.hi.x() - r.lo.x(), MultiRoomParams{}.min_room_side - 1e-9);
      EXPECT_GE(r.hi.y() - r.lo.y(), MultiRoomParams{}.min_room_side - 1e-9);
    }
    for (const FurnitureTruth& f : apt.furniture) {
      kinds_seen.insert(f.kind);
      ASSERT_GE(f.room, 0);
      const RoomTruth& r = apt.rooms[f.room];
      for (const auto& v : f.footprint) {
        EXPECT_GE(v.x(), r.lo.x() - 0.03) << f.kind << " seed " << seed;
        EXPECT_LE(v.x(), r.hi.x() + 0.03) << f.kind << " seed " << seed;
        EXPECT_GE(v.y(), r.lo.y() - 0.03) << f.kind << " seed " << seed;
        EXPECT_LE(v.y(), r.hi.y() + 0.03) << f.kind << " seed " << seed;
      }
      if (f.kind == "bed" || f.kind == "sofa") {
        EXPECT_EQ(apt.scene.objects[f.object].label, Label::Unknown);
      }
      if (f.kind == "table") {
        ASSERT_GE(f.table, 0);
        EXPECT_EQ(apt.scene.tables[f.table].object, f.object);
      }
    }
    // A doorway is open: no obstacle covers its centre, and it is inside the apartment.
    for (const DoorwayTruth& d : apt.doorways) {
      EXPECT_EQ(apt.roomAt(d.center), -1);
      EXPECT_TRUE(robotFits(apt.scene.room_size, apt.scene.obstacles, d.center, 0.3));
    }
  }
  for (const char* kind : {"table", "chair", "cabinet", "bed", "sofa"})
    EXPECT_TRUE(kinds_seen.count(kind)) << kind;
}

TEST(MultiRoomApartment, InteriorWallsAreRenderedAsWalls) {
  const MultiRoomApartment apt = makeMultiRoomApartment(3);
  // From the middle of the first room, looking at the middle of the apartment.
  const RoomTruth& room = apt.rooms.front();
  CameraPose pose;
  pose.xy = room.center();
  const Eigen::Vector2d to = 0.5 * apt.scene.room_size.head<2>() - pose.xy;
  int interior_wall_pixels = 0;
  for (int k = 0; k < 8; ++k) {
    pose.yaw = std::atan2(to.y(), to.x()) + k * M_PI / 4;
    pose.pitch_rad = 0.2;
    const RenderedFrame frame = render(apt.scene, pose, RenderOptions{}, 1);
    for (std::size_t i = 0; i < frame.object.size(); ++i) {
      const int o = frame.object[i];
      if (o >= 6 && apt.scene.objects[o].kind == "wall") {
        ++interior_wall_pixels;
        EXPECT_EQ(frame.labeled.labels[i], static_cast<std::uint8_t>(Label::Wall));
      }
    }
  }
  EXPECT_GT(interior_wall_pixels, 10000);
}

TEST(MultiRoomApartment, TargetMugFollowsItsPrior) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    MultiRoomApartment on_table = makeMultiRoomApartment(2);
    const TargetMug t = placeTargetMug(on_table, seed, {1.0, 0.0, 0.0});
    ASSERT_EQ(t.place, MugPlace::Table);
    const FurnitureTruth& f = on_table.furniture[t.furniture];
    ASSERT_GE(f.table, 0);
    const TableTruth& table = on_table.scene.tables[f.table];
    EXPECT_NEAR(t.position.z(), table.height, 1e-9);
    EXPECT_TRUE(insidePolygon(table.top_polygon, t.position.head<2>()));
    EXPECT_EQ(on_table.scene.objects[t.object].kind, "target_mug");
    EXPECT_EQ(t.room, f.room);

    MultiRoomApartment on_floor = makeMultiRoomApartment(2);
    const std::size_t obstacles = on_floor.scene.obstacles.size();
    const TargetMug m = placeTargetMug(on_floor, seed, {0.0, 0.0, 1.0});
    EXPECT_EQ(m.place, MugPlace::Floor);
    EXPECT_EQ(m.position.z(), 0.0);
    EXPECT_EQ(on_floor.scene.obstacles.size(), obstacles + 1);  // the robot drives around it
    EXPECT_EQ(on_floor.roomAt(m.position.head<2>()), m.room);

    MultiRoomApartment on_cabinet = makeMultiRoomApartment(2);
    const TargetMug c = placeTargetMug(on_cabinet, seed, {0.0, 1.0, 0.0});
    if (c.place == MugPlace::Cabinet) {
      const std::string& kind = on_cabinet.furniture[c.furniture].kind;
      EXPECT_TRUE(kind == "cabinet" || kind == "shelf") << kind;
      EXPECT_GT(c.position.z(), 0.2);
    }
  }
  MultiRoomApartment apt = makeMultiRoomApartment(2);
  const TargetMug a = placeTargetMug(apt, 9);
  MultiRoomApartment again = makeMultiRoomApartment(2);
  EXPECT_EQ(placeTargetMug(again, 9).position, a.position);
  EXPECT_THROW(placeTargetMug(apt, 1, {-1.0, 1.0, 1.0}), Error);
  EXPECT_THROW(placeTargetMug(apt, 1, {0.0, 0.0, 0.0}), Error);
}

// The target is the apartment's only red mug unless told otherwise: the furnishing's red
// mugs (twins no recogniser can tell from it) turn blue; red boxes and books stay.
TEST(MultiRoomApartment, TargetMugHasNoTwinUnlessTwinsAreKept) {
  // The palette's red and orange at the jitter's extremes (+-15 % brightness, +-6 % a channel).
  EXPECT_TRUE(looksLikeTargetMugRed({205, 35, 35}));
  EXPECT_TRUE(looksLikeTargetMugRed({160, 40, 40}));   // dark red, greenest
  EXPECT_TRUE(looksLikeTargetMugRed({244, 46, 46}));
  EXPECT_FALSE(looksLikeTargetMugRed({186, 99, 27}));  // orange, reddest
  EXPECT_FALSE(looksLikeTargetMugRed({252, 110, 30}));
  EXPECT_FALSE(looksLikeTargetMugRed({40, 90, 200}));
  auto redMugs = [](const SynthScene& scene, const std::string& kind) {
    int n = 0;
    std::vector<bool> counted(scene.objects.size(), false);
    for (const Primitive& p : scene.primitives)
      if (scene.objects[p.object].kind == kind && looksLikeTargetMugRed(p.material.color) &&
          !counted[p.object])
        counted[p.object] = true, ++n;
    return n;
  };
  int kept_twins = 0, red_boxes = 0;
  for (std::uint64_t seed = 1000003; seed < 1000013; ++seed) {
    MultiRoomApartment kept = makeMultiRoomApartment(seed);
    const TargetMug k = placeTargetMug(kept, seed * 7919, {}, LookAlikes::Keep);
    MultiRoomApartment unique = makeMultiRoomApartment(seed);
    const TargetMug u = placeTargetMug(unique, seed * 7919);
    EXPECT_EQ(k.position, u.position);
    EXPECT_EQ(k.look_alikes_recoloured, 0);
    EXPECT_EQ(u.look_alikes_recoloured, redMugs(kept.scene, "mug"));
    EXPECT_EQ(redMugs(unique.scene, "mug"), 0) << "seed " << seed;
    EXPECT_EQ(redMugs(unique.scene, "target_mug"), 1);
    EXPECT_EQ(redMugs(unique.scene, "box"), redMugs(kept.scene, "box"));
    kept_twins += redMugs(kept.scene, "mug");
    red_boxes += redMugs(kept.scene, "box");
  }
  EXPECT_GT(kept_twins, 5);  // the rule has twins to remove in these apartments
  EXPECT_GT(red_boxes, 0);
}

// The oracle recogniser of the search benchmark counts the mug's pixels with
// countObjectPixels instead of rendering a frame: the count must be the full render's, to
// the pixel, whether the mug is in full view, cut by the image border, hidden behind
// furniture or walls, or out of view; so must the count of any other object.
TEST(MultiRoomApartment, ObjectPixelCountEqualsTheRenderedFrames) {
  int views = 0, mug_seen = 0, mug_partly = 0, mug_hidden_in_box = 0;
  for (std::uint64_t seed : {2ULL, 5ULL, 11ULL}) {
    MultiRoomApartment apt = makeMultiRoomApartment(seed);
    const TargetMug mug = placeTargetMug(apt, seed * 7 + 1);
    const Eigen::Vector3d box = apt.scene.room_size;
    int full = 0;
    for (int k = 0; k < 24; ++k) {
      // Around the mug at 0.7-4 m, facing it or turned away by up to about a field of view.
      const double bearing = 0.9 * k, range = 0.7 + 0.15 * k;
      CameraPose pose;
      pose.xy = mug.position.head<2>() + range * Eigen::Vector2d(std::cos(bearing),
                                                                 std::sin(bearing));
      pose.xy.x() = std::clamp(pose.xy.x(), 0.2, box.x() - 0.2);
      pose.xy.y() = std::clamp(pose.xy.y(), 0.2, box.y() - 0.2);
      const Eigen::Vector2d to = mug.position.head<2>() - pose.xy;
      pose.yaw = std::atan2(to.y(), to.x()) + (k % 4 == 3 ? 0.55 : 0.12 * (k % 3 - 1));
      pose.pitch_rad = k % 2 ? 0.5 : 0.3;
      RenderOptions options;
      if (k % 3 == 0) options.noise.enabled = false;  // the object index ignores the noise
      const RenderedFrame frame = render(apt.scene, pose, options, seed * 100 + k);
      auto rendered = [&frame](int object) {
        return static_cast<int>(std::count(frame.object.begin(), frame.object.end(), object));
      };
      const int n = rendered(mug.object);
      ASSERT_EQ(countObjectPixels(apt.scene, pose, options, mug.object), n)
          << "seed " << seed << " view " << k;
      ++views;
      full = std::max(full, n);
      mug_seen += n > 0;
      // In the middle of the image, yet not a pixel: something stands in front of it.
      const Eigen::Vector3d c = cameraToWorld(pose).inverse() *
                                (mug.position + Eigen::Vector3d(0, 0, 0.05));
      const double u = 525.0 * c.x() / c.z() + 319.5, v = 525.0 * c.y() / c.z() + 239.5;
      if (c.z() > 0.3 && u > 40 && u < 600 && v > 40 && v < 440 && n == 0) ++mug_hidden_in_box;
      if (n > 0 && (u < 10 || u > 630 || v < 10 || v > 470)) ++mug_partly;
      // Other objects: the floor (a shell surface, everywhere) and the furniture under the mug.
      EXPECT_EQ(countObjectPixels(apt.scene, pose, options, 0), rendered(0));
      for (const Primitive& p : apt.scene.primitives)
        if (p.object != mug.object && (p.center - mug.position).norm() < 1.0) {
          EXPECT_EQ(countObjectPixels(apt.scene, pose, options, p.object), rendered(p.object))
              << "object " << p.object << " seed " << seed << " view " << k;
          break;
        }
    }
    EXPECT_GT(full, 150) << "seed " << seed << ": the mug was never in full view";
  }
  EXPECT_EQ(views, 72);
  EXPECT_GT(mug_seen, 10);
  EXPECT_LT(mug_seen, views);
  EXPECT_GT(mug_hidden_in_box + mug_partly, 0);
  MultiRoomApartment apt = makeMultiRoomApartment(2);
  CameraPose pose;
  pose.xy = {1.0, 1.0};
  EXPECT_THROW(countObjectPixels(apt.scene, pose, RenderOptions{},
                                 static_cast<int>(apt.scene.objects.size())),
               Error);
  pose.xy = {-1.0, 1.0};
  EXPECT_THROW(countObjectPixels(apt.scene, pose, RenderOptions{}, 0), Error);
}

// The training views of findmug-synth --multi-room: the robot fits where it stands, in the
// room of what it looks at, and every piece of furniture (beds and sofas as much as tables)
// fills part of some view; the same seed gives the same views.
TEST(MultiRoomApartment, TrainingViewsShowEveryPieceOfFurnitureFromWhereTheRobotFits) {
  for (std::uint64_t seed : {2ULL, 5ULL}) {
    const MultiRoomApartment apt = makeMultiRoomApartment(seed);
    const int n = 2 * static_cast<int>(apt.furniture.size());
    const std::vector<CameraPose> views = apartmentViews(apt, n, seed);
    ASSERT_EQ(static_cast<int>(views.size()), n);
    const std::vector<CameraPose> again = apartmentViews(apt, n, seed);
    std::vector<int> best_pixels(apt.furniture.size(), 0);
    int views_with_furniture = 0;
    for (std::size_t v = 0; v < views.size(); ++v) {
      const CameraPose& pose = views[v];
      EXPECT_EQ(pose.xy, again[v].xy);
      EXPECT_EQ(pose.yaw, again[v].yaw);
      EXPECT_TRUE(robotFits(apt.scene.room_size, apt.scene.obstacles, pose.xy, 0.3))
          << "seed " << seed << " view " << v;
      EXPECT_GE(apt.roomAt(pose.xy), 0) << "seed " << seed << " view " << v;
      EXPECT_GE(pose.pitch_rad, 20.0 * M_PI / 180.0 - 1e-9);
      EXPECT_LE(pose.pitch_rad, 45.0 * M_PI / 180.0 + 1e-9);
      RenderOptions options;
      options.noise.enabled = false;
      const RenderedFrame frame = render(apt.scene, pose, options, seed);
      bool any = false;
      for (std::size_t f = 0; f < apt.furniture.size(); ++f) {
        const int px = static_cast<int>(
            std::count(frame.object.begin(), frame.object.end(), apt.furniture[f].object));
        best_pixels[f] = std::max(best_pixels[f], px);
        any = any || px > 2000;
      }
      views_with_furniture += any;
    }
    EXPECT_GE(views_with_furniture, n * 9 / 10) << "seed " << seed;
    for (std::size_t f = 0; f < apt.furniture.size(); ++f)
      EXPECT_GT(best_pixels[f], 1000) << "seed " << seed << ": " << apt.furniture[f].kind << " "
                                      << f << " never in view";
  }
  EXPECT_THROW(apartmentViews(makeMultiRoomApartment(2), -1, 1), Error);
}

TEST(MultiRoomApartment, FurnitureKnowsItsCentreAndWhatItsFootprintCovers) {
  FurnitureTruth piece;
  piece.footprint = {{1.0, 2.0}, {3.0, 2.0}, {3.0, 3.0}, {1.0, 3.0}};  // CCW
  EXPECT_TRUE(piece.centre().isApprox(Eigen::Vector2d(2.0, 2.5)));
  EXPECT_TRUE(piece.covers({2.0, 2.5}));
  EXPECT_TRUE(piece.covers({3.0, 2.2}));  // on an edge
  EXPECT_FALSE(piece.covers({3.01, 2.5}));
  EXPECT_FALSE(piece.covers({2.0, 1.99}));
  // Every table of an apartment covers its own centre, and no other table's.
  const MultiRoomApartment apt = makeMultiRoomApartment(4);
  int tables = 0;
  for (const FurnitureTruth& a : apt.furniture) {
    if (a.kind != "table") continue;
    ++tables;
    EXPECT_TRUE(a.covers(a.centre()));
    for (const FurnitureTruth& b : apt.furniture) {
      if (&a != &b && b.kind == "table") {
        EXPECT_FALSE(b.covers(a.centre()));
      }
    }
  }
  EXPECT_GE(tables, 1);
  piece.footprint.resize(2);
  EXPECT_FALSE(piece.covers({2.0, 2.0}));  // two corners cover nothing
}

TEST(MultiRoomApartment, BadParametersAreRejected) {
  MultiRoomParams p;
  p.rooms_min = 5;
  p.rooms_max = 4;
  EXPECT_THROW(makeMultiRoomApartment(1, p), Error);
  p = {};
  p.door_width = 0.3;
  EXPECT_THROW(makeMultiRoomApartment(1, p), Error);
}

}  // namespace
}  // namespace findmug::synth
