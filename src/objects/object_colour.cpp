// An object's colour (table_objects.hpp): its histogram, and the distance between two
// histograms that the object map and the taught-object matcher compare colours with.
#include <algorithm>
#include <cmath>

#include "findmug/objects/table_objects.hpp"
#include "objects/table_objects_internal.hpp"

namespace findmug {

ObjectColourHistogram objectColourHistogram(const std::vector<Rgb8>& rgb) {
  std::array<int, kObjectColourBins> counts{};
  for (const Rgb8& c : rgb) ++counts[static_cast<std::size_t>(objects_detail::colourBin(c))];
  ObjectColourHistogram out;
  objects_detail::normaliseColourCounts(counts, static_cast<int>(rgb.size()), out);
  return out;
}

float colourHistogramDistance(const ObjectColourHistogram& a, const ObjectColourHistogram& b) {
  double coefficient = 0.0;
  for (int i = 0; i < kObjectColourBins; ++i) {
    coefficient += std::sqrt(std::max(0.0, static_cast<double>(a[i]) * b[i]));
  }
  return static_cast<float>(std::clamp(1.0 - coefficient, 0.0, 1.0));
}

}  // namespace findmug
