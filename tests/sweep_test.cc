// Studies (script/sweep.h) and script variables (script/variables.h): values fill ${NAME} words,
// defaults make the script run alone, grids and lists give the cases, a failing case is a row,
// and the table does not depend on the number of threads.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "wobble/core/errors.h"
#include "wobble/formats/csv.h"
#include "wobble/formats/parse_error.h"
#include "wobble/script/interpreter.h"
#include "wobble/script/sweep.h"
#include "wobble/script/variables.h"
#include "support/source_paths.h"

namespace wobble::script {
namespace {

const std::string kData = wobble::test_env::DataDir();

TEST(Variables, ValuesThenDefaultsFillTheWords) {
  const std::string text = "set dt ${dt}\nset seed ${seed:-4}\n# ${unused:-x} in a comment too\n";
  EXPECT_EQ(ExpandVariables(text, {{"dt", "0.01"}}, "s.wob"), "set dt 0.01\nset seed 4\n# x in a comment too\n");
  EXPECT_EQ(ExpandVariables(text, {{"dt", "0.02"}, {"seed", "9"}}, "s.wob"), "set dt 0.02\nset seed 9\n# x in a comment too\n");
  EXPECT_EQ(VariablesUsed(text, "s.wob"), (std::set<std::string>{"dt", "seed", "unused"}));
  EXPECT_EQ(ExpandVariables("cost $5 and ${a:-}", {}, "s.wob"), "cost $5 and ");  // a lone $ stays
}

TEST(Variables, AMissingValueOrBrokenReferenceNamesTheLine) {
  try {
    ExpandVariables("set dt 0.01\nset seed ${seed}\n", {}, "study.wob");
    FAIL();
  } catch (const formats::ParseError& e) {
    EXPECT_EQ(e.line(), 2);
    EXPECT_NE(e.message().find("${seed} has no value"), std::string::npos) << e.what();
  }
  try {
    ExpandVariables("a\nb\nset dt ${dt\n", {}, "study.wob");
    FAIL();
  } catch (const formats::ParseError& e) {
    EXPECT_EQ(e.line(), 3);
  }
  EXPECT_THROW(ExpandVariables("set dt ${2x}\n", {}, "s.wob"), formats::ParseError);
  EXPECT_THROW(ExpandVariables("set dt ${}\n", {}, "s.wob"), formats::ParseError);
}

TEST(SweepPlan, ListsRangesAndGridsInCaseOrder) {
  EXPECT_EQ(ParseSweepParameter("frsin=0.3,0.5").values, (std::vector<std::string>{"0.3", "0.5"}));
  EXPECT_EQ(ParseSweepParameter("seed=1:4:4").values, (std::vector<std::string>{"1", "2", "3", "4"}));
  EXPECT_EQ(ParseSweepParameter("k=1e3:1e5:3:log").values, (std::vector<std::string>{"1e3", "10000", "1e5"}));
  EXPECT_EQ(ParseSweepParameter("x=2:9:1").values, (std::vector<std::string>{"2"}));
  const std::vector<std::string> seeds = ParseSweepParameter("seed=1:200:200").values;  // whole steps stay whole
  for (size_t i = 0; i < seeds.size(); ++i) EXPECT_EQ(seeds[i], std::to_string(i + 1));
  for (const char* bad : {"seed", "=1,2", "seed=", "seed=1:2", "seed=1:2:0", "seed=1:2:x", "k=0:1:3:log",
                          "k=1:2:3:lin", "a-b=1", "seed=1,,2"})
    EXPECT_THROW(ParseSweepParameter(bad), InputError) << bad;
  const SweepPlan grid = GridPlan({ParseSweepParameter("a=1,2"), ParseSweepParameter("b=x,y,z")});
  ASSERT_EQ(grid.cases.size(), 6u);
  EXPECT_EQ(grid.cases[0], (std::vector<std::string>{"1", "x"}));
  EXPECT_EQ(grid.cases[2], (std::vector<std::string>{"1", "z"}));
  EXPECT_EQ(grid.cases[3], (std::vector<std::string>{"2", "x"}));
  EXPECT_THROW(GridPlan({ParseSweepParameter("a=1,2"), ParseSweepParameter("a=3")}), InputError);
  EXPECT_THROW(GridPlan({ParseSweepParameter("a=1:2:10000"), ParseSweepParameter("b=1:2:10000")}), LimitExceeded);
}

TEST(SweepPlan, ACaseListIsReadWithFileAndLine) {
  const auto dir = std::filesystem::temp_directory_path() / "wobble_sweep_list";
  std::filesystem::create_directories(dir);
  const std::string good = (dir / "good.csv").string(), bad = (dir / "bad.csv").string();
  std::ofstream(good) << "seed, frsin\n# a comment\n1,0.3\n2, 0.5\n";
  std::ofstream(bad) << "seed,frsin\n1,0.3\n2\n";
  const SweepPlan plan = ReadCaseList(good);
  EXPECT_EQ(plan.names, (std::vector<std::string>{"seed", "frsin"}));
  ASSERT_EQ(plan.cases.size(), 2u);
  EXPECT_EQ(plan.cases[1], (std::vector<std::string>{"2", "0.5"}));
  try {
    ReadCaseList(bad);
    FAIL();
  } catch (const formats::ParseError& e) {
    EXPECT_EQ(e.line(), 3);
    EXPECT_NE(e.message().find("expected 2 values"), std::string::npos) << e.what();
  }
}

// A short study of the bounding table: seeds and ground friction, one case with a value the
// script refuses.
SweepOptions ShortStudy(int threads) {
  SweepOptions o;
  o.script = kData + "/sweep_bounding.wob";
  o.plan = GridPlan({ParseSweepParameter("seed=1,2"), ParseSweepParameter("frsin=0.5,-1")});
  o.plan.cases.push_back({"3", "0.8"});
  o.measures = {"cost", "trials", "distance", "state", "time"};
  o.threads = threads;
  return o;
}

TEST(Sweep, EveryCaseIsARowAndTheTableDoesNotDependOnTheThreads) {
  SweepOptions o = ShortStudy(1);
  // the script's own words: a short anneal, so the test stays quick
  o.plan.names.push_back("iterations");
  o.plan.names.push_back("trial_steps");
  for (auto& c : o.plan.cases) c.push_back("2"), c.push_back("300");
  const SweepTable one = RunSweep(o);
  o.threads = 2;
  const SweepTable two = RunSweep(o);
  EXPECT_EQ(one.header, two.header);
  EXPECT_EQ(one.rows, two.rows);
  EXPECT_EQ(one.header, (std::vector<std::string>{"case", "seed", "frsin", "iterations", "trial_steps", "status", "cost",
                                                  "trials", "distance", "q", "qd", "time", "message"}));
  ASSERT_EQ(one.rows.size(), 5u);
  for (size_t i = 0; i < one.rows.size(); ++i) {
    EXPECT_EQ(one.rows[i][0], std::to_string(i));
    EXPECT_EQ(one.rows[i].size(), one.header.size()) << "row " << i;  // failed cases too
  }
  // frsin -1 is refused by `set`: that case is a row saying so, with the script's line
  EXPECT_EQ(one.rows[1][5], "bad input");
  EXPECT_NE(one.rows[1].back().find("sweep_bounding.wob:"), std::string::npos) << one.rows[1].back();
  EXPECT_EQ(one.rows[1][6], "");
  for (size_t i : {0u, 2u, 4u}) {
    EXPECT_EQ(one.rows[i][5], kCaseOk) << one.rows[i].back();
    EXPECT_EQ(one.rows[i][7], "17");  // 1 + 2 iterations x batch 8
    EXPECT_FALSE(one.rows[i][6].empty());
    EXPECT_FALSE(one.rows[i][8].empty());
  }
  // a case equals the script run alone with the same values: the anneal's best cost
  std::ostringstream out;
  Interpreter interp(out);
  std::istringstream in(ExpandVariables(
      [&] {
        std::ifstream f(o.script);
        std::stringstream all;
        all << f.rdbuf();
        return all.str();
      }(),
      {{"seed", "2"}, {"frsin", "0.5"}, {"iterations", "2"}, {"trial_steps", "300"}}, o.script));
  interp.RunStream(in, o.script, kData);
  EXPECT_EQ(one.rows[2][6], formats::FormatDouble(interp.last_anneal()->best_outcome.cost));
}

TEST(Sweep, RefusesAParameterTheScriptDoesNotUseAndAnUnknownMeasure) {
  SweepOptions o = ShortStudy(1);
  o.plan = GridPlan({ParseSweepParameter("gravity=1,2")});
  EXPECT_THROW(RunSweep(o), InputError);
  o = ShortStudy(1);
  o.measures = {"speed"};
  EXPECT_THROW(RunSweep(o), InputError);
}

}  // namespace
}  // namespace wobble::script
