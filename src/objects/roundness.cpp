// The roundness cue of a taught view or a candidate (object_model.hpp): how
// far its side points are from a vertical cylinder.
//
// Why: ESF (shape_descriptor.cpp) does not tell a mug from a box of its size
// and colour (object_recognition_eval: every false "found" was that box). Seen
// from the side, a cylinder's side points lie on an arc in the floor plane; a
// box's one or two visible faces give a line or an L. A circle fitted to a line
// has a radius far beyond the points' spread; fitted to an L it runs through
// the corner and the ends (Thales), and the legs' middles fall inside it by a
// tenth of the radius, the same sign all along each leg. Depth noise and
// quantisation (several mm at 2 m) scatter single points by as much, so the
// residual is taken per angular bin as the mean of the bin's middle half,
// which averages the noise out and keeps the L's systematic bulge.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "findmug/objects/object_model.hpp"

namespace findmug {
namespace {

// Side points: below the rim and top face (the top fifth of the height holds
// them, with depth noise), above the contact with the table.
constexpr double kTopShare = 0.2, kBottomShare = 0.1;
constexpr int kMinSidePoints = 20;
// A fitted radius beyond this many times the points' spread is a straight face.
constexpr double kMaxRadiusOverSpread = 2.5;
// The circle is first found by RANSAC (a mug's handle, facing the camera,
// pulls a least-squares fit off the cup by a centimetre): the most points
// within kInlierM of a circle through three of them, radius within
// kMinRadiusM..kMaxRadiusM. Then it is refitted to the points within kBandM
// of it: wide enough to keep a box's L, whose middles fall some millimetres
// inside its circle, narrow enough to drop the handle's face (2-3 cm out).
constexpr double kInlierM = 0.005, kBandM = 0.012;
constexpr double kMinRadiusM = 0.01, kMaxRadiusM = 0.3;
constexpr int kRansacDraws = 300;
constexpr double kBinRad = 15.0 * M_PI / 180.0;
constexpr int kMinBinPoints = 4;
constexpr int kMinBins = 3;

struct Circle {
  Eigen::Vector2d center;
  double radius = 0.0;
  bool ok = false;
};

// Kasa's algebraic fit, x^2 + y^2 + D x + E y + F = 0, in coordinates about
// the points' mean (better conditioned than the ground frame's metres).
Circle fitCircle(const std::vector<Eigen::Vector2d>& xy) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : xy) mean += p;
  mean /= static_cast<double>(xy.size());
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  for (const auto& p : xy) {
    const Eigen::Vector2d q = p - mean;
    const Eigen::Vector3d a(q.x(), q.y(), 1.0);
    ata += a * a.transpose();
    atb -= a * q.squaredNorm();
  }
  const Eigen::Vector3d s = ata.ldlt().solve(atb);
  Circle c;
  c.center = mean + Eigen::Vector2d(-s(0) / 2, -s(1) / 2);
  const double r2 = s(0) * s(0) / 4 + s(1) * s(1) / 4 - s(2);
  c.ok = s.allFinite() && r2 > 0.0;
  c.radius = c.ok ? std::sqrt(r2) : 0.0;
  return c;
}

// The mean of the middle half: a median of depth quantised in centimetre
// steps at 2 m is itself a step; the mean of the middle half averages the
// noise that dithers the steps and still drops stray points.
double middleMean(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t lo = v.size() / 4, hi = v.size() - v.size() / 4;
  double sum = 0.0;
  for (std::size_t i = lo; i < hi; ++i) sum += v[i];
  return sum / static_cast<double>(hi - lo);
}

// The circle through three points (ok false when they are on a line).
Circle circleThrough(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  const Eigen::Vector2d ab = b - a, ac = c - a;
  const double d = 2.0 * (ab.x() * ac.y() - ab.y() * ac.x());
  Circle out;
  if (std::abs(d) < 1e-12) return out;
  const Eigen::Vector2d u((ac.y() * ab.squaredNorm() - ab.y() * ac.squaredNorm()) / d,
                          (ab.x() * ac.squaredNorm() - ac.x() * ab.squaredNorm()) / d);
  out.center = a + u;
  out.radius = u.norm();
  out.ok = true;
  return out;
}

int countWithin(const std::vector<Eigen::Vector2d>& xy, const Circle& c, double band) {
  int n = 0;
  for (const auto& p : xy) n += std::abs((p - c.center).norm() - c.radius) <= band;
  return n;
}

