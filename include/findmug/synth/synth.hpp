// findmug/synth/synth.hpp — synthetic apartment scenes rendered as Kinect-like RGB-D
// with exact ground truth (library `findmug_synth`).
//
// What it is for: the README's default demo (no downloads), deterministic tests
// of table clusters and search positions, replay latency tests and training
// augmentation. Everything is a pure function of the seed: the same seed and
// parameters give the same scene, path and bytes (our own counter-based RNG, no
// std::*_distribution, whose output differs between standard libraries).
//
// WORLD FRAME. A room is the axis-aligned box [0, X] x [0, Y] x [0, H] metres:
// z up, floor at z = 0, ceiling at z = H. Furniture yaw is about world z.
//
// CAMERA POSE. The robot base stands at (x, y) on the floor with heading `yaw`
// (about z, 0 = +x). The camera sits above the base at `height_m`, looking along
// the heading, tipped down by `pitch_rad` (> 0 = looking down) and rolled by
// `roll_rad` (> 0 = image axes turned clockwise looking along the optical axis)
// — exactly the CameraExtrinsics convention of frame.hpp / groundFromExtrinsics:
//   camera_to_world = T(x, y, height) * Rz(yaw) * Ry(pitch) * R0 * Rz_optical(roll)
// with R0 taking the optical frame (x right, y down, z forward) to a level
// frame (x forward, y left, z up).
//
// GROUND-ALIGNED FRAME (ground.hpp) of a frame = the robot base frame: origin on
// the floor below the camera, z up, x along the heading. Hence
//   world_to_ground = (T(x, y, 0) * Rz(yaw))^-1
// and groundFromExtrinsics(pose.extrinsics()).camera_to_ground equals
// worldToGround(pose) * cameraToWorld(pose). `tableInGroundFrame` converts the
// world-frame table truth into a given frame's ground-aligned frame, which is
// where findTables() reports clusters and search positions.
//
// DEPTH NOISE MODEL (Kinect v1, structured light), applied per pixel to the
// exact depth z (metres along the optical axis):
//  1. Range: z < min_range_m or z > max_range_m -> 0 (no measurement).
//  2. Grazing incidence: angle between the ray and the surface normal above
//     grazing_start_deg -> dropped with a probability rising linearly to 1 at
//     grazing_full_deg.
//  3. Projector shadow: the IR projector sits projector_baseline_m to the
//     camera's +x (Kinect v1: 7.5 cm); points it cannot see get no depth. With
//     rectified geometry a point is lit iff its projector column
//     u - fx*b/z is left of the projector columns of every pixel to its right
//     on the same row, so shadows appear on the left of foreground objects.
//  4. Disparity noise and quantisation (Khoshelham & Elberink 2012, "Accuracy
//     and resolution of Kinect depth data for indoor mapping applications",
//     Sensors 12(2)): the sensor measures an integer disparity d with
//     1/z = k*d (+ const), k = 2.85e-3 1/m per disparity unit (their m/(f b)).
//     We add Gaussian noise of sigma_d = 0.5 units to the exact disparity
//     1/(k z), round to an integer and convert back, then round to mm. To first
//     order that is their random-error model sigma_z = 0.5*k*z^2
//     = 1.425e-3 * z^2 m (4 mm at 1.7 m, 2.3 cm at 4 m) and their depth
//     resolution (quantisation step) k*z^2 = 2.85e-3 * z^2 m (7 cm at 5 m).
//  Pixel noise is independent (the real sensor's is spatially correlated over
//  its correlation window); the colour camera gets Gaussian noise of
//  rgb_noise_sigma grey levels per channel.
//
// LABELS. Every pixel gets the true class of the surface it sees (no void):
// doors and windows are Wall, shelves are Cabinet, mugs/boxes/books Object.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "findmug/frame/dataset.hpp"
#include "findmug/frame/frame.hpp"
#include "findmug/labels/labels.hpp"

