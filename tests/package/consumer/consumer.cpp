// Uses the core library (a label name, the table extraction types) and the generated
// LCM types from the installed findmug-dev package; prints what it found so that the
// package test can check that both really linked and ran.
#include <findmug/frame/dataset.hpp>
#include <findmug/labels/labels.hpp>
#include <findmug/version.hpp>
#include <findmug_lcm/tables_t.hpp>
#include <iostream>
#include <vector>

int main() {
  findmug_lcm::tables_t tables{};
  tables.num_tables = 0;
  const int size = tables.getEncodedSize();
  std::vector<unsigned char> buffer(static_cast<std::size_t>(size));
  const int written = tables.encode(buffer.data(), 0, size);
  // defaultNyu40Mapping() lives in libfindmug_core.so: NYU-40 id 7 is "table".
  const int table = findmug::defaultNyu40Mapping().to_findmug[7];
  std::cout << "findmug " << findmug::kVersion << " nyu40_7=" << findmug::labelName(table)
            << " tables_t bytes=" << written << "\n";
  return written == size ? 0 : 1;
}
