// findmug/labels/labels.hpp — the eight semantic classes of the paper and their ids.
//
// Ids are the ones of the `label8` PNGs (0 unknown, 1 floor, ... 7 object)
// and 255 for void (no ground truth / no valid depth). They are part of the
// model file and of the LCM label images, so never renumber them.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

namespace findmug {

enum class Label : std::uint8_t {
  Unknown = 0,
  Floor = 1,
  Wall = 2,
  Ceiling = 3,
  Table = 4,
  Chair = 5,
  Cabinet = 6,
  Object = 7,
};

inline constexpr int kNumLabels = 8;
inline constexpr std::uint8_t kVoidLabel = 255;

inline constexpr std::array<std::string_view, kNumLabels> kLabelNames = {
    "unknown", "floor", "wall", "ceiling", "table", "chair", "cabinet", "object"};

struct Rgb8 {
  std::uint8_t r = 0, g = 0, b = 0;
  friend bool operator==(const Rgb8&, const Rgb8&) = default;
};

// The paper's overlay palette: floor red, wall blue, ceiling orange, table
// green, chair pink, cabinet yellow, object purple, unknown brown.
inline constexpr std::array<Rgb8, kNumLabels> kLabelColors = {{
    {139, 90, 43},    // unknown: brown
    {220, 30, 30},    // floor: red
    {40, 70, 220},    // wall: blue
    {255, 150, 0},    // ceiling: orange
    {30, 180, 60},    // table: green
    {255, 120, 200},  // chair: pink
    {240, 220, 20},   // cabinet: yellow
    {140, 50, 190},   // object: purple
}};
inline constexpr Rgb8 kVoidColor = {0, 0, 0};

inline std::string_view labelName(std::uint8_t id) {
  return id < kNumLabels ? kLabelNames[id] : std::string_view("void");
}

// Per-class probability distribution p(y|x) over the eight labels.
using ClassProbabilities = std::array<float, kNumLabels>;

}  // namespace findmug