namespace findmug::synth {

// ---------------------------------------------------------------- scene ----

enum class Shape { Box, Cylinder };  // cylinders are vertical (axis = world z)

enum class Texture {
  Plain,
  Wood,    // grain stripes along the primitive's local x
  Planks,  // floor boards along world x with per-board tone and seams
  Tiles,   // square tiles with grout lines
  Carpet,  // fine speckle
  Panel,   // cabinet fronts: a dark seam between two doors
};

struct Material {
  Rgb8 color;
  Texture texture = Texture::Plain;
  float texture_scale_m = 0.2f;  // board width, tile size, grain period
};

// One solid. Box: half extents along its local axes (local x/y yawed by `yaw`
// about z). Cylinder: half_extent = (radius, radius, half height).
struct Primitive {
  Shape shape = Shape::Box;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // world, metres
  double yaw = 0.0;                                  // rad about world z
  Eigen::Vector3d half_extent = Eigen::Vector3d::Constant(0.1);
  int object = 0;  // index into SynthScene::objects
  Material material;
};

// A semantic object: a table, a chair, a mug, the floor, one wall, ...
struct SceneObject {
  std::string kind;  // "floor", "wall", "door", "window", "table", "chair", "mug", ...
  Label label = Label::Unknown;
  int table = -1;  // index into SynthScene::tables for tables, else -1
};

enum class TableShape { Rectangular, Round };

// Ground truth of one table, world frame.
struct TableTruth {
  int id = 0;      // index in SynthScene::tables
  int object = 0;  // index in SynthScene::objects
  TableShape shape = TableShape::Rectangular;
  std::string kind;  // "dining", "desk", "coffee", "bar"
  Eigen::Vector2d center_xy = Eigen::Vector2d::Zero();
  double yaw = 0.0;                                // rad about z (long side along local x)
  Eigen::Vector2d size = Eigen::Vector2d::Zero();  // length, width (round: diameter twice)
  double height = 0.0;                             // top surface above the floor, metres
  // Outline of the top at z = height, counter-clockwise. Round tops are a
  // 64-gon inscribed in the circle (at most 0.12% of the radius inside it).
  std::vector<Eigen::Vector2d> top_polygon;
};

// 2-D footprint of furniture the robot cannot drive through.
struct Obstacle {
  std::vector<Eigen::Vector2d> polygon;  // convex, counter-clockwise, world xy
  double top_z = 0.0;
  int object = 0;
};

struct SynthScene {
  std::uint64_t seed = 0;
  Eigen::Vector3d room_size = Eigen::Vector3d(5, 4, 2.6);  // X, Y, ceiling height H
  Material floor_material, wall_material, ceiling_material;
  // Objects 0..5 are the room shell: floor, ceiling, walls x=0, x=X, y=0, y=Y.
  std::vector<SceneObject> objects;
  std::vector<Primitive> primitives;  // everything except the room shell
  std::vector<TableTruth> tables;
  std::vector<Obstacle> obstacles;
};

inline constexpr int kFloorObject = 0;
inline constexpr int kCeilingObject = 1;
inline constexpr int kFirstWallObject = 2;  // walls: x=0, x=X, y=0, y=Y

// Ranges are inclusive [min, max]; a fixed value is min == max.
struct ApartmentParams {
  double room_x_min = 4.5, room_x_max = 7.0;
  double room_y_min = 4.0, room_y_max = 6.0;
  double ceiling_min = 2.4, ceiling_max = 2.8;
  int tables_min = 1, tables_max = 3;
  double table_height_min = 0.45, table_height_max = 1.1;
  int cabinets_min = 1, cabinets_max = 3;
  int shelves_min = 0, shelves_max = 2;
  int doors_min = 1, doors_max = 2;
  int windows_min = 0, windows_max = 2;
  int objects_per_table_min = 1, objects_per_table_max = 5;
};

// Throws findmug::Error naming the field when a range is empty or absurd.
void validate(const ApartmentParams& params);

// A random but deterministic apartment room with at least one table the
// camera path can look at.
SynthScene makeApartment(std::uint64_t seed, const ApartmentParams& params = {});

// An empty room (shell only), for tests that build their own scene.
SynthScene makeEmptyRoom(const Eigen::Vector3d& room_size);

// Appends an object made of `parts` (their `object` field is overwritten) and
// returns its index.
int addObject(SynthScene& scene, const std::string& kind, Label label,
              std::vector<Primitive> parts);

// ---------------------------------------------------------------- edits ----
// A changed room for walks that test maps against change (e.g. a table carried elsewhere
// half-way through; tests/bench/semantic_map_walk --move-table).

// Moves table `table` (index into scene.tables) by `offset` (world x, y, metres) with
// what stands on its top (the Object-labelled parts above its top and inside its
// outline): their primitives, the table's truth (centre, top outline) and its obstacle
// footprint. Its chairs stay where they are. Throws findmug::Error when the index is out of
// range.
void moveTable(SynthScene& scene, int table, const Eigen::Vector2d& offset);

// Where table `table` could be carried to: the offset (on a 0.1 m grid) that puts its
// footprint inside the room at least `clearance_m` from the walls and from every other
// obstacle, farthest from where it stands and at least `min_move_m` away; nullopt when no
// such place exists. Throws findmug::Error when the index is out of range.
std::optional<Eigen::Vector2d> freeSpotForTable(const SynthScene& scene, int table,
                                                double clearance_m = 0.7,
                                                double min_move_m = 1.0);

// ------------------------------------------------------ multi-room apartments ----
// Apartments worth searching (src/synth/apartment.cpp; issue 51): 3-6 rooms of a kind
// (kitchen, living room, bedroom, study, hall) inside one shell box, separated by interior
// walls (Wall-labelled box primitives, also obstacles) with open doorways. Each room is
// furnished by makeApartment() in its own frame with settings by room kind, then moved into
// place; bedrooms get a bed and living rooms a sofa (label Unknown, as in the NYU mapping:
// not a search place, though a model may take their flat tops for tables). A target mug
// is added per episode by placeTargetMug(), on a table, a cabinet/shelf or the floor by a
// stated prior. Everything is a pure function of the seeds.

enum class RoomKind { Kitchen, Living, Bedroom, Study, Hall };
const char* roomKindName(RoomKind kind);

struct RoomTruth {
  RoomKind kind = RoomKind::Living;
  Eigen::Vector2d lo = Eigen::Vector2d::Zero(), hi = Eigen::Vector2d::Zero();  // free interior
  Eigen::Vector2d center() const { return 0.5 * (lo + hi); }
  bool contains(const Eigen::Vector2d& xy) const {
    return xy.x() >= lo.x() && xy.y() >= lo.y() && xy.x() <= hi.x() && xy.y() <= hi.y();
  }
};

// An open doorway in an interior wall: its centre on the wall's centre line.
struct DoorwayTruth {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  bool wall_along_y = true;  // the wall runs along y (a split in x), else along x
  double width = 1.0;
};

// A piece of furniture the robot must drive around, with what it is and where.
struct FurnitureTruth {
  int object = 0;    // index into SynthScene::objects
  std::string kind;  // "table", "chair", "cabinet", "shelf", "bed", "sofa"
  int room = -1;     // index into MultiRoomApartment::rooms
  int table = -1;    // index into SynthScene::tables for tables
  std::vector<Eigen::Vector2d> footprint;  // convex, CCW, world xy
  double top_z = 0.0;

