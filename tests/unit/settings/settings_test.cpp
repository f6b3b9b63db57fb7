// The settings mechanism (findmug/settings/settings.hpp): tables of named settings,
// the schema a program reads its file through, and the core's table_map section.
#include "findmug/settings/settings.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "findmug/common/error.hpp"
#include "findmug/map/table_map.hpp"
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

// A schema: the tables a program states, each bound to its struct; values go straight
// into the typed fields, an unknown section or key is refused with its name and line.
TEST(SettingsSchema, ReadsEachValueOnceIntoItsBoundField) {
  const auto table = ownedTable("owned");
  Owned owned;
  SettingsSchema schema;
  schema.bind(table, owned);
  schema.readYaml("owned:\n  count: 4\n  name: mug\n", "own.yaml");
  EXPECT_EQ(owned.count, 4);  // no resolve step: the field holds the value
  EXPECT_EQ(owned.name, "mug");
  schema.applyOverride("owned.rate=0.75");
  EXPECT_DOUBLE_EQ(owned.rate, 0.75);
  EXPECT_EQ(schema.dump(), "owned:\n  count: 4\n  rate: 0.75\n  on: false\n  name: mug\n");

  EXPECT_EQ(errorOf([&] { schema.readYaml("owned:\n  count: 4\n  cuont: 4\n", "own.yaml"); }),
            "own.yaml: line 3: unknown setting 'owned.cuont' (owned keys: owned.count, "
            "owned.name, owned.on, owned.rate)");
  EXPECT_EQ(errorOf([&] { schema.applyOverride("owned.count=99"); }),
            "<flags>: invalid value '99' for owned.count (expected an integer in [1, 10])");
  EXPECT_EQ(errorOf([&] { schema.readYaml("never_bound:\n  x: 1\n", "own.yaml"); }),
            "own.yaml: line 2: unknown setting 'never_bound.x': no section 'never_bound' "
            "(sections: owned)");
  EXPECT_THAT(errorOf([&] { schema.applyOverride("owned.count"); }), HasSubstr("key=value"));
  EXPECT_THAT(errorOf([&] { schema.applyOverride("bogus=1"); }), HasSubstr("section.name"));
  EXPECT_EQ(owned.count, 4);  // refused values leave the fields alone
}

TEST(SettingsSchema, AcceptedSectionsAreCheckedButNotDumpedAndNoSectionIsBoundTwice) {
  const auto mine = ownedTable("mine");
  const auto theirs = ownedTable("theirs");
  Owned owned;
  SettingsSchema schema;
  schema.bind(mine, owned);
  schema.accept(theirs);  // another program's section in the same file
  schema.readYaml("theirs:\n  count: 9\nmine:\n  count: 3\n", "shared.yaml");
  EXPECT_EQ(owned.count, 3);
  EXPECT_THAT(errorOf([&] { schema.readYaml("theirs:\n  count: 11\n", "shared.yaml"); }),
              HasSubstr("shared.yaml: line 2: invalid value '11' for theirs.count"));
  EXPECT_THAT(errorOf([&] { schema.readYaml("theirs:\n  cnt: 1\n", "shared.yaml"); }),
              HasSubstr("unknown setting 'theirs.cnt'"));
  EXPECT_EQ(schema.dump().find("theirs"), std::string::npos);
  EXPECT_THAT(errorOf([&] { schema.bind(theirs, owned); }),
              HasSubstr("section 'theirs' bound twice"));
}

TEST(SettingsSchema, ValidateRunsTheCrossKeyRulesWithTheOrigin) {
  const auto table = ownedTable("owned");
  Owned owned;
  SettingsSchema schema;
  schema.bind(table, owned, [](const Owned& o) {
    if (o.on && o.count < 5) throw Error("owned.on needs owned.count >= 5");
  });
  schema.readYaml("owned:\n  on: true\n", "own.yaml");
  EXPECT_EQ(errorOf([&] { schema.validate("own.yaml"); }),
            "own.yaml: owned.on needs owned.count >= 5");
  schema.applyOverride("owned.count=5");
  EXPECT_NO_THROW(schema.validate("own.yaml + flags"));
}

