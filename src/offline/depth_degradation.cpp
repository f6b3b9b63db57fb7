#include "findmug/offline/depth_degradation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "findmug/common/error.hpp"

namespace findmug {

namespace {

// Kinect disparity <-> depth (NYU toolbox): depth_m = kDepthNumerator / (kDisparityOffset - d).
constexpr double kDepthNumerator = 351.3;
constexpr double kDisparityOffset = 1092.5;

// Counter-based random numbers: the value for (seed, stream, index) does not
// depend on the order pixels are visited nor on the standard library, so a
// seed gives the same frame with any compiler.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

enum Stream : std::uint64_t { kBlobStream = 1, kPixelStream, kNoiseStream };

double uniform01(std::uint64_t seed, Stream stream, std::uint64_t index) {
  const std::uint64_t h = mix(mix(seed ^ (static_cast<std::uint64_t>(stream) << 56)) ^ index);
  return static_cast<double>(h >> 11) * 0x1.0p-53;  // [0, 1)
}

// Standard normal from two of those (Box-Muller).
double normal(std::uint64_t seed, Stream stream, std::uint64_t index) {
  const double u1 = 1.0 - uniform01(seed, stream, 2 * index);  // (0, 1]
  const double u2 = uniform01(seed, stream, 2 * index + 1);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

// Holes along an edge come in short pieces, not single pixels: the edge
// band's chance is compared with noise correlated over this many pixels
// (other noise than the dropouts': seed mixed with a constant).
constexpr double kEdgeBlobPx = 8.0;
constexpr std::uint64_t kEdgeSeedMix = 0x5bd1e9955bd1e995ULL;

double clamp01(double x) { return std::min(1.0, std::max(0.0, x)); }

double grey(const Rgb8& c) { return 0.299 * c.r + 0.587 * c.g + 0.114 * c.b; }

// Pixels that a nearer surface hides from the projector (see the config).
std::vector<std::uint8_t> shadowMask(const std::vector<double>& z, int w, int h,
                                     const DepthDegradationConfig& c) {
  std::vector<std::uint8_t> out(z.size(), 0);
  if (c.shadow_baseline_m == 0.0f) return out;
  const double shift = static_cast<double>(c.shadow_focal_px) * std::abs(c.shadow_baseline_m);
  const bool left = c.shadow_baseline_m > 0;
  for (int y = 0; y < h; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * w;
    // Each pixel's column in the projector image; a pixel is hidden when a
    // pixel on the projector's side of it lands further towards that side.
    double extreme =
        left ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
    for (int k = 0; k < w; ++k) {
      const int x = left ? w - 1 - k : k;
      const double d = z[row + x];
      if (d <= 0) continue;
      const double projected = left ? x - shift / d : x + shift / d;
      if (left ? projected > extreme + 0.5 : projected < extreme - 0.5) out[row + x] = 1;
      extreme = left ? std::min(extreme, projected) : std::max(extreme, projected);
    }
  }
  return out;
}

// Pixels within `band` (Chebyshev distance) of a depth edge.
std::vector<std::uint8_t> edgeBand(const std::vector<double>& z, int w, int h, double jump,
                                   int band) {
  std::vector<std::uint8_t> edge(z.size(), 0);
  auto is_jump = [&](double a, double b) {
    return a > 0 && b > 0 && std::abs(a - b) > jump * std::min(a, b);
  };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      if (x + 1 < w && is_jump(z[i], z[i + 1])) edge[i] = edge[i + 1] = 1;
      if (y + 1 < h && is_jump(z[i], z[i + w])) edge[i] = edge[i + w] = 1;
    }
  }
  if (band <= 0) return edge;
  // Separable dilation: rows, then columns.
  std::vector<std::uint8_t> rows(z.size(), 0), out(z.size(), 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      if (!edge[i]) continue;
      for (int dx = std::max(0, x - band); dx <= std::min(w - 1, x + band); ++dx)
        rows[static_cast<std::size_t>(y) * w + dx] = 1;
    }
  }
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!rows[static_cast<std::size_t>(y) * w + x]) continue;
      for (int dy = std::max(0, y - band); dy <= std::min(h - 1, y + band); ++dy)
        out[static_cast<std::size_t>(dy) * w + x] = 1;
    }
  }
  return out;
}