  // The mean of the footprint's corners: the centre of the boxes and discs furniture is.
  Eigen::Vector2d centre() const;
  // Whether `xy` lies on the footprint, its edges included.
  bool covers(const Eigen::Vector2d& xy) const;
};

struct MultiRoomParams {
  int rooms_min = 3, rooms_max = 6;
  double room_area_min = 16.0, room_area_max = 24.0;  // m^2 per room, before splitting
  double min_room_side = 3.2;                         // metres, interior
  double wall_thickness = 0.1;
  double door_width = 1.0;
  double ceiling = 2.6;
};

struct MultiRoomApartment {
  SynthScene scene;  // room_size = the whole apartment's box
  std::vector<RoomTruth> rooms;
  std::vector<DoorwayTruth> doorways;
  std::vector<FurnitureTruth> furniture;
  // Index into rooms of the room holding `xy`, or -1 (in a wall or a doorway).
  int roomAt(const Eigen::Vector2d& xy) const;
};

// Throws findmug::Error naming the field when a parameter is out of range, or when no
// apartment whose rooms are all connected was found for the seed.
MultiRoomApartment makeMultiRoomApartment(std::uint64_t seed, const MultiRoomParams& params = {});

enum class MugPlace { Table, Cabinet, Floor };
const char* mugPlaceName(MugPlace place);

// Where the target mug stands: probabilities (normalised) of a table top, a cabinet top or
// shelf board (furniture kinds "cabinet" and "shelf", boards below 1.5 m), the floor.
struct MugPrior {
  double table = 0.7, cabinet = 0.2, floor = 0.1;
};

// Whether other mugs may look like the target. The furnishing draws small objects' colours
// from one palette, red among them, so about one small object in 25 is a red mug of the
// target's size: a twin that no recogniser taught from the target's looks can tell from it,
// and a robot asked for "my mug" in a home with two identical mugs has no wrong answer to
// give. Recolour (the default) turns every other mug whose body is as red as the target's
// blue (its colour channels rotated, so as bright as it was), so that a false "found"
// measures a recogniser's confusion, not the world's; boxes and books keep their colours (red
// ones stay, refused by shape). Keep leaves them (the worlds before this rule).
enum class LookAlikes { Recolour, Keep };

struct TargetMug {
  int object = -1;     // index into SynthScene::objects (kind "target_mug")
  MugPlace place = MugPlace::Table;
  int furniture = -1;  // index into MultiRoomApartment::furniture it stands on, -1: the floor
  int room = -1;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // centre of its base, world
  double height = 0.0;
  int look_alikes_recoloured = 0;  // other mugs as red as it, recoloured (LookAlikes)
};

// Adds a target mug to `apartment` (its scene, and an obstacle when on the floor) by the
// prior, clear of the objects already there, and recolours the other mugs that look like it
// unless told to keep them. Deterministic in `seed`. Throws findmug::Error when the prior is
// not a distribution or no place could be found.
TargetMug placeTargetMug(MultiRoomApartment& apartment, std::uint64_t seed,
                         const MugPrior& prior = {},
                         LookAlikes look_alikes = LookAlikes::Recolour);

// Whether a colour is the target mug's red (the palette's red, however the furnishing's
// jitter of +-15 % brightness and +-6 % per channel drew it; its orange is not).
bool looksLikeTargetMugRed(Rgb8 colour);

// ---------------------------------------------------------------- camera ----

struct CameraPose {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();  // robot base on the floor, world
  double yaw = 0.0;                              // heading about z
  double height_m = 1.2;                         // optical centre above the floor
  double pitch_rad = 0.5;                        // > 0 looking down
  double roll_rad = 0.0;
  double time_s = 0.0;  // since the start of the sequence
};

Eigen::Isometry3d cameraToWorld(const CameraPose& pose);
Eigen::Isometry3d worldToGround(const CameraPose& pose);
CameraExtrinsics extrinsicsOf(const CameraPose& pose);

// The table as seen in the frame's ground-aligned frame: centre, yaw and top
// polygon transformed (height and size unchanged).
TableTruth tableInGroundFrame(const TableTruth& table, const CameraPose& pose);

// Signed distance (metres) from a floor point to the outline of the table top
// polygon, in whatever frame the table is given: negative inside, positive
// outside. E.g. a search position should be at about safety_distance_m.
double signedDistanceToTop(const TableTruth& table, const Eigen::Vector2d& xy);

struct CameraPathParams {
  double height_min = 1.0, height_max = 1.4;          // camera height, per sequence
  double pitch_min_deg = 20.0, pitch_max_deg = 45.0;  // tilt down, per sequence
  double speed_mps = 0.4;                             // driving speed
  double max_yaw_rate = 0.8;                          // rad/s, head/base turning
  double dwell_s = 2.0;                               // pause at each viewpoint
  double pan_amplitude_rad = 0.15;                    // head pan while dwelling
  double robot_radius_m = 0.3;                        // clearance to furniture
  double max_view_distance_m = 2.6;                   // viewpoint to table centre
};

void validate(const CameraPathParams& params);

// Views of an apartment's furniture as a robot's head camera sees it, for a model to learn
// the search's domain from (findmug-synth --multi-room): view i looks at a piece of
// furniture (every piece in turn, in an order of the seed's: beds, sofas, chairs and
// shelves as often as tables) from a spot in its room 0.9 to max_view_distance_m + 0.8 m
// from its centre where the robot fits (robot_radius_m), heading at it within twice
// pan_amplitude_rad, camera height and pitch drawn per view from the params' ranges.
// time_s is the view's index. Deterministic in `seed`. Throws findmug::Error when the
// params are out of range or the apartment has no furniture any spot sees.
std::vector<CameraPose> apartmentViews(const MultiRoomApartment& apartment, int n_views,
                                       std::uint64_t seed, const CameraPathParams& params = {});

// A robot's camera driving between viewpoints around the tables (two per table
// where possible), always turning to look at the table it visits next. The
// camera height and pitch are drawn once per sequence from the ranges. Throws
// when the scene has no table the robot can reach.
std::vector<CameraPose> cameraPath(const SynthScene& scene, int n_frames, double fps,
                                   const CameraPathParams& params = {});

// ---------------------------------------------------------------- render ----

struct DepthNoiseParams {
  bool enabled = true;  // false: exact depth (still rounded to mm), no dropouts
  double min_range_m = 0.5;
  double max_range_m = 4.5;
  double disparity_k = 2.85e-3;     // 1/m per disparity unit (K&E 2012)
  double disparity_sigma = 0.5;     // disparity units (K&E 2012)
  bool quantise = true;             // integer disparities
  double grazing_start_deg = 78.0;  // dropout begins
  double grazing_full_deg = 88.0;   // everything dropped beyond
  bool projector_shadows = true;
  double projector_baseline_m = 0.075;
  double rgb_noise_sigma = 2.0;  // grey levels
};

struct RenderOptions {
  int width = 640;
  int height = 480;
  CameraIntrinsics intrinsics;  // Kinect: fx = fy = 525, cx = 319.5, cy = 239.5
  DepthNoiseParams noise;
};

void validate(const RenderOptions& options);

struct RenderedFrame {
  LabeledFrame labeled;              // noisy depth, colour, labels, intrinsics, extrinsics
  std::vector<float> true_depth_m;   // exact z along the optical axis, per pixel
  std::vector<std::int32_t> object;  // index into SynthScene::objects, per pixel
};

// Ray casts one frame. `noise_seed` selects the noise realisation (the same
// seed gives the same bytes). Frame name/seq/utime are left for the caller.
RenderedFrame render(const SynthScene& scene, const CameraPose& pose, const RenderOptions& options,
                     std::uint64_t noise_seed);

// How many pixels of scene object `object` (an index into SynthScene::objects) the frame
// render() would make from `pose` shows: the same ray casts in the same order on the pixels
// where that object's primitives can appear, without shading or noise, so it equals the
// count of `object` in render(...).object for every noise seed, at a fraction of the cost
// (an oracle recogniser asks only this). Throws like render(), and when `object` is not in
// the scene.
int countObjectPixels(const SynthScene& scene, const CameraPose& pose, const RenderOptions& options,
                      int object);

// One depth sample of the noise model above for an exact depth z (metres) on
// a surface seen head-on, without dropouts: the millimetre value written to
// the depth image (0 when out of range). `gaussian` is a standard normal
// sample (the renderer draws it from a per-pixel hash).
std::uint16_t noisyDepthMm(double z_m, const DepthNoiseParams& noise, double gaussian);

// noisyDepthMm for one set of noise parameters, with the depth of every integer disparity
// level a sample can round to worked out once: the renderer's per-pixel depth (the second
// division and rounding of each sample were a tenth of a frame's render). Returns exactly
// noisyDepthMm(z_m, noise, gaussian) for every input.
class NoisyDepthSampler {
 public:
  explicit NoisyDepthSampler(const DepthNoiseParams& noise);
  std::uint16_t operator()(double z_m, double gaussian) const;

