// findmug/tables.hpp — table clusters and search positions (object search).
//
// Everything here is in the ground-aligned frame of ground.hpp (z up, floor
// at z = 0, x forward from below the camera): the robot base frame when the
// camera mount is known.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "findmug/cloud.hpp"
#include "findmug/label_image.hpp"

namespace findmug {

struct SearchPosition {
  Eigen::Vector2f xy = Eigen::Vector2f::Zero();  // on the floor, metres
  float yaw = 0.0f;                               // rad, facing the table
  bool reachable = true;
  std::string reason;  // why unreachable ("obstacle within robot radius", "no observed floor")
};

struct TableCluster {
  int id = 0;
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  float top_height = 0.0f;
  Eigen::Vector2f major_axis = Eigen::Vector2f::UnitX();  // first principal axis (unit, floor plane)
  Eigen::Vector2f minor_axis = Eigen::Vector2f::UnitY();  // second principal axis
  Eigen::Vector2f extents = Eigen::Vector2f::Zero();      // half-lengths along major/minor
  std::vector<Eigen::Vector2f> hull;                      // convex hull of the top, CCW
  int point_count = 0;
  float mean_confidence = 0.0f;
  std::vector<SearchPosition> search_positions;
};

struct TableConfig {
  float cluster_tolerance_m = 0.05f;
  int min_cluster_points = 500;
  int max_cluster_points = 200000;
  float safety_distance_m = 0.5f;  // d: from the table edge to the search position
  float arm_reach_m = 0.8f;
  float robot_radius_m = 0.3f;
  float min_table_height_m = 0.3f;
  float max_table_height_m = 1.3f;
};

std::vector<TableCluster> findTables(const OrganizedCloud& cloud_ground, const LabelImage& labels,
                                     const TableConfig& config);

}  // namespace findmug
