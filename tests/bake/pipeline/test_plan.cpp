// Stage planning and the driver's contract checks, on synthetic stages (not the registry).
#include <gtest/gtest.h>

#include "bake/pipeline/driver.hpp"
#include "bake/pipeline/plan.hpp"
#include "common/error.hpp"

namespace {

using namespace clothbake;
using namespace clothbake::pipeline;

Stage make(const std::string& name, std::vector<std::string> in, std::vector<std::string> out,
           std::vector<std::string> collects = {}, bool always = false) {
  Stage s;
  s.name = name;
  s.inputs = std::move(in);
  s.outputs = std::move(out);
  s.collects = std::move(collects);
  s.always = always;
  s.run = [](StageContext& ctx) {
    int sum = 0;
    for (const auto& i : ctx.stage().inputs)
      sum += ctx.input<int>(i);
    for (const auto& prefix : ctx.stage().collects)
      for (const auto& name : ctx.collected(prefix))
        sum += ctx.input<int>(name);
    for (const auto& o : ctx.stage().outputs)
      ctx.output(o, sum + 1);
  };
  return s;
}

std::vector<std::string> names(const std::vector<const Stage*>& plan) {
  std::vector<std::string> out;
  for (const Stage* s : plan)
    out.push_back(s->name);
  return out;
}

// A diamond with a collecting sink: load -> {b, a} -> write(collects "section/").
std::vector<Stage> diamond() {
  return {make("load", {"path"}, {"fabric"}), make("b", {"fabric"}, {"section/b"}),
          make("a", {"fabric"}, {"section/a", "metadata/a"}),
          make("c", {"section/a"}, {"section/c"}),
          make("write", {"fabric"}, {"asset"}, {"section/", "metadata/"}, true)};
}

TEST(Plan, AllStagesInDependencyOrderTiesByName) {
  const auto stages = diamond();
  EXPECT_EQ(names(plan_stages(stages, {}, {"path"})),
            (std::vector<std::string>{"load", "a", "b", "c", "write"}));
}

TEST(Plan, PickedStagesPullInTheirProducersAndTheAlwaysStages) {
  const auto stages = diamond();
  EXPECT_EQ(names(plan_stages(stages, {"c"}, {"path"})),
            (std::vector<std::string>{"load", "a", "c", "write"}));
  EXPECT_EQ(names(plan_stages(stages, {"b"}, {"path"})),
            (std::vector<std::string>{"load", "b", "write"}));
}

TEST(Plan, SeededArtifactsNeedNoProducer) {
  const auto stages = diamond();
  // With "fabric" given, the loader is neither needed nor run by default.
  EXPECT_EQ(names(plan_stages(stages, {}, {"fabric"})),
            (std::vector<std::string>{"a", "b", "c", "write"}));
}

TEST(Plan, UnknownStageIsAUsageErrorListingTheKnownOnes) {
  try {
    plan_stages(diamond(), {"parallax"}, {"path"});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Usage);
    EXPECT_NE(std::string(e.what()).find("unknown stage 'parallax'"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("a, b, c, load, write"), std::string::npos) << e.what();
  }
}

TEST(Plan, MissingProducerIsNamed) {
  std::vector<Stage> stages{make("x", {"nothing"}, {"y"})};
  try {
    plan_stages(stages, {}, {});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Internal);
    EXPECT_NE(std::string(e.what()).find("stage 'x' needs artifact 'nothing'"), std::string::npos);
  }
}

TEST(Plan, CycleIsNamed) {
  std::vector<Stage> stages{make("p", {"q_out"}, {"p_out"}), make("q", {"p_out"}, {"q_out"}),
                            make("free", {}, {"free_out"})};
  try {
    plan_stages(stages, {}, {});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Internal);
    EXPECT_NE(std::string(e.what()).find("cycle: p, q"), std::string::npos) << e.what();
  }
}

