// shipped_model.hpp — the shipped model (models/findmug.fmf) with the settings it was
// trained with (daemon/findmugd.yaml's stages), and a folder of NYU frames to run it on,
// for the tests that check a stage on real frames.
#pragma once

#include <memory>
#include <string>

#include "findmug/frame/dataset.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/settings/config.hpp"
#include "test_data.hpp"

namespace findmug::test {

inline std::shared_ptr<const RandomForest> shippedModel() {
  return std::make_shared<const RandomForest>(
      RandomForest::load((sourceDir() / "models" / "findmug.fmf").string()));
}

// The settings a program needs to accept the shipped model, on one thread.
inline Config shippedModelConfig() {
  Config config;
  for (const char* kv : {"features.regions=true", "features.scene=true", "learner.classes=nyu13",
                         "features.objects=true", "features.objects_columns=relations",
                         "learner.num_threads=1"})
    applyOverride(config, kv);
  return config;
}

// A dataset folder read for its frames (labels not needed).
inline DatasetFolder framesOf(const std::string& folder) {
  DatasetOptions options;
  options.require_labels = false;
  return DatasetFolder(folder, options);
}

}  // namespace findmug::test