 private:
  DepthNoiseParams noise_;
  // Quantised noise: level_mm_[d] is the sample of disparity level d (1 <= d < size);
  // levels beyond, which only far tails of the noise reach, take the formula.
  std::vector<std::uint16_t> level_mm_;
};

// --------------------------------------------------------- ground truth ----

struct SequenceGroundTruth {
  std::uint64_t seed = 0;
  double fps = 30.0;
  int width = 640, height = 480;
  CameraIntrinsics intrinsics;
  Eigen::Vector3d room_size = Eigen::Vector3d::Zero();
  std::vector<std::string> frame_names;
  std::vector<std::uint64_t> frame_utimes;
  std::vector<CameraPose> poses;
  std::vector<TableTruth> tables;
  // Furniture footprints the robot cannot drive through (tables included),
  // world frame. Absent from files written before they were recorded.
  std::vector<Obstacle> obstacles;
};

// Whether a round robot of `robot_radius` standing at world `xy` is clear of
// the walls and of every obstacle footprint (the same test the camera path
// planner uses): a search position is "reachable in the ground truth".
bool robotFits(const Eigen::Vector3d& room_size, const std::vector<Obstacle>& obstacles,
               const Eigen::Vector2d& xy, double robot_radius);

// YAML (DIR/ground_truth.yaml). Reading throws findmug::Error naming the file
// and the missing or malformed field.
void writeGroundTruth(const std::string& path, const SequenceGroundTruth& truth);
SequenceGroundTruth readGroundTruth(const std::string& path);

struct SequenceSpec {
  std::uint64_t seed = 1;
  int frames = 30;
  double fps = 30.0;
  // false: one room (makeApartment, `apartment`) along cameraPath; true: a multi-room
  // apartment (makeMultiRoomApartment, `multi_room`) in apartmentViews, one view a frame.
  bool multi_room = false;
  MultiRoomParams multi_room_params;
  ApartmentParams apartment;
  CameraPathParams path;
  RenderOptions render;
};

// Frame i is named "%06d" (a multi-room apartment's "apartmentSEED-%06d", writeSequence);
// utime = round(i * 1e6 / fps) microseconds.
std::string frameName(int index);

// What `findmug-synth` does: renders the sequence into the dataset folder
// layout of dataset.hpp (rgb/, depth/, label8/ via writeLabeledFrame, plus
// intrinsics.yaml and extrinsics.csv) and DIR/ground_truth.yaml. Returns the
// ground truth it wrote. `progress(done, total)` may be empty.
SequenceGroundTruth writeSequence(const std::string& dir, const SequenceSpec& spec,
                                  const std::function<void(int, int)>& progress = {});

}  // namespace findmug::synth