TEST(Plan, TwoProducersOfOneArtifactAreRefused) {
  std::vector<Stage> stages{make("p", {}, {"x"}), make("q", {}, {"x"})};
  EXPECT_THROW(plan_stages(stages, {}, {}), Error);
}

TEST(Driver, RunsStagesAndCollectsPrefixedArtifacts) {
  const auto stages = diamond();
  Artifacts seeded;
  seeded.put("path", 10);
  const RunResult result = run_pipeline({}, std::move(seeded), {}, stages);
  // fabric = 11; a -> 12 (section/a, metadata/a); b -> 12; c -> 13; write = 11 + 12+12+13 + 12 + 1.
  EXPECT_EQ(result.artifacts.get<int>("section/c"), 13);
  EXPECT_EQ(result.artifacts.get<int>("asset"), 11 + 12 + 12 + 13 + 12 + 1);
  ASSERT_EQ(result.stages.size(), 5u);
  for (const auto& s : result.stages) {
    EXPECT_GE(s.wall_seconds, 0.0);
    EXPECT_GE(s.cpu_seconds, 0.0);
    EXPECT_GT(s.peak_rss_bytes, 0u);
  }
}

TEST(Driver, UndeclaredReadsAndWritesAndMissingOutputsAreInternalErrors) {
  Stage reads = make("reads", {}, {"out"});
  reads.run = [](StageContext& ctx) { ctx.output("out", ctx.input<int>("secret")); };
  Stage writes = make("writes", {}, {"out"});
  writes.run = [](StageContext& ctx) { ctx.output("other", 1); };
  Stage lazy = make("lazy", {}, {"out"});
  lazy.run = [](StageContext&) {};
  for (const Stage& s : {reads, writes, lazy}) {
    std::vector<Stage> stages{s};
    Artifacts seeded;
    seeded.put("secret", 1);
    try {
      run_pipeline({}, std::move(seeded), {}, stages);
      FAIL() << s.name;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ExitCode::Internal);
      EXPECT_NE(std::string(e.what()).find("stage '" + s.name + "'"), std::string::npos);
    }
  }
}

// RunOptions::progress sees every stage in run order, (name, 0) first and (name, 1) last, with the
// stage's own reports between; an exception it throws ends the run and later stages do not run.
TEST(Driver, ProgressCallbackSeesEveryStageAndItsExceptionEndsTheRun) {
  auto stages = diamond();
  stages[2].run = [](StageContext& ctx) {  // "a" reports, then produces as make() does
    ctx.progress(0.25);
    ctx.progress(0.75);
    ctx.output("section/a", 12);
    ctx.output("metadata/a", 12);
  };
  std::vector<std::pair<std::string, double>> reports;
  RunOptions options;
  options.progress = [&](const std::string& stage, double f) { reports.emplace_back(stage, f); };
  Artifacts seeded;
  seeded.put("path", 10);
  run_pipeline({}, std::move(seeded), options, stages);
  const std::vector<std::pair<std::string, double>> expected{
      {"load", 0.0}, {"load", 1.0}, {"a", 0.0}, {"a", 0.25}, {"a", 0.75},    {"a", 1.0},
      {"b", 0.0},    {"b", 1.0},    {"c", 0.0}, {"c", 1.0},  {"write", 0.0}, {"write", 1.0}};
  EXPECT_EQ(reports, expected);

  struct Stop {};
  std::vector<std::string> ran;
  options.progress = [&](const std::string& stage, double f) {
    if (f == 0.0) ran.push_back(stage);
    if (stage == "a" && f > 0.5) throw Stop{};
  };
  Artifacts again;
  again.put("path", 10);
  EXPECT_THROW(run_pipeline({}, std::move(again), options, stages), Stop);
  EXPECT_EQ(ran, (std::vector<std::string>{"load", "a"}));
}

TEST(Driver, ThreadLimitIsApplied) {
  std::vector<Stage> stages{make("only", {}, {"x"})};
  RunOptions options;
  options.threads = 1;
  EXPECT_EQ(run_pipeline({}, {}, options, stages).threads, 1);
}

}  // namespace