// RANSAC with a fixed generator (splitmix64): the same points, the same circle.
Circle ransacCircle(const std::vector<Eigen::Vector2d>& xy) {
  std::uint64_t state = 0x853C49E6748FEA9Bull;
  auto draw = [&](std::size_t n) {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return static_cast<std::size_t>((z ^ (z >> 31)) % n);
  };
  Circle best;
  int best_count = -1;
  for (int i = 0; i < kRansacDraws; ++i) {
    const Circle c = circleThrough(xy[draw(xy.size())], xy[draw(xy.size())], xy[draw(xy.size())]);
    if (!c.ok || c.radius < kMinRadiusM || c.radius > kMaxRadiusM) continue;
    const int n = countWithin(xy, c, kInlierM);
    if (n > best_count) {
      best_count = n;
      best = c;
    }
  }
  return best;
}

std::vector<double> residuals(const std::vector<Eigen::Vector2d>& xy, const Circle& c) {
  std::vector<double> r;
  r.reserve(xy.size());
  for (const auto& p : xy) r.push_back((p - c.center).norm() - c.radius);
  return r;
}

std::vector<Eigen::Vector2d> within(const std::vector<Eigen::Vector2d>& xy, const Circle& c,
                                    double band) {
  std::vector<Eigen::Vector2d> kept;
  for (const auto& p : xy)
    if (std::abs((p - c.center).norm() - c.radius) <= band) kept.push_back(p);
  return kept;
}

std::vector<Eigen::Vector2d> sidePoints(const std::vector<Eigen::Vector3f>& points) {
  float lo = INFINITY, hi = -INFINITY;
  for (const auto& p : points) {
    if (!p.allFinite()) continue;
    lo = std::min(lo, p.z());
    hi = std::max(hi, p.z());
  }
  const double h = hi - lo;
  std::vector<Eigen::Vector2d> xy;
  for (const auto& p : points) {
    if (p.allFinite() && p.z() >= lo + kBottomShare * h && p.z() <= hi - kTopShare * h) {
      xy.emplace_back(p.x(), p.y());
    }
  }
  return xy;
}

double spreadOf(const std::vector<Eigen::Vector2d>& xy) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : xy) mean += p;
  mean /= static_cast<double>(xy.size());
  double spread = 0.0;
  for (const auto& p : xy) spread = std::max(spread, (p - mean).norm());
  return spread;
}

// RMS over the angular bins (about the centre) of each bin's median residual.
double binnedResidual(const std::vector<Eigen::Vector2d>& xy, const Circle& c) {
  const int bins = static_cast<int>(std::ceil(2 * M_PI / kBinRad));
  std::vector<std::vector<double>> per_bin(bins);
  const std::vector<double> r = residuals(xy, c);
  for (std::size_t i = 0; i < xy.size(); ++i) {
    const Eigen::Vector2d d = xy[i] - c.center;
    const double a = std::atan2(d.y(), d.x()) + M_PI;
    per_bin[std::min(bins - 1, static_cast<int>(a / kBinRad))].push_back(r[i]);
  }
  double sum = 0.0;
  int used = 0;
  for (auto& b : per_bin) {
    if (static_cast<int>(b.size()) < kMinBinPoints) continue;
    // Less what the bin's noise alone gives its mean squared (its variance
    // over the points): a far cylinder's noisy bins then count near zero,
    // a box's systematic offsets stay.
    const double m = middleMean(b);
    double mean = 0.0, var = 0.0;
    for (double x : b) mean += x;
    mean /= static_cast<double>(b.size());
    for (double x : b) var += (x - mean) * (x - mean);
    var /= static_cast<double>(b.size() - 1);
    sum += std::max(0.0, m * m - var / static_cast<double>(b.size()));
    ++used;
  }
  return used >= kMinBins ? std::sqrt(sum / used) : -1.0;
}

}  // namespace

float objectRoundnessResidual(const std::vector<Eigen::Vector3f>& points) {
  const std::vector<Eigen::Vector2d> side = sidePoints(points);
  if (static_cast<int>(side.size()) < kMinSidePoints) return kNotRound;
  Circle c = ransacCircle(side);
  std::vector<Eigen::Vector2d> kept;
  for (int round = 0; round < 2 && c.ok; ++round) {
    kept = within(side, c, kBandM);
    if (static_cast<int>(kept.size()) < kMinSidePoints) return kNotRound;
    c = fitCircle(kept);
  }
  if (!c.ok || c.radius > kMaxRadiusOverSpread * spreadOf(kept)) return kNotRound;
  const double binned = binnedResidual(kept, c);
  if (binned < 0.0) return kNotRound;
  return static_cast<float>(std::min(binned / c.radius, static_cast<double>(kNotRound)));
}

}  // namespace findmug
