// The registry: what a registration adds is checked, and kept only if all of it is.
#include "robotperf/plugin/registry.hpp"

#include <gtest/gtest.h>

#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::plugin {
namespace {

KernelInfo kernel(const std::string& name) {
  return {.name = name,
          .description = "test",
          .inputs = {{"in", "sensor_msgs/msg/Image"}},
          .outputs = {{"out", "sensor_msgs/msg/Image"}},
          .parameters = {int_parameter("n", 1, "n")}};
}

KernelFactory no_node() {
  return
      [](graph::Context&, const KernelConfig&) -> std::shared_ptr<graph::Node> { return nullptr; };
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

TEST(Registry, AddsWhatARegistrationRegistersWithItsOrigin) {
  Registry r;
  r.add("lib_a.so", [](Registrar& reg) { reg.add_kernel(kernel("a/k"), no_node()); });
  const KernelEntry* k = r.find_kernel("a/k");
  ASSERT_NE(k, nullptr);
  EXPECT_EQ(k->origin, "lib_a.so");
  EXPECT_EQ(k->info.find_port("out")->type, "sensor_msgs/msg/Image");
  EXPECT_EQ(r.find_kernel("a/other"), nullptr);
  EXPECT_EQ(r.kernels().size(), 1u);
}

TEST(Registry, ANameTakenByAnotherOriginIsRefusedNamingBoth) {
  Registry r;
  r.add("first.so", [](Registrar& reg) { reg.add_kernel(kernel("a/k"), no_node()); });
  const std::string e = error_of(r, "second.so", [](Registrar& reg) {
    reg.add_kernel(kernel("b/k"), no_node());
    reg.add_kernel(kernel("a/k"), no_node());
  });
  EXPECT_NE(e.find("second.so"), std::string::npos) << e;
  EXPECT_NE(e.find("'a/k' is already registered by first.so"), std::string::npos) << e;
  // All or nothing: b/k, registered first, is not kept either.
  EXPECT_EQ(r.find_kernel("b/k"), nullptr);
}

TEST(Registry, ARegistrationThatThrowsAddsNothing) {
  Registry r;
  const std::string e = error_of(r, "broken.so", [](Registrar& reg) {
    reg.add_kernel(kernel("c/k"), no_node());
    throw std::runtime_error("device not found");
  });
  EXPECT_NE(e.find("broken.so: registration failed: device not found"), std::string::npos) << e;
  EXPECT_EQ(r.find_kernel("c/k"), nullptr);
}

TEST(Registry, UnusableDescriptionsAreRefused) {
  const std::vector<std::pair<std::string, std::function<void(Registrar&)>>> cases{
      {"is not one robotperf knows",
       [](Registrar& reg) {
         KernelInfo k = kernel("d/k");
         k.inputs[0].type = "my_msgs/msg/Unknown";
         reg.add_kernel(k, no_node());
       }},
      {"port 'in' declared twice",
       [](Registrar& reg) {
         KernelInfo k = kernel("d/k");
         k.outputs[0].name = "in";
         reg.add_kernel(k, no_node());
       }},
      {"default of parameter 'n'",
       [](Registrar& reg) {
         KernelInfo k = kernel("d/k");
         k.parameters[0].default_value = "many";
         reg.add_kernel(k, no_node());
       }},
      {"without a name", [](Registrar& reg) { reg.add_kernel(kernel(""), no_node()); }},
      {"no backend",
       [](Registrar& reg) {
         KernelInfo k = kernel("d/k");
         k.backends.clear();
         reg.add_kernel(k, no_node());
       }},
      {"control loop rate parameter",
       [](Registrar& reg) {
         KernelInfo k = kernel("d/k");
         k.control_loop = ControlLoopInfo{"rate", 2};
         reg.add_kernel(k, no_node());
       }},
      {"no generator",
       [](Registrar& reg) {
         reg.add_dataset({.name = "d/ds",
                          .rate_hz = 1,
                          .streams = {{"s", "/s", "sensor_msgs/msg/Image", false, ""}}},
                         nullptr);
       }},
      {"topic",
       [](Registrar& reg) {
         reg.add_dataset({.name = "d/ds",
                          .rate_hz = 1,
                          .streams = {{"s", "not a topic", "sensor_msgs/msg/Image", false, ""}}},
                         [](const Parameters&) { return std::vector<DatasetStream>{}; });
       }},
      {"no metric",
       [](Registrar& reg) {
         reg.add_evaluator(
             {.name = "d/ev", .output_type = "sensor_msgs/msg/Image", .truth_roles = {"truth"}},
             [](const TruthStreams&, const Parameters&) {
               return std::unique_ptr<FunctionalEvaluator>();
             });
       }},
  };
  for (const auto& [problem, fn] : cases) {
    Registry r;
    const std::string e = error_of(r, "x.so", fn);
    EXPECT_NE(e.find(problem), std::string::npos) << problem << ": " << e;
    EXPECT_TRUE(r.kernels().empty() && r.datasets().empty() && r.evaluators().empty());
  }
}

TEST(Registry, KernelsDatasetsAndEvaluatorsHaveTheirOwnNames) {
  Registry r;
  r.add("x.so", [](Registrar& reg) {
    reg.add_kernel(kernel("same/name"), no_node());
    reg.add_dataset({.name = "same/name",
                     .rate_hz = 1,
                     .streams = {{"s", "/s", "sensor_msgs/msg/Image", false, ""}}},
                    [](const Parameters&) { return std::vector<DatasetStream>{}; });
  });
  EXPECT_NE(r.find_kernel("same/name"), nullptr);
  EXPECT_NE(r.find_dataset("same/name"), nullptr);
}

// Output comparisons and backends: checked as they come, one entry per message type or name
// whoever registers it, and the built-in perception category's among them.

OutputComparison agreeing() {
  return [](const void*, const void*) { return Agreement{1.0, 1.0, "always"}; };
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

// An implementation on a further backend, registered with the kernel or by a later registration,
// is what its entry builds on that backend, and the entry lists the backend.
TEST(KernelBackends, AreListedAndBuildTheirBackendsNodes) {
  Registry r;
  r.add("lib_a.so", [](Registrar& reg) {
    reg.add_kernel_backend({.kernel = "a/k", .backend = "device"}, no_node());
    reg.add_kernel(kernel("a/k"), no_node());
  });
  r.add("lib_b.so", [](Registrar& reg) {
    reg.add_kernel_backend({.kernel = "a/k", .backend = "other", .device_resident = true},
                           no_node());
  });
  const KernelEntry* k = r.find_kernel("a/k");
  ASSERT_NE(k, nullptr);
  EXPECT_EQ(k->info.backends, (std::vector<std::string>{"cpu", "device", "other"}));
  EXPECT_EQ(k->info.device_resident_backends, std::vector<std::string>{"other"});
  EXPECT_EQ(k->origin_on("cpu"), "lib_a.so");
  EXPECT_EQ(k->origin_on("other"), "lib_b.so");
  EXPECT_EQ(&k->factory_on("other"), &k->implementations.at("other").factory);
  EXPECT_EQ(&k->factory_on("cpu"), &k->factory);
}

TEST(KernelBackends, AnUnknownKernelOrATakenBackendAddsNothing) {
  Registry r;
  r.add("lib_a.so", [](Registrar& reg) {
    reg.add_kernel(kernel("a/k"), no_node());
    reg.add_kernel_backend({.kernel = "a/k", .backend = "device"}, no_node());
  });
  std::string e = error_of(r, "lib_b.so", [](Registrar& reg) {
    reg.add_kernel_backend({.kernel = "a/k", .backend = "other"}, no_node());
    reg.add_kernel_backend({.kernel = "a/none", .backend = "other"}, no_node());
  });
  EXPECT_NE(e.find("kernel 'a/none' on backend 'other': no such kernel is registered"),
            std::string::npos)
      << e;
  EXPECT_EQ(r.find_kernel("a/k")->info.backends, (std::vector<std::string>{"cpu", "device"}));
  e = error_of(r, "lib_c.so", [](Registrar& reg) {
    reg.add_kernel_backend({.kernel = "a/k", .backend = "device"}, no_node());
  });
  EXPECT_NE(e.find("kernel 'a/k' already has backend 'device' (lib_a.so)"), std::string::npos) << e;
  e = error_of(r, "lib_d.so", [](Registrar& reg) {
    reg.add_kernel_backend({.kernel = "a/k", .backend = "twice"}, no_node());
    reg.add_kernel_backend({.kernel = "a/k", .backend = "twice"}, no_node());
  });
  EXPECT_NE(e.find("kernel 'a/k' on backend 'twice' registered twice"), std::string::npos) << e;
  e = error_of(r, "lib_e.so", [](Registrar& reg) {
    reg.add_kernel_backend({.kernel = "a/k", .backend = "none"}, nullptr);
  });
  EXPECT_NE(e.find("kernel a/k on backend none: no factory"), std::string::npos) << e;
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
  // Its kernels' implementations, one per backend, each registered with the registry.
  const KernelEntry* rectify = registry().find_kernel("image_proc/rectify");
  ASSERT_NE(rectify, nullptr);
  EXPECT_EQ(rectify->info.backends.front(), "cpu");
  EXPECT_TRUE(rectify->implementations.contains("opencl"));
}

}  // namespace
}  // namespace robotperf::plugin
