#include "findmug/offline/mrf_context.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/labels/labels.hpp"

namespace findmug {

namespace {

constexpr double kRidge = 1e-3;
constexpr int kNewtonSteps = 25;

double logistic(double t) { return 1.0 / (1.0 + std::exp(-t)); }

}  // namespace

PairwiseContext learnPairwiseContext(const std::vector<LabelledGraph>& graphs) {
  std::vector<std::array<float, kPairFeatureDim>> xs;
  std::vector<double> ys;
  for (std::size_t g = 0; g < graphs.size(); ++g) {
    const LabelledGraph& graph = graphs[g];
    if (!graph.features || !graph.edges || !graph.labels ||
        graph.features->size() != graph.labels->size())
      throw Error("learnPairwiseContext: graph " + std::to_string(g) +
                  " lacks features, edges or labels, or their counts differ");
    const auto n = static_cast<long long>(graph.labels->size());
    for (const auto& [a, b] : *graph.edges) {
      if (a < 0 || b < 0 || a >= n || b >= n)
        throw Error("learnPairwiseContext: graph " + std::to_string(g) + " has edge (" +
                    std::to_string(a) + ", " + std::to_string(b) + ") outside its " +
                    std::to_string(n) + " patches");
      const std::uint8_t la = (*graph.labels)[static_cast<std::size_t>(a)];
      const std::uint8_t lb = (*graph.labels)[static_cast<std::size_t>(b)];
      if (la >= kNumLabels || lb >= kNumLabels) continue;
      const auto x = pairFeatures((*graph.features)[static_cast<std::size_t>(a)],
                                  (*graph.features)[static_cast<std::size_t>(b)]);
      bool finite = true;
      for (float v : x) finite = finite && std::isfinite(v);
      if (!finite) continue;
      xs.push_back(x);
      ys.push_back(la == lb ? 1.0 : 0.0);
    }
  }
  if (xs.empty()) throw Error("learnPairwiseContext: no edge joins two labelled patches");
  PairwiseContext m;
  m.training_edges = xs.size();
  const double count = static_cast<double>(xs.size());
  for (int k = 0; k < kPairFeatureDim; ++k) {
    double sum = 0, sum2 = 0;
    for (const auto& x : xs) {
      sum += x[k];
      sum2 += static_cast<double>(x[k]) * x[k];
    }
    m.mean[k] = sum / count;
    const double var = sum2 / count - m.mean[k] * m.mean[k];
    m.scale[k] = var > 1e-12 ? std::sqrt(var) : 1.0;
  }
  // Newton's method on the mean log-likelihood (the problem is convex).
  constexpr int kDim = kPairFeatureDim + 1;
  Eigen::Matrix<double, kDim, 1> theta = Eigen::Matrix<double, kDim, 1>::Zero();
  double same = 0;
  for (double y : ys) same += y;
  const double prior = std::min(std::max(same / count, 1e-6), 1 - 1e-6);
  theta[0] = std::log(prior / (1 - prior));
  for (int step = 0; step < kNewtonSteps; ++step) {
    Eigen::Matrix<double, kDim, 1> gradient = Eigen::Matrix<double, kDim, 1>::Zero();
    Eigen::Matrix<double, kDim, kDim> hessian = Eigen::Matrix<double, kDim, kDim>::Zero();
    for (std::size_t i = 0; i < xs.size(); ++i) {
      Eigen::Matrix<double, kDim, 1> z;
      z[0] = 1.0;
      for (int k = 0; k < kPairFeatureDim; ++k) z[k + 1] = (xs[i][k] - m.mean[k]) / m.scale[k];
      const double p = logistic(theta.dot(z));
      gradient += (ys[i] - p) * z;
      hessian -= p * (1 - p) * z * z.transpose();
    }
    gradient /= count;
    hessian /= count;
    for (int k = 1; k < kDim; ++k) {
      gradient[k] -= kRidge * theta[k];
      hessian(k, k) -= kRidge;
    }
    const Eigen::Matrix<double, kDim, 1> delta = hessian.ldlt().solve(-gradient);
    theta += delta;
    if (delta.cwiseAbs().maxCoeff() < 1e-8) break;
  }
  m.bias = theta[0];
  for (int k = 0; k < kPairFeatureDim; ++k) m.weights[k] = theta[k + 1];
  double mean_cost = 0;
  for (const auto& x : xs) mean_cost += contextPartingCost(sameLabelProbability(m, x));
  m.mean_cost = mean_cost / count;
  return m;
}

}  // namespace findmug
