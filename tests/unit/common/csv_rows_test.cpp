// The one reader of small CSV files with a header (src/common/csv_rows.hpp): label
// mappings, per-frame extrinsics and gravity, and the NYU-894 -> 40 table all go through it.
#include "common/csv_rows.hpp"

#include <gtest/gtest.h>

#include <string>

#include "expect_error.hpp"

namespace findmug::detail {
namespace {

TEST(CsvRows, SkipsCommentsAndBlankLinesAndTrimsFieldsAndNamesTheirLines) {
  const auto rows =
      readCsvRows("# a comment\n\nid, name\r\n 1 ,wall\n# more\n2,floor \n", "m.csv", "id,name");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].where, "m.csv:4");
  EXPECT_EQ(rows[0].fields, (std::vector<std::string>{"1", "wall"}));
  EXPECT_EQ(rows[1].where, "m.csv:6");
  EXPECT_EQ(rows[1].fields, (std::vector<std::string>{"2", "floor"}));
}

TEST(CsvRows, AStarColumnTakesAnyNameTheOthersMustMatch) {
  EXPECT_EQ(readCsvRows("a,whatever,c\n1,2,3\n", "f", "a,*,c").size(), 1u);
  EXPECT_CONTAINS(test::errorOf([] { readCsvRows("a,b,d\n", "f", "a,*,c"); }),
                  "f:1: expected header 'a,*,c', found 'a,b,d'");
  EXPECT_CONTAINS(test::errorOf([] { readCsvRows("a,b\n", "f", "a,*,c"); }),
                  "f:1: expected header");
}

TEST(CsvRows, ARowWithAnotherFieldCountIsRefusedWithItsLine) {
  EXPECT_CONTAINS(test::errorOf([] { readCsvRows("a,b\n1,2\n1,2,3\n", "f.csv", "a,b"); }),
                  "f.csv:3: expected 2 fields, found 3");
  EXPECT_CONTAINS(test::errorOf([] { readCsvRows("a,b\n1\n", "f.csv", "a,b"); }),
                  "f.csv:2: expected 2 fields, found 1");
}

TEST(CsvRows, NoHeaderAtAllIsAnEmptyFile) {
  EXPECT_CONTAINS(test::errorOf([] { readCsvRows("", "e.csv", "a,b"); }),
                  "e.csv: empty (expected header 'a,b')");
  EXPECT_CONTAINS(test::errorOf([] { readCsvRows("# only\n\n", "e.csv", "a,b"); }), "e.csv: empty");
  EXPECT_TRUE(readCsvRows("a,b\n", "e.csv", "a,b").empty());
}

}  // namespace
}  // namespace findmug::detail