TEST(TableMapSettings, TheCoreTableParsesAndValidatesItsSection) {
  TableMapConfig m;
  SettingsSchema schema;
  schema.bind(tableMapSettings(), m, validateTableMapConfig);
  schema.readYaml("table_map:\n  confirm_sightings: 5\n  match_gap_m: 0.25\n", "map.yaml");
  EXPECT_EQ(m.confirm_sightings, 5);
  EXPECT_FLOAT_EQ(m.match_gap_m, 0.25f);
  EXPECT_EQ(m.forget_misses, TableMapConfig{}.forget_misses);
  const auto values = tableMapSettings().values(m);
  EXPECT_EQ(values.at("table_map.forget_misses"), "3");
  EXPECT_EQ(values.at("table_map.view_max_range_m"), "4");
  EXPECT_EQ(values.at("table_map.match_height_m"), "0.15");  // the float's shortest text
  EXPECT_EQ(tableMapSettings().settings().size(), 11u);

  EXPECT_THAT(errorOf([&] { schema.readYaml("table_map:\n  no_such_key: 1\n", "map.yaml"); }),
              HasSubstr("map.yaml: line 2: unknown setting 'table_map.no_such_key' (table_map keys: "));
  EXPECT_THAT(errorOf([&] { schema.readYaml("table_map:\n  confirm_sightings: 0\n", "map.yaml"); }),
              HasSubstr("'0' for table_map.confirm_sightings"));
  // Consistency across keys is checked once everything is read.
  schema.readYaml("table_map:\n  view_max_range_m: 0.5\n", "map.yaml");
  EXPECT_THAT(errorOf([&] { schema.validate("map.yaml"); }),
              HasSubstr("map.yaml: table_map.view_max_range_m"));
}

// The segmenter's struct spans several sections: one table, each key's own section
// named when a key is unknown.
TEST(SettingsTable, SeveralSectionsNameTheKeysOfTheOneAsked) {
  const auto& table = segmenterSettings();
  EXPECT_TRUE(table.holds("forest"));
  EXPECT_TRUE(table.holds("mrf"));
  EXPECT_FALSE(table.holds("daemon"));
  SegmenterConfig c;
  const std::string msg = errorOf([&] { table.set(c, "mrf.lamda", "1"); });
  EXPECT_THAT(msg, HasSubstr("unknown setting 'mrf.lamda' (mrf keys: "));
  EXPECT_THAT(msg, HasSubstr("mrf.lambda"));
  EXPECT_EQ(msg.find("forest."), std::string::npos) << msg;
}

// A renamed key (renamedSettings): the old name is read as the new one with a
// warning naming the new key, and one file or the flags giving both is refused.
TEST(SettingsSchema, OldKeyNamesAreReadAsTheNewOnesWithAWarning) {
  EXPECT_EQ(currentSettingKey("overseg.seed_resolution_m"), "oversegmentation.seed_resolution_m");
  EXPECT_EQ(currentSettingKey("oversegmentation.method"), "oversegmentation.method");
  EXPECT_EQ(currentSettingKey("oversegx.method"), "oversegx.method");
  EXPECT_EQ(currentSettingKey("mrf.lambda"), "mrf.lambda");

  Config by_old, by_new;
  std::vector<std::string> warnings;
  SettingsSchema old_schema, new_schema;
  old_schema.onWarning([&](const std::string& w) { warnings.push_back(w); });
  new_schema.onWarning([&](const std::string& w) { warnings.push_back(w); });
  bindCoreSettings(old_schema, by_old);
  bindCoreSettings(new_schema, by_new);
  old_schema.readYaml("overseg:\n  method: pcl\n  seed_resolution_m: 0.15\n", "old.yaml");
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_THAT(warnings[0], HasSubstr("old.yaml: line 2: setting 'overseg.method' is now called "
                                     "'oversegmentation.method'"));
  EXPECT_THAT(warnings[1], HasSubstr("'oversegmentation.seed_resolution_m'"));
  new_schema.readYaml("oversegmentation:\n  method: pcl\n  seed_resolution_m: 0.15\n",
                      "new.yaml");
  EXPECT_EQ(warnings.size(), 2u);  // the new names warn of nothing
  // The same effect: the same values in the same fields.
  EXPECT_EQ(by_old.segmenter.oversegmentation.kind, OversegmenterKind::PclSupervoxels);
  EXPECT_EQ(old_schema.dump(), new_schema.dump());
  EXPECT_EQ(segmenterSettings().values(by_old.segmenter),
            segmenterSettings().values(by_new.segmenter));
  EXPECT_EQ(old_schema.dump().find("overseg:"), std::string::npos);  // printed by the new name

  // --set takes the old name too, and a later origin overrides an earlier one
  // whichever name each uses.
  old_schema.applyOverride("overseg.min_segment_points=30");
  EXPECT_EQ(by_old.segmenter.oversegmentation.min_segment_points, 30);
  EXPECT_THAT(warnings.back(), HasSubstr("<flags>: setting 'overseg.min_segment_points' is now"));
  old_schema.applyOverride("oversegmentation.method=organized");
  EXPECT_EQ(by_old.segmenter.oversegmentation.kind, OversegmenterKind::Organized);
}

