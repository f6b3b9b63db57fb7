// The distance between two object colour histograms (table_objects.hpp): what
// the object map and the taught-object matcher compare colours with.
#include <algorithm>
#include <cmath>

#include "findmug/objects/table_objects.hpp"

namespace findmug {

float colourHistogramDistance(const ObjectColourHistogram& a, const ObjectColourHistogram& b) {
  double coefficient = 0.0;
  for (int i = 0; i < kObjectColourBins; ++i) {
    coefficient += std::sqrt(std::max(0.0, static_cast<double>(a[i]) * b[i]));
  }
  return static_cast<float>(std::clamp(1.0 - coefficient, 0.0, 1.0));
}

}  // namespace findmug