// Mean grey value over a (2r+1)^2 window (integral image): IR reflectance
// follows a surface, not its texture's single pixels.
std::vector<double> smoothedGrey(const RgbdFrame& f, int r) {
  const int w = f.width, h = f.height;
  std::vector<double> integral(static_cast<std::size_t>(w + 1) * (h + 1), 0.0);
  for (int y = 0; y < h; ++y) {
    double row = 0;
    for (int x = 0; x < w; ++x) {
      row += grey(f.rgb[static_cast<std::size_t>(y) * w + x]);
      integral[static_cast<std::size_t>(y + 1) * (w + 1) + x + 1] =
          integral[static_cast<std::size_t>(y) * (w + 1) + x + 1] + row;
    }
  }
  std::vector<double> out(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    const int y0 = std::max(0, y - r), y1 = std::min(h, y + r + 1);
    for (int x = 0; x < w; ++x) {
      const int x0 = std::max(0, x - r), x1 = std::min(w, x + r + 1);
      const auto at = [&](int yy, int xx) {
        return integral[static_cast<std::size_t>(yy) * (w + 1) + xx];
      };
      const double sum = at(y1, x1) - at(y0, x1) - at(y1, x0) + at(y0, x0);
      out[static_cast<std::size_t>(y) * w + x] = sum / ((y1 - y0) * (x1 - x0));
    }
  }
  return out;
}

// The share of the blob noise's variance that is correlated (squared); the
// rest roughens the blobs' outlines.
constexpr double kSmoothShare = 0.995;

// Uniform [0, 1) noise whose values are correlated over about `size` px:
// normals on a grid of that spacing, interpolated bilinearly and rescaled to
// unit variance, mixed with a little per-pixel noise for ragged blob edges,
// then through the normal CDF.
double blobNoise(std::uint64_t seed, int x, int y, int grid_w, double size) {
  double n;
  if (size <= 0) {
    n = normal(seed, kPixelStream, static_cast<std::uint64_t>(y) * 65536u + x);
  } else {
    const double gx = x / size, gy = y / size;
    const int ix = static_cast<int>(gx), iy = static_cast<int>(gy);
    const double fx = gx - ix, fy = gy - iy;
    auto node = [&](int cx, int cy) {
      return normal(seed, kBlobStream, static_cast<std::uint64_t>(cy) * grid_w + cx);
    };
    const double w00 = (1 - fx) * (1 - fy), w10 = fx * (1 - fy), w01 = (1 - fx) * fy, w11 = fx * fy;
    const double smooth = (w00 * node(ix, iy) + w10 * node(ix + 1, iy) + w01 * node(ix, iy + 1) +
                           w11 * node(ix + 1, iy + 1)) /
                          std::sqrt(w00 * w00 + w10 * w10 + w01 * w01 + w11 * w11);
    const double rough = normal(seed, kPixelStream, static_cast<std::uint64_t>(y) * 65536u + x);
    n = kSmoothShare * smooth + std::sqrt(1 - kSmoothShare * kSmoothShare) * rough;
  }
  return 0.5 * std::erfc(-n / std::sqrt(2.0));
}

// The share of holes inside the bounding box of the measured pixels: a
// masked border (NYU's projection mask, zero in the filled frames too) is
// not a sign of raw depth.
double innerHoleFraction(const RgbdFrame& f) {
  int x0 = f.width, x1 = -1, y0 = f.height, y1 = -1;
  for (int y = 0; y < f.height; ++y)
    for (int x = 0; x < f.width; ++x)
      if (f.depth_mm[static_cast<std::size_t>(y) * f.width + x] != 0) {
        x0 = std::min(x0, x);
        x1 = std::max(x1, x);
        y0 = std::min(y0, y);
        y1 = std::max(y1, y);
      }
  if (x1 < 0) return 1.0;
  std::size_t holes = 0;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x)
      holes += f.depth_mm[static_cast<std::size_t>(y) * f.width + x] == 0;
  return static_cast<double>(holes) / (static_cast<double>(x1 - x0 + 1) * (y1 - y0 + 1));
}

}  // namespace

