// The fast oversegmenter (issue 7): VCCS-like supervoxels computed on the
// image grid instead of an octree.
//
// Why it is fast: the organized cloud already knows each point's neighbours,
// so there is no voxelisation, no octree and no k-d tree. Clustering is SLIC
// (Achanta et al. 2012) with PCL's VCCS distance and importances:
//
//   D = color_importance   * |Lab_p - Lab_c| / 80
//     + spatial_importance * |xyz_p - xyz_c| / seed_resolution
//     + normal_importance  * (1 - |n_p . n_c|)
//
// (PCL uses |RGB| / 255; kLabScale below puts CIELAB on the same scale.)
//
// Steps (the seeds in organized_seeds.cpp, connectivity in
// organized_connectivity.cpp, the SIMD inner loops in organized_kernels.hpp,
// the colour conversion in lab.cpp):
//  1. A half-resolution feature grid (one usable pixel of each 2x2 block:
//     CIELAB through lookup tables, xyz, normal; structure of arrays). Seeds
//     and iterations run on it, which quarters their cost.
//  2. Seeds: each pixel covers (z/fx)(z/fy)/cos(theta) m^2 of surface (theta:
//     normal vs viewing ray, capped; footprint capped beyond 4 m as PCL's
//     seeding fades out there). The image is cut k-d-tree style, longer side
//     first, into cells holding about one seed's worth of surface,
//     seed_resolution^2 / organized_seed_density, so seeds are about
//     seed_resolution apart on the surface at every depth and slant, as
//     PCL's 3-D seeding gives, and the count scales with
//     organized_seed_density / seed_resolution^2. The focal lengths come from
//     the cloud itself (u = fx x/z + cx is linear). Each cell's seed goes to
//     the usable pixel nearest its centre, then to the lowest-gradient pixel
//     of its 3x3 neighbourhood (SLIC), off colour and depth edges.
//  3. max_iterations rounds of: every cluster scans a window of
//     search_window_factor times its cell around its centre (SSE2) and claims
//     the pixels it is nearest to; centres become the means.
//  4. Full resolution: a pixel takes the label its nearest coarse samples
//     agree on, or along boundaries the nearest of their clusters.
//  5. Connectivity (on horizontal runs): each 4-connected piece of a label
//     becomes its own segment; pieces smaller than max(min_segment_points, a
//     quarter of the cell) merge into the neighbouring piece they share the
//     longest border with.
//  6. finalizeOversegmentation: drop what is still too small (islands in
//     invalid depth), renumber, 4-neighbour adjacency.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "common/cpu_features.hpp"
#include "common/scratch.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"
#include "oversegmentation/lab_internal.hpp"
#include "oversegmentation/organized_internal.hpp"
#include "oversegmentation/organized_kernels.hpp"
#include "oversegmentation/oversegmentation_internal.hpp"

