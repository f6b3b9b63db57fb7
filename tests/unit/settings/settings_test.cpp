// The settings mechanism (findmug/settings/settings.hpp): tables of named settings,
// the registry of config sections, and the core's table_map section.
#include "findmug/settings/settings.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "findmug/common/error.hpp"
#include "findmug/settings/config.hpp"

namespace findmug {
namespace {

using ::testing::HasSubstr;

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

struct Owned {
  int count = 2;
  double rate = 0.5;
  bool on = false;
  std::string name = "x";
};

SettingsTable<Owned> ownedTable(const std::string& section) {
  SettingsTable<Owned> t(section);
  t.add(integerSetting<Owned, int>(
      section + ".count", [](Owned& o) -> int& { return o.count; }, 1, 10));
  t.add(numberSetting<Owned, double>(
      section + ".rate", [](Owned& o) -> double& { return o.rate; }, 0, 1));
  t.add(boolSetting<Owned>(section + ".on", [](Owned& o) -> bool& { return o.on; }));
  t.add(textSetting<Owned>(
      section + ".name", [](Owned& o) -> std::string& { return o.name; },
      [](const std::string& v) { return v.empty() ? "a name" : ""; }));
  return t;
}

TEST(SettingsTable, ParsesPrintsAndNamesTheKey) {
  const auto table = ownedTable("owned");
  Owned o;
  table.set(o, "owned.count", "7");
  table.set(o, "owned.rate", "0.25");
  table.set(o, "owned.on", "yes");
  table.set(o, "owned.name", "mug");
  EXPECT_EQ(o.count, 7);
  EXPECT_DOUBLE_EQ(o.rate, 0.25);
  EXPECT_TRUE(o.on);
  EXPECT_EQ(o.name, "mug");
  const auto values = table.values(o);
  EXPECT_EQ(values.at("owned.count"), "7");
  EXPECT_EQ(values.at("owned.rate"), "0.25");
  EXPECT_EQ(values.at("owned.on"), "true");
  EXPECT_EQ(values.at("owned.name"), "mug");

  EXPECT_EQ(errorOf([&] { table.set(o, "owned.cuont", "1"); }),
            "unknown setting 'owned.cuont' (owned keys: owned.count, owned.name, owned.on, "
            "owned.rate)");
  EXPECT_EQ(errorOf([&] { table.set(o, "owned.count", "11"); }),
            "invalid value '11' for owned.count (expected an integer in [1, 10])");
  EXPECT_EQ(errorOf([&] { table.set(o, "owned.rate", "nan"); }),
            "invalid value 'nan' for owned.rate (expected a number in [0, 1])");
  EXPECT_THAT(errorOf([&] { table.set(o, "owned.on", "maybe"); }), HasSubstr("true or false"));
  EXPECT_THAT(errorOf([&] { table.set(o, "owned.name", ""); }), HasSubstr("a name"));
  EXPECT_EQ(o.count, 7);  // a refused value leaves the field alone
}

TEST(SettingsTable, DuplicateAndForeignKeysAreRefused) {
  auto table = ownedTable("owned");
  EXPECT_THAT(errorOf([&] {
                table.add(integerSetting<Owned, int>(
                    "owned.count", [](Owned& o) -> int& { return o.count; }, 0, 1));
              }),
              HasSubstr("'owned.count' registered twice"));
  EXPECT_THAT(errorOf([&] {
                table.add(integerSetting<Owned, int>(
                    "other.count", [](Owned& o) -> int& { return o.count; }, 0, 1));
              }),
              HasSubstr("does not belong to section 'owned'"));
}

TEST(ConfigSections, SecondOwnerRefusedNameOnlyUpgradedAndIdempotent) {
  ConfigSections sections;
  const auto table = ownedTable("a");
  auto check = [&table](const std::string& k, const std::string& v) { table.check(k, v); };
  sections.addSectionName("a");
  sections.addSectionName("a");
  sections.check("a", "a.anything", "goes");  // known by name only: unchecked
  sections.addSection("a", check);            // its owner brings the keys
  EXPECT_THAT(errorOf([&] { sections.check("a", "a.anything", "goes"); }),
              HasSubstr("unknown setting 'a.anything'"));
  EXPECT_THAT(errorOf([&] { sections.addSection("a", check); }), HasSubstr("'a' registered twice"));
  sections.addSectionName("a");  // a name-only declaration keeps the owner's check
  EXPECT_THAT(errorOf([&] { sections.check("a", "a.count", "0"); }), HasSubstr("a.count"));
  EXPECT_THAT(errorOf([&] { sections.check("b", "b.x", "1"); }),
              HasSubstr("unknown setting 'b.x'"));
}

// The process-wide registry as parseConfig and applyOverride use it.
TEST(ConfigSections, ParseConfigChecksOwnedSectionsAndKeepsNameOnlyOnes) {
  static const auto owned = ownedTable("settings_test_owned");
  configSections().addSection(
      "settings_test_owned", [](const std::string& k, const std::string& v) { owned.check(k, v); });
  configSections().addSectionName("settings_test_other");

  Config c = parseConfig("settings_test_owned:\n  count: 4\nsettings_test_other:\n  whatever: 1\n",
                         "own.yaml");
  EXPECT_EQ(c.extra.at("settings_test_owned.count"), "4");
  EXPECT_EQ(c.extra.at("settings_test_other.whatever"), "1");  // kept for its owner
  applyOverride(c, "settings_test_owned.rate=0.75");
  EXPECT_EQ(c.extra.at("settings_test_owned.rate"), "0.75");

  EXPECT_EQ(errorOf([] { parseConfig("settings_test_owned:\n  cuont: 4\n", "own.yaml"); }),
            "own.yaml: unknown setting 'settings_test_owned.cuont' (settings_test_owned keys: "
            "settings_test_owned.count, settings_test_owned.name, settings_test_owned.on, "
            "settings_test_owned.rate)");
  EXPECT_EQ(errorOf([&] { applyOverride(c, "settings_test_owned.count=99"); }),
            "<flags>: invalid value '99' for settings_test_owned.count (expected an integer in "
            "[1, 10])");
  EXPECT_EQ(errorOf([] { parseConfig("never_registered:\n  x: 1\n", "own.yaml"); }),
            "own.yaml: unknown setting 'never_registered.x'");
}

TEST(TableMapSettings, TheCoreParsesValidatesAndWritesBackItsSection) {
  Config c = parseConfig("table_map:\n  confirm_sightings: 5\n  match_gap_m: 0.25\n", "map.yaml");
  const TableMapConfig m = resolveTableMapConfig(c);
  EXPECT_EQ(m.confirm_sightings, 5);
  EXPECT_FLOAT_EQ(m.match_gap_m, 0.25f);
  EXPECT_EQ(m.forget_misses, TableMapConfig{}.forget_misses);
  EXPECT_EQ(c.extra.at("table_map.forget_misses"), "3");  // every key written back
  EXPECT_EQ(c.extra.at("table_map.view_max_range_m"), "4");
  EXPECT_EQ(c.extra.at("table_map.match_height_m"), "0.15");  // the float's shortest text
  EXPECT_EQ(tableMapSettings().settings().size(), 10u);

  EXPECT_THAT(errorOf([] { parseConfig("table_map:\n  no_such_key: 1\n", "map.yaml"); }),
              HasSubstr("map.yaml: unknown setting 'table_map.no_such_key' (table_map keys: "));
  EXPECT_THAT(errorOf([] { parseConfig("table_map:\n  confirm_sightings: 0\n", "map.yaml"); }),
              HasSubstr("'0' for table_map.confirm_sightings"));
  // Consistency across keys is checked when the section is resolved.
  Config inconsistent = parseConfig("table_map:\n  view_max_range_m: 0.5\n", "map.yaml");
  EXPECT_THAT(errorOf([&] { resolveTableMapConfig(inconsistent); }),
              HasSubstr("table_map.view_max_range_m"));
}

}  // namespace
}  // namespace findmug
