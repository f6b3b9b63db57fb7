// type_layout.cpp — the library's own view of its types' layouts (type_layout.hpp).
#include "segmenter/type_layout.hpp"

namespace findmug::detail {

std::vector<TypeLayout> coreTypeLayouts() { return typeLayoutsHere(); }

}  // namespace findmug::detail