namespace findmug::detail::organized {
namespace {

// CIELAB distance to PCL's colour scale (|dRGB| / 255): on the 31 NYU frames
// the mean |dLab| between pixels 9 px apart is 79.5 times their mean
// |dRGB| / 255, so |dLab| / 80 makes color_importance mean what it means to PCL.
constexpr float kLabScale = 1.0f / 80.0f;

// The L, a and b planes of one row's picked pixels, in `lab` (sized here to
// three planes of picks.size(), the row's capacity).
struct LabPlanes {
  const float* l;
  const float* a;
  const float* b;
};
LabPlanes convertPicks(const OrganizedCloud& cloud, const std::vector<int>& picks,
                       std::size_t count, std::vector<float>& lab) {
  const std::size_t capacity = picks.size();
  lab.resize(3 * capacity);
  float* l = lab.data();
  float* a = l + capacity;
  float* b = a + capacity;
  labFromRgb(cloud.colors.data(), picks.data(), count, l, a, b, LabSimd::Auto);
  return {l, a, b};
}

struct Pending {  // refineToFullResolution: a boundary pixel's candidate clusters
  std::array<int, 4> candidates;
  int count;
};

// The working memory of one segmentInto call, kept per thread between frames
// so that a stream of frames of one size allocates nothing here once warm.
// Each function borrows the vectors it needs for the call (scratch.hpp).
struct OversegBuffers {
  FeatureGrid coarse;
  std::vector<std::uint8_t> block_valid;
  std::vector<Cluster> clusters;
  std::vector<float> best;
  std::vector<int> labels, labels_full;
  std::vector<CentreSum> sums;
  // buildCoarse, refineToFullResolution: a row's pixels whose colour is
  // wanted, their cells (buildCoarse), candidates (refine) and L, a, b
  std::vector<int> picks, cells;
  std::vector<Pending> pending;
  std::vector<float> lab;
};
thread_local OversegBuffers g_buffers;

using detail::Borrowed;

class OrganizedOversegmenter final : public Oversegmenter {
 public:
  // `simd`: detail::OversegSimd::Off keeps to the scalar refinement (tests).
  explicit OrganizedOversegmenter(const OversegmentationConfig& config,
                                  detail::OversegSimd simd = detail::OversegSimd::Auto)
      : config_(config), simd_(simd) {
    weights_.color = config.color_importance * kLabScale;
    weights_.spatial = config.spatial_importance / config.seed_resolution_m;
    weights_.normal = config.normal_importance;
  }

  std::string name() const override { return "organized"; }

  Oversegmentation segment(const OrganizedCloud& cloud, const NormalImage& normals) const override {
    Oversegmentation seg;
    segmentInto(cloud, normals, seg);
    return seg;
  }

  void segmentInto(const OrganizedCloud& cloud, const NormalImage& normals,
                   Oversegmentation& seg) const override {
    detail::checkOversegmentationInput(cloud, normals, "organized oversegmenter");
    const int w = cloud.width;
    const int h = cloud.height;
    const std::size_t n = cloud.size();

    seg.width = w;
    seg.height = h;
    // Every pixel is written below (enforceConnectivity), or here when no
    // pixel is usable.
    seg.pixel_segment.resize(n);

    // Working buffers: this thread's from earlier frames (see OversegBuffers).
    // Half-resolution features; a pixel is usable when it has a point in
    // front of the camera (z <= 0 cannot come from one).
    Borrowed coarse_buffer(g_buffers.coarse);
    FeatureGrid& coarse = *coarse_buffer;
    Borrowed block_valid_buffer(g_buffers.block_valid);
    std::vector<std::uint8_t>& block_valid =
        *block_valid_buffer;  // usable full pixels per coarse pixel
    if (buildCoarse(cloud, normals, coarse, block_valid) == 0) {
      std::fill(seg.pixel_segment.begin(), seg.pixel_segment.end(), -1);
      finalizeOversegmentation(seg, config_.min_segment_points);
      return;
    }

    Borrowed clusters_buffer(g_buffers.clusters);
    std::vector<Cluster>& clusters = *clusters_buffer;
    placeSeeds(cloud, coarse, block_valid, config_, weights_, useAvx2(), clusters);

    // Iterations on the coarse grid.
    const std::size_t nc = static_cast<std::size_t>(coarse.width) * coarse.height;
    Borrowed best_buffer(g_buffers.best);
    std::vector<float>& best = *best_buffer;
    best.resize(nc);
    Borrowed labels_buffer(g_buffers.labels);
    std::vector<int>& labels = *labels_buffer;
    labels.resize(nc);
    const bool iterate_avx2 = useAvx2();  // window search and centre sums
    for (int iter = 0; iter < config_.max_iterations; ++iter) {
      std::fill(best.begin(), best.end(), std::numeric_limits<float>::infinity());
      std::fill(labels.begin(), labels.end(), -1);
      for (std::size_t k = 0; k < clusters.size(); ++k) {
        const Cluster& c = clusters[k];
        const int cu = static_cast<int>(std::lround(c.u));
        const int cv = static_cast<int>(std::lround(c.v));
        assignWindow(coarse, c.centre, weights_, static_cast<int>(k), std::max(0, cu - c.half_w),
                     std::min(coarse.width, cu + c.half_w + 1), std::max(0, cv - c.half_h),
                     std::min(coarse.height, cv + c.half_h + 1), best.data(), labels.data(),
                     iterate_avx2);
      }
      updateCentres(coarse, labels, clusters, iterate_avx2);
    }

    Borrowed labels_full_buffer(g_buffers.labels_full);
    std::vector<int>& labels_full = *labels_full_buffer;
    refineToFullResolution(cloud, normals, coarse, labels, clusters, labels_full);
    enforceConnectivity(w, h, clusters, labels_full, config_.min_segment_points, seg.pixel_segment);
    finalizeOversegmentation(seg, config_.min_segment_points);
  }