RgbdFrame degradeDepth(const RgbdFrame& frame, const DepthDegradationConfig& c, std::uint64_t seed,
                       DegradationReport* report) {
  validateFrame(frame);
  DegradationReport r;
  RgbdFrame out = frame;
  const int w = frame.width, h = frame.height;
  const std::size_t n = frame.depth_mm.size();
  std::vector<double> z(n);
  for (std::size_t i = 0; i < n; ++i) {
    z[i] = frame.depth_mm[i] * 0.001;
    if (frame.depth_mm[i] != 0) ++r.valid_before;
  }
  if (n == 0 || innerHoleFraction(frame) > c.max_input_hole_fraction) {
    r.skipped = true;
    if (report) *report = r;
    return out;
  }

  const std::vector<std::uint8_t> shadow = shadowMask(z, w, h, c);
  const std::vector<std::uint8_t> edge = edgeBand(z, w, h, c.edge_relative_jump, c.edge_band_px);
  const std::vector<double> grey_level = smoothedGrey(frame, 2);
  const int grid_w = c.blob_size_px > 0 ? static_cast<int>(w / c.blob_size_px) + 2 : 0;
  const int edge_grid_w = static_cast<int>(w / kEdgeBlobPx) + 2;
  const double dark_level = std::max(1e-6, static_cast<double>(c.dark_level));
  const double bright_span = std::max(1e-6, 255.0 - c.bright_level);

  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      if (z[i] <= 0) continue;
      bool hole = false;
      if (shadow[i]) {
        hole = true;
        ++r.shadow;
      } else if (edge[i] && blobNoise(seed ^ kEdgeSeedMix, x, y, edge_grid_w, kEdgeBlobPx) <
                                c.edge_hole_probability) {
        hole = true;
        ++r.edge;
      } else {
        const double g = grey_level[i];
        const double dark = c.dark_hole_probability * clamp01((dark_level - g) / dark_level);
        const double bright =
            c.bright_hole_probability * clamp01((g - c.bright_level) / bright_span);
        const double far = clamp01(c.far_hole_per_m * (z[i] - c.far_start_m));
        const double keep = (1 - c.base_hole_probability) * (1 - dark) * (1 - bright) * (1 - far);
        if (blobNoise(seed, x, y, grid_w, c.blob_size_px) < 1 - keep) {
          hole = true;
          ++r.dropout;
        }
      }
      if (hole) {
        out.depth_mm[i] = 0;
        ++r.holes_added;
        continue;
      }
      if (!c.quantise && c.disparity_noise == 0.0f) continue;
      double d = kDisparityOffset - kDepthNumerator / z[i];
      d += c.disparity_noise * normal(seed, kNoiseStream, i);
      if (c.quantise) d = std::round(d);
      const double depth_mm =
          d < kDisparityOffset ? 1000.0 * kDepthNumerator / (kDisparityOffset - d) : 0.0;
      // Out of the sensor's range after the noise: no measurement.
      const bool in_range = depth_mm >= 0.5 && depth_mm <= 65535.0;
      out.depth_mm[i] = in_range ? static_cast<std::uint16_t>(std::lround(depth_mm)) : 0;
      if (!in_range) {
        ++r.holes_added;
        ++r.dropout;
      }
    }
  }
  if (report) *report = r;
  return out;
}

