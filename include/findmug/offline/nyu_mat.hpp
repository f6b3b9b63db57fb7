// findmug/offline/nyu_mat.hpp — the official NYU Depth V2 labelled .mat file as a source
// of labelled frames (findmug-train and findmug-eval `--mat`, findmug-import).
//
// Offline: it needs HDF5, which the daemon does not link.
#pragma once

#include <cstddef>
#include <string>

#include "findmug/frame/dataset.hpp"

namespace findmug {

// Reads the official nyu_depth_v2_labeled.mat (MATLAB v7.3 = HDF5):
// `images` (3x640x480 uint8), `depths` (640x480 float metres), `labels`
// (640x480 uint16 NYU-894 ids), mapped 894 -> 40 (CSV with columns
// nyu894_id,name,nyu40_id,nyu40_name, read at run time) -> 8 (the shipped
// mapping). MATLAB is column-major, so HDF5 sees N x 3 x W x H etc.; frames
// come out row-major like every other frame. Depth becomes uint16 mm. The NYU
// border is NOT masked here (DatasetFolder does that when reading). Frame
// names are the 1-based NYU index, 4 digits ("0001").
class NyuMatFile {
 public:
  explicit NyuMatFile(const std::string& path,
                      const std::string& nyu894_to_40_csv = defaultNyu894To40CsvPath());
  ~NyuMatFile();
  NyuMatFile(const NyuMatFile&) = delete;
  NyuMatFile& operator=(const NyuMatFile&) = delete;
  std::size_t size() const;
  LabeledFrame load(std::size_t index0) const;  // 0-based
 private:
  struct Impl;
  Impl* impl_;
};

}  // namespace findmug
