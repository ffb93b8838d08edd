#include "robotperf/sysinfo/run_rules.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "../fixture_root.hpp"

namespace robotperf::sysinfo {
namespace {

namespace fs = std::filesystem;

using robotperf::testing::FixtureRoot;

std::vector<std::string> rules_of(const std::vector<RunWarning>& warnings) {
  std::vector<std::string> rules;
  for (const auto& w : warnings) rules.push_back(w.rule);
  return rules;
}

const RunWarning* find(const std::vector<RunWarning>& warnings, const std::string& rule) {
  for (const auto& w : warnings) {
    if (w.rule == rule) return &w;
  }
  return nullptr;
}

// A tuned bare-metal Release setup: nothing to warn about.
RunRuleInputs clean(const fs::path& root) {
  RunRuleInputs in;
  in.root = root;
  in.build_type = "Release";
  in.measured_messages = 5000;
  in.other_load_percent = 3.0;
  in.machine.governors = {"performance"};
  in.machine.smt_enabled = false;
  in.machine.virtual_machine = false;
  return in;
}

TEST(RunRules, TunedMachineHasNoWarnings) {
  FixtureRoot root;
  root.write("sys/devices/system/cpu/intel_pstate/no_turbo", "1\n");
  root.write("sys/kernel/tracing/tracing_on", "1\n");  // on, but nothing is traced
  root.write("sys/kernel/tracing/current_tracer", "nop\n");
  root.write("sys/kernel/tracing/set_event", "");
  const auto warnings = check_run_rules(clean(root.path()));
  EXPECT_TRUE(warnings.empty()) << warnings.front().message;
}

TEST(RunRules, TheBuildRulesAloneJudgeOnlyTheBuild) {
  EXPECT_TRUE(build_warnings("Release", false).empty());
  EXPECT_TRUE(build_warnings("RelWithDebInfo", false).empty());
  const auto unset = build_warnings("", false);
  ASSERT_EQ(unset.size(), 1u);
  EXPECT_NE(unset[0].message.find("unoptimised"), std::string::npos);
  EXPECT_EQ(rules_of(build_warnings("Release", true)), std::vector<std::string>{"build"});
  EXPECT_EQ(build_warnings("Debug", true).size(), 2u);
}

TEST(RunRules, EveryRuleFires) {
  FixtureRoot root;
  root.write("sys/devices/system/cpu/intel_pstate/no_turbo", "0\n");
  root.write("proc/4711/comm", "lttng-sessiond\n");
  RunRuleInputs in = clean(root.path());
  in.build_type = "Debug";
  in.sanitized = true;
  in.machine.governors = {"performance", "powersave"};
  in.machine.smt_enabled = true;
  in.machine.virtual_machine = true;
  in.machine.in_container = true;
  in.machine.container_runtime = "docker";
  in.other_load_percent = 80.0;
  in.measured_messages = 63;
  const auto warnings = check_run_rules(in);
  EXPECT_EQ(rules_of(warnings), (std::vector<std::string>{"build", "build", "governor", "turbo",
                                                          "smt", "virtual_machine", "container",
                                                          "system_busy", "tracing", "samples"}));
  EXPECT_NE(find(warnings, "governor")->message.find("powersave"), std::string::npos);
  EXPECT_EQ(find(warnings, "governor")->message.find("performance,"), std::string::npos);
  EXPECT_NE(find(warnings, "system_busy")->message.find("80 %"), std::string::npos);
  EXPECT_NE(find(warnings, "tracing")->message.find("4711"), std::string::npos);
  EXPECT_NE(find(warnings, "samples")->message.find("63 measured"), std::string::npos);
  EXPECT_NE(find(warnings, "samples")->message.find("below 368 samples"), std::string::npos);
  EXPECT_NE(find(warnings, "container")->message.find("docker"), std::string::npos);
}

TEST(RunRules, FtraceWithATracerAndUnknownFrequency) {
  FixtureRoot root;
  root.write("sys/kernel/tracing/tracing_on", "1\n");
  root.write("sys/kernel/tracing/current_tracer", "function_graph\n");
  RunRuleInputs in = clean(root.path());
  in.machine.governors.clear();
  // Enough for the p99's interval: the p99.9's is reported as far as its samples go.
  in.measured_messages = 500;
  const auto warnings = check_run_rules(in);
  EXPECT_EQ(rules_of(warnings), (std::vector<std::string>{"frequency", "tracing"}));
  EXPECT_NE(find(warnings, "tracing")->message.find("function_graph"), std::string::npos);
}

TEST(RunRules, AGreyBoxRunsOwnLttngDaemonIsNoWarningButOtherTracingIs) {
  FixtureRoot root;
  root.write("proc/4711/comm", "lttng-sessiond\n");
  RunRuleInputs in = clean(root.path());
  in.measured_messages = 5000;
  in.grey_box = true;
  EXPECT_TRUE(check_run_rules(in).empty());
  root.write("sys/kernel/tracing/tracing_on", "1\n");
  root.write("sys/kernel/tracing/current_tracer", "function\n");
  const auto warnings = check_run_rules(in);
  ASSERT_EQ(rules_of(warnings), (std::vector<std::string>{"tracing"}));
  EXPECT_NE(warnings[0].message.find("beside this grey-box run's own LTTng session"),
            std::string::npos)
      << warnings[0].message;
}

TEST(RunRules, BusyThresholdIsStrict) {
  FixtureRoot root;
  RunRuleInputs in = clean(root.path());
  in.other_load_percent = kBusyThresholdPercent;
  EXPECT_TRUE(check_run_rules(in).empty());
  in.other_load_percent = kBusyThresholdPercent + 1;
  EXPECT_EQ(rules_of(check_run_rules(in)), std::vector<std::string>{"system_busy"});
}

}  // namespace
}  // namespace robotperf::sysinfo