HoleStatistics holeStatistics(const RgbdFrame& frame, const StatisticsWindow& window) {
  validateFrame(frame);
  const int w = frame.width, h = frame.height;
  StatisticsWindow win = window;
  if (win.x0 == 0 && win.y0 == 0 && win.x1 == 0 && win.y1 == 0) {
    win.x1 = w;
    win.y1 = h;
  }
  if (win.x0 < 0 || win.y0 < 0 || win.x1 > w || win.y1 > h || win.x0 >= win.x1 ||
      win.y0 >= win.y1 || win.radius_px < 1) {
    throw Error(frame.source + ": hole statistics window [" + std::to_string(win.x0) + ", " +
                std::to_string(win.x1) + ") x [" + std::to_string(win.y0) + ", " +
                std::to_string(win.y1) + ") radius " + std::to_string(win.radius_px) +
                " does not fit a " + std::to_string(w) + "x" + std::to_string(h) + " frame");
  }
  HoleStatistics s;
  const auto depth = [&](int x, int y) {
    return frame.depth_mm[static_cast<std::size_t>(y) * w + x] * 0.001;
  };
  const int r = win.radius_px;
  for (int y = win.y0; y < win.y1; ++y) {
    for (int x = win.x0; x < win.x1; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      const bool hole = frame.depth_mm[i] == 0;
      ++s.pixels;
      s.holes += hole;
      const double g = grey(frame.rgb[i]);
      const int gb = g < 40 ? 0 : g < 80 ? 1 : g < 140 ? 2 : g < 220 ? 3 : 4;
      ++s.by_brightness[gb][0];
      s.by_brightness[gb][1] += hole;
      // The neighbourhood's measured depths (inside the window only, so that
      // a masked border does not count as holes' context).
      double lo = std::numeric_limits<double>::infinity(), hi = 0, sum = 0;
      int count = 0;
      for (int yy = std::max(win.y0, y - r); yy < std::min(win.y1, y + r + 1); ++yy) {
        for (int xx = std::max(win.x0, x - r); xx < std::min(win.x1, x + r + 1); ++xx) {
          const double d = depth(xx, yy);
          if (d <= 0) continue;
          lo = std::min(lo, d);
          hi = std::max(hi, d);
          sum += d;
          ++count;
        }
      }
      if (count == 0) {
        ++s.isolated;
        continue;
      }
      const double spread = (hi - lo) / lo;
      const int sb = spread < 0.02 ? 0 : spread < 0.10 ? 1 : spread < 0.30 ? 2 : 3;
      ++s.by_spread[sb][0];
      s.by_spread[sb][1] += hole;
      const double mean = sum / count;
      const int rb = mean < 2.0 ? 0 : mean < 3.0 ? 1 : mean < 4.5 ? 2 : 3;
      ++s.by_range[rb][0];
      s.by_range[rb][1] += hole;
    }
  }
  std::size_t runs = 0, run_pixels = 0;
  for (int y = win.y0; y < win.y1; ++y) {
    int x = win.x0;
    while (x < win.x1) {
      if (depth(x, y) > 0) {
        ++x;
        continue;
      }
      const int start = x;
      while (x < win.x1 && depth(x, y) <= 0) ++x;
      ++runs;
      run_pixels += static_cast<std::size_t>(x - start);
      if (start > win.x0 && x < win.x1) {
        const double left = depth(start - 1, y), right = depth(x, y);
        if (std::max(left, right) > 1.1 * std::min(left, right)) {
          (left > right ? s.far_left_runs : s.far_right_runs) += 1;
        }
      }
    }
  }
  s.mean_run_px = runs ? static_cast<double>(run_pixels) / runs : 0.0;
  return s;
}

std::string brightnessBinName(int bin) {
  static const char* names[] = {"grey 0-40", "grey 40-80", "grey 80-140", "grey 140-220",
                                "grey 220-255"};
  return bin >= 0 && bin < HoleStatistics::kBrightnessBins ? names[bin] : "?";
}

std::string spreadBinName(int bin) {
  static const char* names[] = {"spread <2%", "spread 2-10%", "spread 10-30%", "spread >=30%"};
  return bin >= 0 && bin < HoleStatistics::kSpreadBins ? names[bin] : "?";
}

std::string rangeBinName(int bin) {
  static const char* names[] = {"range <2m", "range 2-3m", "range 3-4.5m", "range >=4.5m"};
  return bin >= 0 && bin < HoleStatistics::kRangeBins ? names[bin] : "?";
}

}  // namespace findmug
