// Output comparisons and backends in the registry: checked as they come, one entry per message
// type or name whoever registers it, and the built-in perception category's among them.
#include <gtest/gtest.h>

#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/plugin/registry.hpp"

namespace robotperf::plugin {
namespace {

OutputComparison agreeing() {
  return [](const void*, const void*) { return Agreement{1.0, 1.0, "always"}; };
}

std::string error_of(Registry& r, const std::string& origin,
                     const std::function<void(Registrar&)>& fn) {
  try {
    r.add(origin, fn);
  } catch (const PluginError& e) {
    return e.what();
  }
  return "";
}

TEST(OutputComparisons, AreFoundByMessageTypeWithTheirOrigin) {
  Registry r;
  r.add("lib_a.so", [](Registrar& reg) {
    reg.add_output_comparison({"sensor_msgs/msg/JointState", "positions"}, agreeing());
  });
  const OutputComparisonEntry* c = r.find_output_comparison("sensor_msgs/msg/JointState");
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->origin, "lib_a.so");
  msgs::JointState a, b;
  EXPECT_EQ(c->compare(&a, &b).criterion, "always");
  EXPECT_EQ(r.find_output_comparison("sensor_msgs/msg/Image"), nullptr);
  ASSERT_EQ(r.output_comparisons().size(), 1u);
}

TEST(OutputComparisons, ASecondForOneTypeIsRefusedNamingBothOrigins) {
  Registry r;
  r.add("first.so", [](Registrar& reg) {
    reg.add_output_comparison({"sensor_msgs/msg/JointState", "positions"}, agreeing());
  });
  const std::string e = error_of(r, "second.so", [](Registrar& reg) {
    reg.add_backend({"second_backend", "kept only with the rest"}, {});
    reg.add_output_comparison({"sensor_msgs/msg/JointState", "mine"}, agreeing());
  });
  EXPECT_NE(e.find("second.so: output comparison of 'sensor_msgs/msg/JointState' is already "
                   "registered by first.so"),
            std::string::npos)
      << e;
  EXPECT_EQ(r.find_backend("second_backend"), nullptr);
  const std::string twice = error_of(r, "third.so", [](Registrar& reg) {
    reg.add_output_comparison({"sensor_msgs/msg/Image", "one"}, agreeing());
    reg.add_output_comparison({"sensor_msgs/msg/Image", "two"}, agreeing());
  });
  EXPECT_NE(twice.find("'sensor_msgs/msg/Image' registered twice"), std::string::npos) << twice;
}

TEST(OutputComparisons, AnUnknownTypeOrNoFunctionIsRefused) {
  Registry r;
  const std::string unknown = error_of(r, "x.so", [](Registrar& reg) {
    reg.add_output_comparison({"my_msgs/msg/Thing", "?"}, agreeing());
  });
  EXPECT_NE(unknown.find("'my_msgs/msg/Thing' is not one robotperf knows"), std::string::npos)
      << unknown;
  const std::string empty = error_of(r, "x.so", [](Registrar& reg) {
    reg.add_output_comparison({"sensor_msgs/msg/JointState", "?"}, {});
  });
  EXPECT_NE(empty.find("no comparison"), std::string::npos) << empty;
}

TEST(Backends, AreFoundByNameSortedWithTheirHooks) {
  Registry r;
  r.add("lib_b.so", [](Registrar& reg) {
    reg.add_backend({"zeta", "z"}, {});
    reg.add_backend({"alpha", "a"},
                    {.devices = [] { return std::vector<DeviceInfo>{{.name = "a0"}}; },
                     .unavailable_reason = [] { return std::string("not here"); }});
  });
  const auto all = r.backends();
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[0]->info.name, "alpha");
  EXPECT_EQ(all[1]->info.name, "zeta");
  const BackendEntry* alpha = r.find_backend("alpha");
  ASSERT_NE(alpha, nullptr);
  EXPECT_EQ(alpha->origin, "lib_b.so");
  EXPECT_EQ(alpha->hooks.devices().at(0).name, "a0");
  EXPECT_EQ(alpha->hooks.unavailable_reason(), "not here");
  EXPECT_FALSE(r.find_backend("zeta")->hooks.devices);
}

TEST(Backends, CpuIsImplicitAndNamesAreUniqueAndPrintable) {
  Registry r;
  const std::string cpu = error_of(r, "x.so", [](Registrar& reg) {
    reg.add_backend({"cpu", "the host"}, {});
  });
  EXPECT_NE(cpu.find("backend 'cpu' is the host's"), std::string::npos) << cpu;
  const std::string spaced = error_of(r, "x.so", [](Registrar& reg) {
    reg.add_backend({"my gpu", "?"}, {});
  });
  EXPECT_NE(spaced.find("names are printable, without spaces"), std::string::npos) << spaced;
  r.add("first.so", [](Registrar& reg) { reg.add_backend({"fpga", "one"}, {}); });
  const std::string again = error_of(r, "second.so", [](Registrar& reg) {
    reg.add_backend({"fpga", "two"}, {});
  });
  EXPECT_NE(again.find("second.so: backend 'fpga' is already registered by first.so"),
            std::string::npos)
      << again;
}

// Registered by the test program's built-in categories (BUILTINS).
TEST(BuiltinCategories, PerceptionBringsItsComparisonsAndBackends) {
  for (const char* type :
       {"sensor_msgs/msg/Image", "sensor_msgs/msg/PointCloud2", "stereo_msgs/msg/DisparityImage"}) {
    const OutputComparisonEntry* c = registry().find_output_comparison(type);
    ASSERT_NE(c, nullptr) << type;
    EXPECT_EQ(c->origin, "built-in perception") << type;
  }
  for (const char* name : {"opencl", "cuda"}) {
    const BackendEntry* b = registry().find_backend(name);
    ASSERT_NE(b, nullptr) << name;
    EXPECT_EQ(b->origin, "built-in perception") << name;
    EXPECT_TRUE(b->hooks.devices) << name;
  }
  EXPECT_EQ(registry().find_backend("cpu"), nullptr);
}

}  // namespace
}  // namespace robotperf::plugin
