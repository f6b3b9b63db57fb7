#include "findmug/offline/pseudo_labels.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <tuple>

#include "findmug/common/error.hpp"
#include "findmug/mrf/context_pairwise.hpp"
#include "findmug/mrf/object_consistency.hpp"
#include "findmug/tables/table_regions.hpp"

namespace findmug {

SampleLabelling labelSample(const RandomForest& model, const FrameSample& s,
                            const SegmenterConfig& config, const RegionFeatures* regions,
                            const LayoutPrior* layout) {
  SampleLabelling out;
  out.probabilities = predictSample(model, s, config);
  // Per patch its pixel count: the object means' and the region vote's weights.
  const std::vector<float> weights(s.segment_pixels.begin(), s.segment_pixels.end());
  std::vector<ClassProbabilities> unaries = out.probabilities;
  if (config.use_mrf) {
    ObjectMeanScratch scratch;
    mixObjectMeansInPlace(unaries, s.features.object_group, weights,
                          config.mrf.object_consistency, scratch);
  }
  weightTableProbabilityInPlace(unaries, config.tables.table_weight);
  const bool with_layout = config.use_mrf && config.mrf.pairwise == MrfPairwise::Layout;
  if (with_layout && !layout)
    throw Error("labelSample: mrf.pairwise = layout without a loaded layout prior");
  const bool with_context = config.use_mrf && config.mrf.pairwise == MrfPairwise::Context;
  const PairwiseContext* pairwise = with_context ? model.pairwiseContext() : nullptr;
  if (with_context && !pairwise)
    throw Error("labelSample: mrf.pairwise = context but model " + model.id() +
                " carries no learned pairwise term (train it with mrf.pairwise = context)");
  if (with_layout) {
    std::vector<float> heights;
    const float threshold =
        layoutHeightsInto(config.mrf, {&s.pixel_segment, s.width, &s.features.features}, heights);
    MrfPairFactors factors;
    layoutPairFactorsInto(*layout, config.mrf.layout_weight, threshold, heights, s.edges, factors);
    solveMrfWithFactorsInto(unaries, s.features.centroids, s.edges, factors, config.mrf, out.mrf);
  } else if (config.use_mrf) {
    out.mrf = pairwise ? solveMrfScaled(unaries, s.features.centroids, s.edges,
                                        pairwiseContextScales(*pairwise, s.features.features,
                                                              s.edges),
                                        config.mrf)
                       : solveMrf(unaries, s.features.centroids, s.edges, config.mrf);
  } else {
    for (const ClassProbabilities& p : unaries) {
      const auto best = std::max_element(p.begin(), p.end());
      out.mrf.labels.push_back(static_cast<std::uint8_t>(best - p.begin()));
      out.mrf.confidence.push_back(*best);
    }
  }
  if (regions) {
    RegionVoteResult vote =
        voteTableRegions(out.mrf.labels, out.mrf.confidence, unaries, weights, *regions,
                         config.tables);
    out.mrf.labels = std::move(vote.labels);
    out.mrf.confidence = std::move(vote.confidence);
  }
  return out;
}

int PseudoLabelRound::keptTotal() const { return std::accumulate(kept.begin(), kept.end(), 0); }

namespace {

// Per label, its most frequent fine class among the labelled frames' patches
// (0 where no labelled patch has the label), for pseudo patches of a model
// with internal classes. Ties go to the lower id.
std::array<std::uint8_t, kNumLabels> dominantFineClasses(
    const std::vector<const FrameSample*>& labelled) {
  std::array<std::array<int, kNyu40Classes + 1>, kNumLabels> votes{};
  for (const FrameSample* s : labelled) {
    if (s->segment_fine_labels.size() != s->segment_labels.size()) continue;
    for (std::size_t k = 0; k < s->segment_labels.size(); ++k) {
      const std::uint8_t label = s->segment_labels[k], fine = s->segment_fine_labels[k];
      if (label < kNumLabels && fine > 0 && fine <= kNyu40Classes) ++votes[label][fine];
    }
  }
  std::array<std::uint8_t, kNumLabels> out{};
  for (int label = 0; label < kNumLabels; ++label) {
    const auto& v = votes[static_cast<std::size_t>(label)];
    const auto best = std::max_element(v.begin() + 1, v.end());
    if (*best > 0) out[static_cast<std::size_t>(label)] = static_cast<std::uint8_t>(best - v.begin());
  }
  return out;
}

std::array<long, kNumLabels> labelledPatchCounts(const std::vector<const FrameSample*>& labelled) {
  std::array<long, kNumLabels> out{};
  for (const FrameSample* s : labelled)
    for (const std::uint8_t label : s->segment_labels)
      if (label < kNumLabels) ++out[label];
  return out;
}

}  // namespace

std::vector<FrameSample> pseudoLabelledSamples(const std::vector<FrameSample>& unlabelled,
                                               const std::vector<SampleLabelling>& labellings,
                                               const std::vector<const FrameSample*>& labelled,
                                               const SegmenterConfig& config,
                                               const TrainingOptions& t, PseudoLabelRound& round) {
  if (labellings.size() != unlabelled.size())
    throw Error("pseudoLabelledSamples: " + std::to_string(labellings.size()) + " labellings for " +
                std::to_string(unlabelled.size()) + " frames");
  const bool internal = config.learner.classes != ClassScheme::Labels;
  const std::array<std::uint8_t, kNumLabels> fine_of = dominantFineClasses(labelled);
  // Candidates per label: (confidence, frame, segment), most confident first;
  // frame and segment order break ties, so the choice does not depend on the sort.
  std::array<std::vector<std::tuple<float, std::size_t, std::size_t>>, kNumLabels> candidates;
  round.confident.fill(0);
  round.kept.fill(0);
  round.frames.clear();
  for (std::size_t f = 0; f < unlabelled.size(); ++f) {
    const MrfResult& m = labellings[f].mrf;
    const std::size_t n = unlabelled[f].segment_pixels.size();
    if (m.labels.size() != n || m.confidence.size() != n)
      throw Error("pseudoLabelledSamples: frame " + unlabelled[f].name + " has " +
                  std::to_string(n) + " segments but " + std::to_string(m.labels.size()) +
                  " labels");
    for (std::size_t k = 0; k < n; ++k) {
      const std::uint8_t label = m.labels[k];
      if (label >= kNumLabels || !(m.confidence[k] > t.pseudo_min_confidence)) continue;
      if (internal && fine_of[label] == 0) continue;
      ++round.confident[label];
      candidates[label].emplace_back(m.confidence[k], f, k);
    }
  }
  const std::array<long, kNumLabels> labelled_count = labelledPatchCounts(labelled);
  std::vector<std::vector<std::uint8_t>> kept(unlabelled.size());
  for (std::size_t f = 0; f < unlabelled.size(); ++f)
    kept[f].assign(unlabelled[f].segment_pixels.size(), kVoidLabel);
  for (int label = 0; label < kNumLabels; ++label) {
    auto& c = candidates[static_cast<std::size_t>(label)];
    std::sort(c.begin(), c.end(), [](const auto& a, const auto& b) {
      if (std::get<0>(a) != std::get<0>(b)) return std::get<0>(a) > std::get<0>(b);
      return std::make_pair(std::get<1>(a), std::get<2>(a)) <
             std::make_pair(std::get<1>(b), std::get<2>(b));
    });
    const double cap = std::floor(static_cast<double>(t.pseudo_class_cap) *
                                  static_cast<double>(labelled_count[static_cast<std::size_t>(label)]));
    const std::size_t keep = std::min(c.size(), static_cast<std::size_t>(cap));
    for (std::size_t i = 0; i < keep; ++i)
      kept[std::get<1>(c[i])][std::get<2>(c[i])] = static_cast<std::uint8_t>(label);
    round.kept[static_cast<std::size_t>(label)] = static_cast<int>(keep);
  }
  std::vector<FrameSample> out;
  for (std::size_t f = 0; f < unlabelled.size(); ++f) {
    const auto& labels = kept[f];
    if (std::all_of(labels.begin(), labels.end(), [](std::uint8_t l) { return l == kVoidLabel; }))
      continue;
    const FrameSample& u = unlabelled[f];
    FrameSample p;
    p.name = u.name + "~pseudo";
    p.source_index = u.source_index;
    p.width = u.width;
    p.height = u.height;
    p.edges = u.edges;
    p.features = u.features;
    p.segment_pixels = u.segment_pixels;
    p.segment_labels = labels;
    if (internal) {
      p.segment_fine_labels.assign(labels.size(), 0);
      for (std::size_t k = 0; k < labels.size(); ++k)
        if (labels[k] < kNumLabels) p.segment_fine_labels[k] = fine_of[labels[k]];
    }
    p.ground_method = u.ground_method;
    p.training_weight = t.pseudo_weight;
    round.frames.push_back(u.name);
    out.push_back(std::move(p));
  }
  return out;
}

RandomForest trainModelWithPseudoLabels(
    const std::vector<const FrameSample*>& labelled, const std::vector<FrameSample>& unlabelled,
    const SegmenterConfig& config, const TrainingOptions& training, PseudoLabelReport* report, const std::function<void(int, const RandomForest&)>& after_round) {
  RandomForest model = trainModel(labelled, config, training);
  if (after_round) after_round(0, model);
  if (report) {
    report->pool.clear();
    report->rounds.clear();
    for (const FrameSample& u : unlabelled) report->pool.push_back(u.name);
  }
  if (unlabelled.empty()) return model;
  std::vector<RegionFeatures> regions;
  if (config.regions.enabled && config.tables.region_vote)
    for (const FrameSample& u : unlabelled) regions.push_back(sampleRegionFeatures(u, config.regions));
  for (int r = 1; r <= training.pseudo_rounds; ++r) {
    std::vector<SampleLabelling> labellings;
    labellings.reserve(unlabelled.size());
    for (std::size_t f = 0; f < unlabelled.size(); ++f)
      labellings.push_back(labelSample(model, unlabelled[f], config,
                                       regions.empty() ? nullptr : &regions[f]));
    PseudoLabelRound round;
    round.round = r;
    const std::vector<FrameSample> pseudo =
        pseudoLabelledSamples(unlabelled, labellings, labelled, config, training, round);
    std::vector<const FrameSample*> frames = labelled;
    for (const FrameSample& p : pseudo) frames.push_back(&p);
    model = trainModel(frames, config, training);
    if (report) report->rounds.push_back(std::move(round));
    if (after_round) after_round(r, model);
  }
  return model;
}

SegmenterConfig unlabelledExtractionConfig(SegmenterConfig config) {
  config.ground.reestimate_every_frames = 1;
  // No labels, so no labelled floor: the floor is found in the frame itself.
  if (config.ground.source == GroundSource::FloorLabels)
    config.ground.source = GroundSource::Estimated;
  return config;
}

std::string formatPseudoLabelReport(const PseudoLabelReport& report) {
  std::ostringstream out;
  for (const PseudoLabelRound& r : report.rounds) {
    int confident = 0;
    for (int c : r.confident) confident += c;
    out << "round " << r.round << ": " << r.keptTotal() << " patches kept of " << confident
        << " confident (";
    for (int label = 0; label < kNumLabels; ++label) {
      out << (label ? ", " : "") << kLabelNames[static_cast<std::size_t>(label)] << " "
          << r.kept[static_cast<std::size_t>(label)];
    }
    out << ") from " << r.frames.size() << " of " << report.pool.size() << " frames\n";
  }
  return out.str();
}

}  // namespace findmug