 private:
  static bool usable(const Eigen::Vector3f& p) { return p.z() > 0.0f && p.allFinite(); }

  // Point and normal channels (kX..kNZ) of full-resolution pixel i (usable)
  // into f.
  static void pointAndNormal(const OrganizedCloud& cloud, const NormalImage& normals, std::size_t i,
                             std::array<float, kNumChannels>& f) {
    const Eigen::Vector3f& p = cloud.points[i];
    f[kX] = p.x();
    f[kY] = p.y();
    f[kZ] = p.z();
    // No normal: a zero vector makes the normal term the same (1) for every
    // cluster, so the others decide.
    const Eigen::Vector3f& nv = normals.normals[i];
    const bool has_normal = nv.allFinite();
    f[kNX] = has_normal ? nv.x() : 0.0f;
    f[kNY] = has_normal ? nv.y() : 0.0f;
    f[kNZ] = has_normal ? nv.z() : 0.0f;
  }

  float distance(const std::array<float, kNumChannels>& f,
                 const std::array<float, kNumChannels>& c) const {
    const float dl = f[kL] - c[kL], da = f[kA] - c[kA], db = f[kB] - c[kB];
    const float dx = f[kX] - c[kX], dy = f[kY] - c[kY], dz = f[kZ] - c[kZ];
    const float dot = f[kNX] * c[kNX] + f[kNY] * c[kNY] + f[kNZ] * c[kNZ];
    return weights_.color * std::sqrt(dl * dl + da * da + db * db) +
           weights_.spatial * std::sqrt(dx * dx + dy * dy + dz * dz) +
           weights_.normal * (1.0f - std::fabs(dot));
  }

  // distance(f, centre of clusters[candidates[c]]) into d[c] for c < count
  // (2..4): one SSE2 lane per candidate, the same operations in the same
  // order as distance(), so the same values.
  void candidateDistances(const std::array<float, kNumChannels>& f,
                          const std::vector<Cluster>& clusters,
                          const std::array<int, 4>& candidates, int count,
                          std::array<float, 4>& d) const {
#if defined(__SSE2__)
    const float* c0 = clusters[candidates[0]].centre.data();
    const float* c1 = clusters[candidates[1]].centre.data();
    const float* c2 = count > 2 ? clusters[candidates[2]].centre.data() : c0;
    const float* c3 = count > 3 ? clusters[candidates[3]].centre.data() : c0;
    const auto diff = [&](int k) {
      return _mm_sub_ps(_mm_set1_ps(f[k]), _mm_setr_ps(c0[k], c1[k], c2[k], c3[k]));
    };
    const auto times = [&](int k) {
      return _mm_mul_ps(_mm_set1_ps(f[k]), _mm_setr_ps(c0[k], c1[k], c2[k], c3[k]));
    };
    const __m128 dl = diff(kL), da = diff(kA), db = diff(kB);
    const __m128 dx = diff(kX), dy = diff(kY), dz = diff(kZ);
    const __m128 color2 =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(dl, dl), _mm_mul_ps(da, da)), _mm_mul_ps(db, db));
    const __m128 space2 =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    const __m128 dot = _mm_add_ps(_mm_add_ps(times(kNX), times(kNY)), times(kNZ));
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 result =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(weights_.color), _mm_sqrt_ps(color2)),
                              _mm_mul_ps(_mm_set1_ps(weights_.spatial), _mm_sqrt_ps(space2))),
                   _mm_mul_ps(_mm_set1_ps(weights_.normal),
                              _mm_sub_ps(_mm_set1_ps(1.0f), _mm_and_ps(dot, abs_mask))));
    _mm_storeu_ps(d.data(), result);