TEST(SettingsSchema, BothNamesOfOneSettingAreRefusedNamingBoth) {
  Config config;
  SettingsSchema schema;
  schema.onWarning([](const std::string&) {});
  bindCoreSettings(schema, config);
  const std::string in_file = errorOf([&] {
    schema.readYaml("oversegmentation:\n  method: organized\noverseg:\n  method: pcl\n",
                    "both.yaml");
  });
  EXPECT_THAT(in_file, HasSubstr("both.yaml: line 4: setting 'oversegmentation.method' is given "
                                 "by both its names, 'oversegmentation.method' (both.yaml: line "
                                 "2) and 'overseg.method'; 'overseg.method' is its old name"));
  // Either order, and in the flags.
  SettingsSchema flags;
  flags.onWarning([](const std::string&) {});
  Config flag_config;
  bindCoreSettings(flags, flag_config);
  flags.applyOverride("overseg.seed_resolution_m=0.2");
  const std::string in_flags =
      errorOf([&] { flags.applyOverride("oversegmentation.seed_resolution_m=0.3"); });
  EXPECT_THAT(in_flags, HasSubstr("<flags>: setting 'oversegmentation.seed_resolution_m' is "
                                  "given by both its names"));
  EXPECT_THAT(in_flags, HasSubstr("'overseg.seed_resolution_m' is its old name"));
  // One name twice is not a conflict: the later value wins, as before.
  flags.applyOverride("overseg.seed_resolution_m=0.25");
  EXPECT_FLOAT_EQ(flag_config.segmenter.oversegmentation.seed_resolution_m, 0.25f);
}

// forest.class_weighting and forest.num_threads train either learner: they are
// learner.* now, the old keys read as the new ones (one key each, not a section).
TEST(SettingsSchema, TheLearnersSharedKeysAreReadByTheirOldForestNames) {
  EXPECT_EQ(currentSettingKey("forest.num_threads"), "learner.num_threads");
  EXPECT_EQ(currentSettingKey("forest.class_weighting"), "learner.class_weighting");
  EXPECT_EQ(currentSettingKey("forest.num_trees"), "forest.num_trees");  // the forest's own
  Config config;
  std::vector<std::string> warnings;
  SettingsSchema schema;
  schema.onWarning([&](const std::string& w) { warnings.push_back(w); });
  bindCoreSettings(schema, config);
  schema.readYaml("forest:\n  num_trees: 3\n  num_threads: 2\n  class_weighting: false\n",
                  "old.yaml");
  EXPECT_EQ(config.segmenter.forest.num_trees, 3);
  EXPECT_EQ(config.segmenter.forest.num_threads, 2);
  EXPECT_FALSE(config.segmenter.forest.class_weighting);
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_THAT(warnings[0], HasSubstr("'forest.num_threads' is now called 'learner.num_threads'"));
  const std::string dump = schema.dump();
  EXPECT_THAT(dump, HasSubstr("learner:\n"));
  EXPECT_THAT(dump, HasSubstr("  num_threads: 2\n"));
  EXPECT_THAT(errorOf([&] {
                schema.readYaml("learner:\n  num_threads: 1\nforest:\n  num_threads: 2\n",
                                "both.yaml");
              }),
              HasSubstr("'learner.num_threads' is given by both its names"));
}

}  // namespace
}  // namespace findmug

namespace findmug {
namespace {

// A section whose every key is commented out (daemon/findmugd.yaml's normals:, whose keys
// the model gives) reads as nothing set; a section no table knows is still refused.
TEST(SettingsSchema, AnEmptySectionSetsNothingButMustBeKnown) {
  Owned owned;
  SettingsSchema schema;
  schema.bind(ownedTable("owned"), owned);
  schema.readYaml("owned:\n  # count: 3\n", "a.yaml");
  EXPECT_EQ(owned.count, 2);
  EXPECT_THAT(errorOf([&] { schema.readYaml("owned:\nowend:\n", "a.yaml"); }),
              HasSubstr("a.yaml: line 2: unknown section 'owend'"));
}

// What --help-settings prints: key = value (what a value must be), the doc line below.
TEST(SettingsSchema, HelpListsEveryBoundAndAcceptedSetting) {
  Owned owned;
  SettingsSchema schema;
  auto table = ownedTable("owned");
  schema.bind(table, owned);
  schema.accept(ownedTable("other"));
  owned.count = 4;
  const std::string help = schema.help();
  EXPECT_THAT(help, HasSubstr("owned.count = 4  (an integer in [1, 10])\n    \n"));
  EXPECT_THAT(help, HasSubstr("owned.on = false  (true or false)\n"));
  EXPECT_THAT(help, HasSubstr("other.rate = 0.5  (a number in [0, 1])\n"));
  EXPECT_THAT(help, HasSubstr("owned.name = x  (text)\n"));
  EXPECT_LT(help.find("other.count"), help.find("owned.count"));  // sections in name order
  const auto described = schema.describe();
  ASSERT_EQ(described.size(), 8u);
  EXPECT_FALSE(described[0].recorded_in_model);
}

}  // namespace
}  // namespace findmug
