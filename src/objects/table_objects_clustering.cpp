// table_objects_clustering.cpp — the table-top points clustered on a sample of the image
// grid (table_objects.point_stride > 1), or exactly (stride 1); see
// table_objects_internal.hpp.
#include <algorithm>

#include "common/union_find.hpp"
#include "objects/table_objects_internal.hpp"
#include "tables/tables_internal.hpp"

namespace findmug::objects_detail {

namespace {

// Image reach of the organized clustering, in sampled steps: a sampled point
// links to the sampled points up to this many steps away on each image axis
// (within cluster_tolerance_m in 3-D), so that a gap of a few pixels (a depth
// hole, a thin occluder) does not split an object.
constexpr int kOrganizedReachSteps = 2;

}  // namespace

int clusterSampled(const std::vector<Eigen::Vector3f>& points, const std::vector<int>& pixels,
                   float tolerance, int width, int height, int stride, SampledClusteringScratch& s,
                   std::vector<int>& cluster_of) {
  if (stride <= 1) {
    tables_detail::clusterPointsInto(points, tolerance, tables_detail::PointGrid{&pixels, width, 1},
                                     cluster_of);
    return *std::max_element(cluster_of.begin(), cluster_of.end()) + 1;
  }
  s.sample_points.clear();
  s.sample_pixels.clear();
  // Per point, its sampled point's index, or -1 when it is not sampled. The
  // pixels ascend, so the row is followed without a division per point.
  std::vector<int>& sample_index = s.sample_index;
  sample_index.assign(points.size(), -1);
  int row = 0, row_start = 0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    const int p = pixels[k];
    if (p >= row_start + width) {
      row = p / width;
      row_start = row * width;
    }
    if (row % stride != 0 || (p - row_start) % stride != 0) continue;
    sample_index[k] = static_cast<int>(s.sample_points.size());
    s.sample_points.push_back(points[k]);
    s.sample_pixels.push_back(p);
  }
  cluster_of.assign(points.size(), 0);
  const int samples = static_cast<int>(s.sample_points.size());
  if (samples == 0) return 0;  // every point joins no cluster (id 0 = the count)
  const std::size_t image = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (s.sample_at_pixel.size() < image) s.sample_at_pixel.resize(image, -1);
  for (int j = 0; j < samples; ++j) {
    s.sample_at_pixel[static_cast<std::size_t>(s.sample_pixels[static_cast<std::size_t>(j)])] = j;
  }
  const float tol2 = tolerance * tolerance;
  std::vector<int>& parent = s.sample_of;
  parent.resize(static_cast<std::size_t>(samples));
  for (int j = 0; j < samples; ++j) parent[static_cast<std::size_t>(j)] = j;
  constexpr int R = kOrganizedReachSteps;
  for (int j = 0; j < samples; ++j) {
    const int p = s.sample_pixels[static_cast<std::size_t>(j)];
    const int x = p % width, y = p / width;
    const Eigen::Vector3f& a = s.sample_points[static_cast<std::size_t>(j)];
    // The later half of the window: the rest of this row, then the rows below.
    for (int dy = 0; dy <= R; ++dy) {
      const int yy = y + dy * stride;
      if (yy >= height) break;
      for (int dx = dy == 0 ? 1 : -R; dx <= R; ++dx) {
        const int xx = x + dx * stride;
        if (xx < 0 || xx >= width) continue;
        const int q = s.sample_at_pixel[static_cast<std::size_t>(yy) * width + xx];
        if (q < 0 || (a - s.sample_points[static_cast<std::size_t>(q)]).squaredNorm() > tol2) {
          continue;
        }
        detail::unionFindJoin(parent, j, q);
      }
    }
  }
  // Roots are the lowest index of their set (union_find.hpp), so numbering
  // the roots in index order numbers the clusters in pixel order.
  s.sample_cluster_of_root.assign(static_cast<std::size_t>(samples), -1);
  int clusters = 0;
  for (int j = 0; j < samples; ++j) {
    const int root = detail::unionFindRoot(parent, j);
    int& id = s.sample_cluster_of_root[static_cast<std::size_t>(root)];
    if (id < 0) id = clusters++;
    parent[static_cast<std::size_t>(j)] = root;
  }
  for (int j = 0; j < samples; ++j) {
    parent[static_cast<std::size_t>(j)] =
        s.sample_cluster_of_root[static_cast<std::size_t>(parent[static_cast<std::size_t>(j)])];
  }
  row = 0;
  row_start = 0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    if (sample_index[k] >= 0) {
      cluster_of[k] = parent[static_cast<std::size_t>(sample_index[k])];
      continue;
    }
    const int p = pixels[k];
    if (p >= row_start + width) {
      row = p / width;
      row_start = row * width;
    }
    const int x = p - row_start, y = row;
    const int x0 = x - x % stride, y0 = y - y % stride;
    int best = -1;
    float best_d2 = tol2;
    // The four sampled pixels around it (steps 0 and 1); when none is within
    // the tolerance (a silhouette's edge, quantised depth far away), the ring
    // of twelve around those (steps -1 and 2): on rendered rooms a small far
    // object otherwise lost a fifth of its pixels.
    for (const int ring : {0, 1}) {
      for (int dy = -ring; dy <= 1 + ring; ++dy) {
        const int yy = y0 + dy * stride;
        if (yy < 0 || yy >= height) continue;
        for (int dx = -ring; dx <= 1 + ring; ++dx) {
          if (ring == 1 && dy >= 0 && dy <= 1 && dx >= 0 && dx <= 1) continue;  // looked at
          const int xx = x0 + dx * stride;
          if (xx < 0 || xx >= width) continue;
          const int j = s.sample_at_pixel[static_cast<std::size_t>(yy) * width + xx];
          if (j < 0) continue;
          const float d2 = (points[k] - s.sample_points[static_cast<std::size_t>(j)]).squaredNorm();
          if (d2 <= best_d2) {
            best_d2 = d2;
            best = j;
          }
        }
      }
      if (best >= 0) break;
    }
    cluster_of[k] = best < 0 ? clusters : parent[static_cast<std::size_t>(best)];
  }
  for (const int p : s.sample_pixels) s.sample_at_pixel[static_cast<std::size_t>(p)] = -1;
  return clusters;
}

}  // namespace findmug::objects_detail