#else
    for (int c = 0; c < count; ++c) d[c] = distance(f, clusters[candidates[c]].centre);
#endif
  }

  // Full-resolution labels from the coarse ones. A pixel lies between the
  // (up to) 2x2 coarse samples nearest to it; where they agree it takes
  // their label, along boundaries it picks the nearest of their clusters.
  // Pixels with no labelled sample around are kUnassigned, unusable ones -1.
  // Only boundary pixels need their own features, which is most of the
  // saving over a full-resolution SLIC pass.
  void refineToFullResolution(const OrganizedCloud& cloud, const NormalImage& normals,
                              const FeatureGrid& coarse, const std::vector<int>& labels,
                              const std::vector<Cluster>& clusters, std::vector<int>& out) const {
    const int w = cloud.width;
    const int h = cloud.height;
    const int cw = coarse.width;
    const int chh = coarse.height;
    out.resize(cloud.size());  // every pixel is written below, once
    std::array<float, kNumChannels> f{};
    // The sample of coarse pixel c is (usually) full pixel 2c: an even pixel
    // sits on it (its other neighbour is c - 1), an odd one between c, c + 1.
    const auto other = [](int full, int c, int size) {
      return std::clamp(full % kCoarseStride == 0 ? c - 1 : c + 1, 0, size - 1);
    };
    // A row's boundary pixels wait here until their colours have been
    // converted together (eight at a time with AVX2).
    Borrowed pending_buffer(g_buffers.pending);
    std::vector<Pending>& pending = *pending_buffer;
    Borrowed picks_buffer(g_buffers.picks);
    std::vector<int>& picks = *picks_buffer;
    Borrowed lab_buffer(g_buffers.lab);
    std::vector<float>& lab = *lab_buffer;
    pending.resize(w);
    picks.resize(w);
#if defined(FINDMUG_AVX2_DISPATCH)
    const bool avx2 = useAvx2();
#endif
    for (int y = 0; y < h; ++y) {
      std::size_t waiting = 0;
      const int cy = y / kCoarseStride;
      const int* row_a = labels.data() + static_cast<std::size_t>(cy) * cw;
      const int* row_b = labels.data() + static_cast<std::size_t>(other(y, cy, chh)) * cw;
      // The scalar decision for pixel x of this row.
      const auto refinePixel = [&](int x) {
        const std::size_t i = static_cast<std::size_t>(y) * w + x;
        if (!usable(cloud.points[i])) {
          out[i] = -1;
          return;
        }
        const int cx = x / kCoarseStride;
        const int ox = other(x, cx, cw);
        const std::array<int, 4> around = {row_a[cx], row_a[ox], row_b[cx], row_b[ox]};
        // Inside a segment (most pixels) the four agree: no search.
        if (around[0] == around[1] && around[0] == around[2] && around[0] == around[3]) {
          out[i] = around[0] >= 0 ? around[0] : kUnassigned;
          return;
        }
        std::array<int, 4> candidates{};
        int count = 0;
        for (const int k : around) {
          if (k >= 0 && std::find(candidates.begin(), candidates.begin() + count, k) ==
                            candidates.begin() + count) {
            candidates[count++] = k;
          }
        }
        if (count <= 1) {
          out[i] = count == 1 ? candidates[0] : kUnassigned;
          return;
        }
        pending[waiting] = {candidates, count};
        picks[waiting] = static_cast<int>(i);
        // Nothing else in this pass reads the normal and colour images, so a
        // boundary pixel's normal and colour were cache misses when the
        // distances below read them (a third of the refinement's time on the
        // synthetic walk): ask for them now, while the row is scanned.
        __builtin_prefetch(normals.normals.data() + i);
        __builtin_prefetch(cloud.colors.data() + i);
        ++waiting;
      };
      int x = 0;
#if defined(FINDMUG_AVX2_DISPATCH)
      if (avx2) {
        // Eight pixels at a time where the block's samples stay inside the
        // coarse row; the lanes whose samples differ go to refinePixel, in
        // order, so `pending` is the same list as pixel by pixel.
        const Eigen::Vector3f* row_points = cloud.points.data() + static_cast<std::size_t>(y) * w;
        int* row_out = out.data() + static_cast<std::size_t>(y) * w;
        for (; x < 2; ++x) refinePixel(x);
        for (; x + 8 <= w && x / 2 + 7 <= cw; x += 8) {
          for (int left = refineBlockAvx2(row_points, row_a, row_b, x, row_out); left != 0;
               left &= left - 1) {
            refinePixel(x + __builtin_ctz(static_cast<unsigned>(left)));
          }
        }
      }
#endif
      for (; x < w; ++x) refinePixel(x);
      const LabPlanes colour = convertPicks(cloud, picks, waiting, lab);
      for (std::size_t j = 0; j < waiting; ++j) {
        const Pending& p = pending[j];
        f[kL] = colour.l[j];
        f[kA] = colour.a[j];
        f[kB] = colour.b[j];
        pointAndNormal(cloud, normals, static_cast<std::size_t>(picks[j]), f);
        std::array<float, 4> d{};
        candidateDistances(f, clusters, p.candidates, p.count, d);
        int best_k = p.candidates[0];
        float best_d = d[0];
        for (int c = 1; c < p.count; ++c) {
          if (d[c] < best_d) {
            best_d = d[c];
            best_k = p.candidates[c];
          }
        }
        out[static_cast<std::size_t>(picks[j])] = best_k;
      }
    }
  }

  // One usable pixel per 2x2 block (not the mean: a mean across a depth
  // edge is a point in mid-air). Returns the number of usable full pixels.
  static std::size_t buildCoarse(const OrganizedCloud& cloud, const NormalImage& normals,
                                 FeatureGrid& coarse, std::vector<std::uint8_t>& block_valid) {
    const int w = cloud.width;
    const int h = cloud.height;
    const int cw = (w + kCoarseStride - 1) / kCoarseStride;
    const int chh = (h + kCoarseStride - 1) / kCoarseStride;
    coarse.resize(cw, chh);
    block_valid.assign(static_cast<std::size_t>(cw) * chh, 0);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::size_t total = 0;
    std::array<float, kNumChannels> f{};
    // The colours of a row's picks are converted together (eight at a time
    // with AVX2), then scattered to their cells.
    Borrowed picks_buffer(g_buffers.picks);
    std::vector<int>& picks = *picks_buffer;
    Borrowed cells_buffer(g_buffers.cells);
    std::vector<int>& cells = *cells_buffer;
    Borrowed lab_buffer(g_buffers.lab);
    std::vector<float>& lab = *lab_buffer;
    picks.resize(cw);
    cells.resize(cw);
    for (int cy = 0; cy < chh; ++cy) {
      std::size_t picked = 0;
      for (int cx = 0; cx < cw; ++cx) {
        const std::size_t ci = static_cast<std::size_t>(cy) * cw + cx;
        std::size_t pick = 0;
        int count = 0;
        for (int y = cy * kCoarseStride; y < std::min(h, (cy + 1) * kCoarseStride); ++y) {
          for (int x = cx * kCoarseStride; x < std::min(w, (cx + 1) * kCoarseStride); ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * w + x;
            if (!usable(cloud.points[i])) continue;
            if (count == 0) pick = i;
            ++count;
          }
        }
        block_valid[ci] = static_cast<std::uint8_t>(count);
        total += count;
        if (count == 0) {
          coarse.ch[kX][ci] = coarse.ch[kY][ci] = coarse.ch[kZ][ci] = nan;
          continue;
        }
        pointAndNormal(cloud, normals, pick, f);
        for (int k = kX; k < kNumChannels; ++k) coarse.ch[k][ci] = f[k];
        picks[picked] = static_cast<int>(pick);
        cells[picked] = static_cast<int>(ci);
        ++picked;
      }
      const LabPlanes colour = convertPicks(cloud, picks, picked, lab);
      for (std::size_t j = 0; j < picked; ++j) {
        coarse.ch[kL][cells[j]] = colour.l[j];
        coarse.ch[kA][cells[j]] = colour.a[j];
        coarse.ch[kB][cells[j]] = colour.b[j];
      }
    }
    return total;
  }

  // `avx2`: the channel sums four pixels at a time (the same bits).
  static void updateCentres(const FeatureGrid& g, const std::vector<int>& labels,
                            std::vector<Cluster>& clusters, bool avx2) {
    Borrowed sums_buffer(g_buffers.sums);
    std::vector<CentreSum>& sums = *sums_buffer;
    sums.assign(clusters.size(), CentreSum{});
    const float* ch[kNumChannels];
    for (int c = 0; c < kNumChannels; ++c) ch[c] = g.ch[c].data();
    // A row holds a few runs of one cluster each: a run's sums are added in
    // locals (registers), then stored. Per cluster the additions happen in
    // the same order as pixel by pixel, so the centres are the same bits;
    // through sums[k] every pixel cost a load and a store per sum.
    for (int y = 0; y < g.height; ++y) {
      const int* row = labels.data() + static_cast<std::size_t>(y) * g.width;
      for (int x = 0; x < g.width;) {
        const int k = row[x];
        int x1 = x + 1;
        while (x1 < g.width && row[x1] == k) ++x1;
        if (k >= 0) {
          CentreSum& sum = sums[k];
          const std::size_t row_start = static_cast<std::size_t>(y) * g.width;
#if defined(FINDMUG_AVX2_DISPATCH)
          if (avx2) {
            addRunChannelsAvx2(ch, row_start, x, x1, sum);
          } else {
            addRunChannels(ch, row_start, x, x1, sum);
          }
#else
          (void)avx2;
          addRunChannels(ch, row_start, x, x1, sum);
#endif
          // Sums of pixel coordinates are integers far below 2^53, exact
          // in any order: whole runs at once.
          sum.u += columnSum(x, x1);
          sum.v += static_cast<double>(y) * (x1 - x);
          sum.count += x1 - x;
        }
        x = x1;
      }
    }
    for (std::size_t k = 0; k < clusters.size(); ++k) {
      const CentreSum& s = sums[k];
      if (s.count == 0) continue;  // keeps its old centre; may win pixels next round
      Cluster& c = clusters[k];
      const double inv = 1.0 / s.count;
      for (int ch = 0; ch < kNumChannels; ++ch) c.centre[ch] = static_cast<float>(s.ch[ch] * inv);
      const float norm = std::sqrt(c.centre[kNX] * c.centre[kNX] + c.centre[kNY] * c.centre[kNY] +
                                   c.centre[kNZ] * c.centre[kNZ]);
      if (norm > 1e-6f) {
        c.centre[kNX] /= norm;
        c.centre[kNY] /= norm;
        c.centre[kNZ] /= norm;
      }
      c.u = static_cast<float>(s.u * inv);
      c.v = static_cast<float>(s.v * inv);
    }
  }

  // Whether the AVX2 variants (window search, refinement, centre sums, seed
  // density) run: the CPU has AVX2 and the tests did not switch them off.
  bool useAvx2() const {
#if defined(FINDMUG_AVX2_DISPATCH)
    return simd_ == detail::OversegSimd::Auto && detail::cpuHasAvx2();
#else
    return false;
#endif
  }

  OversegmentationConfig config_;
  detail::OversegSimd simd_ = detail::OversegSimd::Auto;
  Weights weights_{};
};

}  // namespace
}  // namespace findmug::detail::organized

namespace findmug::detail {

std::unique_ptr<Oversegmenter> makeOrganizedOversegmenter(const OversegmentationConfig& config,
                                                          OversegSimd simd) {
  return std::make_unique<organized::OrganizedOversegmenter>(config, simd);
}

}  // namespace findmug::detail
