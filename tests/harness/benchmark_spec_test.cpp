#include "robotperf/harness/benchmark_spec.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "robotperf/harness/dataset.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/plugin/registry.hpp"
#include "test_package.hpp"

namespace robotperf::harness {
namespace {

using testing::relay_graph;
using testing::TestPackage;

std::string error_of(const std::filesystem::path& dir) {
  try {
    load_benchmark(dir);
  } catch (const BenchmarkError& e) {
    return e.what();
  }
  return "";
}

TEST(BenchmarkSpec, LoadsTheShippedPerceptionPackages) {
  const auto specs =
      discover_benchmarks(std::filesystem::path(ROBOTPERF_SOURCE_DIR) / "benchmarks");
  std::vector<std::string> ids;
  for (const auto& s : specs) ids.push_back(s.id);
  for (const char* id : {"a1", "a2", "a5"}) EXPECT_NE(std::ranges::find(ids, id), ids.end()) << id;

  const auto a1 = find_benchmark(std::filesystem::path(ROBOTPERF_SOURCE_DIR) / "benchmarks", "a1");
  EXPECT_EQ(a1.name, "a1_perception_2nodes");
  EXPECT_EQ(a1.category, "perception");
  ASSERT_EQ(a1.nodes.size(), 2u);
  EXPECT_EQ(a1.nodes[0].kernel, "image_proc/rectify");
  EXPECT_EQ(a1.nodes[1].parameters.at("scale_width"), "2.0");
  EXPECT_EQ(a1.output.topic, "/resize/image");
  EXPECT_DOUBLE_EQ(a1.rate_hz, 30.0);
}

TEST(BenchmarkSpec, UnknownBenchmarkListsTheKnownOnes) {
  try {
    find_benchmark(std::filesystem::path(ROBOTPERF_SOURCE_DIR) / "benchmarks", "z9");
    FAIL();
  } catch (const BenchmarkError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown benchmark 'z9'"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("a1"), std::string::npos);
  }
}

TEST(BenchmarkSpec, MalformedYamlNamesFileAndLine) {
  TestPackage p("malformed", "dataset: perception/image\ninputs: [\n  {topic: /in\n");
  const std::string err = error_of(p.dir());
  EXPECT_NE(err.find("graph.yaml:"), std::string::npos) << err;
  EXPECT_NE(err.find("malformed YAML"), std::string::npos) << err;
}

TEST(BenchmarkSpec, RejectsUnknownKeysKernelsPortsAndParameters) {
  {
    TestPackage p("typo", relay_graph("", "rate_hzz: 5\n"));
    EXPECT_NE(error_of(p.dir()).find("unknown key 'rate_hzz'"), std::string::npos);
  }
  {
    std::string g = relay_graph("");
    g.replace(g.find("util/relay"), 10, "util/nothing");
    TestPackage p("kernel", g);
    EXPECT_NE(error_of(p.dir()).find("unknown kernel 'util/nothing'"), std::string::npos);
  }
  {
    std::string g = relay_graph("");
    g.replace(g.find("output: /out"), 12, "exit: /out");
    TestPackage p("port", g);
    EXPECT_NE(error_of(p.dir()).find("no port 'exit'"), std::string::npos);
  }
  {
    std::string g = relay_graph("");
    g.replace(g.find("stream: image}"), 14, "stream: image, qos: fastest}");
    TestPackage q("qos", g);
    EXPECT_NE(error_of(q.dir()).find("unknown QoS profile 'fastest'"), std::string::npos);
  }
}

TEST(BenchmarkSpec, RefusesValuesOutsideTheirLimits) {
  const std::pair<std::string, std::string> cases[] = {
      {"executor_threads: 100000\n", "executor_threads must be 1 to 256"},
      {"executor_threads: 0\n", "executor_threads must be 1 to 256"},
  };
  for (const auto& [extra, message] : cases) {
    TestPackage p("limits", relay_graph("", extra));
    const std::string err = error_of(p.dir());
    EXPECT_NE(err.find("graph.yaml:5: " + message), std::string::npos) << err;
  }
  std::string loss = relay_graph("");
  loss.replace(loss.find("max_loss_percent: 0.0"), 21, "max_loss_percent: -5");
  TestPackage negative("loss", loss);
  EXPECT_NE(error_of(negative.dir()).find("max_loss_percent must be within 0-100"),
            std::string::npos);
  std::string samples = relay_graph("");
  samples.replace(samples.find("min_samples: 5"), 14, "min_samples: 0");
  TestPackage none("samples", samples);
  EXPECT_NE(error_of(none.dir()).find("min_samples must be >= 1"), std::string::npos);
  TestPackage fail_after("fail_after", relay_graph("fail_after: -1"));
  RunOptions o;
  o.load.count = 5;
  try {
    run_benchmark(load_benchmark(fail_after.dir()), o);
    FAIL() << "a negative fail_after was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fail_after must be >= 0"), std::string::npos);
  }
}

// Found by fuzz_benchmark_packages: a graph.yaml without `nodes:` or `inputs:` threw yaml-cpp's
// "invalid node" instead of a BenchmarkError.
TEST(BenchmarkSpec, MissingListsAndOddKeysAreOneLineErrors) {
  std::string no_nodes = relay_graph("");
  no_nodes.erase(no_nodes.find("nodes:"));
  TestPackage p("no_nodes", no_nodes);
  EXPECT_NE(error_of(p.dir()).find("'nodes' must be a list"), std::string::npos);

  std::string no_inputs = relay_graph("");
  const auto inputs = no_inputs.find("inputs:");
  no_inputs.erase(inputs, no_inputs.find("output:") - inputs);
  TestPackage q("no_inputs", no_inputs);
  EXPECT_NE(error_of(q.dir()).find("'inputs' must be a non-empty list"), std::string::npos);

  // A mapping used as a key is yaml-cpp's BadConversion: still one line naming the package.
  TestPackage r("map_key", relay_graph("", "{a: 1}: 2\n"));
  const std::string err = error_of(r.dir());
  EXPECT_NE(err.find(r.dir().string()), std::string::npos) << err;
}

// An id or a name becomes part of a file name (results, reports, logs): one that
// could leave the output folder, or make an odd file name, is refused where the package is loaded.
TEST(BenchmarkSpec, NamesThatBecomeFileNamesAreRefusedUnlessPlain) {
  const char* const kBad[] = {"/abs/ABSOLUTE", "../../..", "\"\"", "\"a\\nb\"",
                              ".hidden",       "a/b",      "-rf"};
  for (const std::string bad : kBad) {
    TestPackage p("ids", relay_graph(""));
    std::ofstream(p.dir() / "benchmark.yaml")
        << "id: " << bad << "\nname: t1_ids\nshort: test\ndescription: test\nresults: []\n";
    std::string err = error_of(p.dir());
    EXPECT_NE(err.find("benchmark.yaml:1: id '"), std::string::npos) << bad << ": " << err;
    EXPECT_NE(err.find("is not a name robotperf can put in a file name"), std::string::npos) << err;
    std::ofstream(p.dir() / "benchmark.yaml")
        << "id: t1\nname: " << bad << "\nshort: test\ndescription: test\nresults: []\n";
    err = error_of(p.dir());
    EXPECT_NE(err.find("benchmark.yaml:2: name '"), std::string::npos) << bad << ": " << err;
  }
}

// Node names are ROS 2 names, split into namespace and name as rcl does: a namespace is allowed,
// anything rcl refuses is refused where the package is loaded, naming the line.
TEST(BenchmarkSpec, NodeNamesAreRosNames) {
  auto with_node_name = [](const std::string& name) {
    std::string graph = relay_graph("");
    graph.replace(graph.find("name: relay"), 11, "name: " + name);
    return graph;
  };
  for (const std::string good : {"ns/relay", "/ns/relay", "_relay2"}) {
    TestPackage p("node_names", with_node_name(good));
    EXPECT_NO_THROW(load_benchmark(p.dir())) << good;
  }
  for (const std::string bad : {"my-relay", "2relay", "\"relay node\"", "a//b", "../relay"}) {
    TestPackage p("node_names", with_node_name(bad));
    const std::string err = error_of(p.dir());
    EXPECT_NE(err.find("is not a ROS 2 node name"), std::string::npos) << bad << ": " << err;
    EXPECT_NE(err.find("graph.yaml:"), std::string::npos) << err;
  }
}

// yaml-cpp keeps the first of two equal keys: the package is refused instead, naming both lines.
TEST(BenchmarkSpec, DuplicateKeysAreRefusedNamingBothLines) {
  TestPackage p("duplicate", relay_graph("", "rate_hz: 30\n"));
  const std::string err = error_of(p.dir());
  EXPECT_NE(err.find("graph.yaml:5: duplicate key 'rate_hz' (first at line 2)"), std::string::npos)
      << err;
  TestPackage q("nested", relay_graph("reliable: true, reliable: false"));
  EXPECT_NE(error_of(q.dir()).find("duplicate key 'reliable'"), std::string::npos)
      << error_of(q.dir());
}

// An output that is an input would time the Playback's own messages as the graph's; only a graph
// of no node does that on purpose (the harness's own overhead). Two inputs on one topic are one
// stream too many.
TEST(BenchmarkSpec, OutputAndInputsAreDistinctTopicsUnlessTheGraphIsEmpty) {
  std::string looped = relay_graph("");
  looped.replace(looped.find("output: {topic: /out"), 20, "output: {topic: /in");
  TestPackage p("looped", looped);
  const std::string err = error_of(p.dir());
  EXPECT_NE(err.find("the output topic /in is also an input"), std::string::npos) << err;
  TestPackage empty("empty_graph", relay_graph("none"));
  EXPECT_EQ(error_of(empty.dir()), "");
  std::string twice = relay_graph("");
  twice.replace(twice.find("output:"), 0,
                "  - {topic: /in, type: sensor_msgs/msg/CameraInfo, stream: camera_info}\n");
  TestPackage q("twice", twice);
  EXPECT_NE(error_of(q.dir()).find("two inputs are published on /in"), std::string::npos)
      << error_of(q.dir());
}

// Before any run: an input no node reads (every message would be lost) and a node that publishes
// back onto an input (a relay loop: the Playback's topic fed again, duplicates by the thousand)
// are refused naming the topic and the node.
TEST(BenchmarkSpec, AnUnreadInputAndALoopOntoAnInputAreRefused) {
  std::string unread = relay_graph("");
  unread.replace(unread.find("output:"), 0,
                 "  - {topic: /unused, type: sensor_msgs/msg/CameraInfo, stream: camera_info}\n");
  TestPackage p("unread", unread);
  EXPECT_NE(error_of(p.dir()).find("input /unused is read by no node"), std::string::npos)
      << error_of(p.dir());
  TestPackage q("loop", relay_graph("") +
                            "  - name: back\n    kernel: util/relay\n"
                            "    topics: {input: /out, output: /in}\n");
  EXPECT_NE(error_of(q.dir()).find("node 'back' publishes (port 'output') on /in, an input"),
            std::string::npos)
      << error_of(q.dir());
}

// A package one level too high up (<root>/<package>, with no category folder), or a package given
// as the benchmarks folder itself, is named with the layout it needs instead of being skipped.
TEST(BenchmarkSpec, PackageOutsideACategoryFolderIsNamed) {
  TestPackage p("shallow", relay_graph(""));
  const std::filesystem::path categories = p.root() / "test";
  try {
    find_benchmark(categories, "t1");
    FAIL() << "a package outside any category folder was found";
  } catch (const BenchmarkError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(p.dir().string() + ": a benchmark package directly in the benchmarks "
                                           "folder"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("<category>"), std::string::npos) << what;
  }
  std::vector<std::string> broken;
  EXPECT_TRUE(discover_benchmarks(categories, &broken).empty());
  EXPECT_EQ(broken.size(), 1u);
  try {
    discover_benchmarks(p.dir());
    FAIL() << "a package given as the benchmarks folder was accepted";
  } catch (const BenchmarkError& e) {
    EXPECT_NE(std::string(e.what()).find("is a benchmark package, not a folder of them"),
              std::string::npos)
        << e.what();
  }
  // `list` lists the packages of the other folders and says which folder it skipped.
  broken.clear();
  EXPECT_EQ(
      discover_benchmarks(std::vector<std::filesystem::path>{p.dir(), p.root()}, &broken).size(),
      1u);
  ASSERT_EQ(broken.size(), 1u);
  EXPECT_NE(broken[0].find("is a benchmark package, not a folder of them"), std::string::npos);
  EXPECT_THROW(find_benchmark(p.dir(), "t1"), BenchmarkError);
  EXPECT_EQ(find_benchmark(p.root(), "t1").dir, p.dir());
}

// Two kernels for keep_on_device's rules, whatever this build's backends: "test/hand_on" keeps
// its output on "test_device", "test/take_on" takes its "image" input there (not its "info").
void register_hand_over_kernels() {
  static const bool registered = [] {
    plugin::registry().add("benchmark_spec_test", [](plugin::Registrar& r) {
      const auto no_node = [](graph::Context&, const plugin::KernelConfig&) {
        return std::shared_ptr<graph::Node>();
      };
      const std::vector<std::string> backends{"cpu", "test_device"};
      r.add_kernel({.name = "test/hand_on",
                    .description = "keeps its output on the device",
                    .backends = backends,
                    .inputs = {{"in", "sensor_msgs/msg/Image"}},
                    .outputs = {{"out", "sensor_msgs/msg/Image", true}},
                    .device_resident_backends = {"test_device"}},
                   no_node);
      r.add_kernel(
          {.name = "test/take_on",
           .description = "takes its image on the device",
           .backends = backends,
           .inputs = {{"image", "sensor_msgs/msg/Image", true}, {"info", "sensor_msgs/msg/Image"}},
           .outputs = {{"out", "sensor_msgs/msg/Image", true}},
           .device_resident_backends = {"test_device"}},
          no_node);
    });
    return true;
  }();
  static_cast<void>(registered);
}

// in -> hand (hand_on) -> /mid -> take (take_on, image) -> /out (the Monitor's), all on
// `backend`; `mid_port` is the port of take that /mid reaches.
BenchmarkSpec hand_over_graph(const std::string& backend, const std::string& mid_port = "image") {
  register_hand_over_kernels();
  BenchmarkSpec spec;
  spec.id = "h1";
  spec.output.topic = "/out";
  NodeSpec hand, take;
  hand.name = "hand";
  hand.kernel = "test/hand_on";
  hand.backend = backend;
  hand.topics = {{"in", "/in"}, {"out", "/mid"}};
  take.name = "take";
  take.kernel = "test/take_on";
  take.backend = backend;
  take.topics = {{mid_port, "/mid"}, {"out", "/out"}};
  spec.nodes = {hand, take};
  return spec;
}

// --device-resident keeps on the device only a topic that nodes alone take, through ports that
// hand data over, all on one backend that both kernels hand over on; never the Monitor's topic.
TEST(BenchmarkSpec, DeviceResidentKeepsOnlyTopicsThatNodesAloneTakeOnOneDevice) {
  BenchmarkSpec spec = hand_over_graph("test_device");
  const std::vector<ResidentTopic> kept = keep_on_device(spec);
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_EQ(kept[0].topic, "/mid");
  EXPECT_EQ(kept[0].from, "hand");
  EXPECT_EQ(kept[0].to, std::vector<std::string>{"take"});
  EXPECT_EQ(kept[0].backend, "test_device");
  EXPECT_EQ(spec.nodes[0].device_resident_outputs, std::set<std::string>{"out"});
  EXPECT_TRUE(spec.nodes[1].device_resident_outputs.empty()) << "the Monitor takes /out";
  EXPECT_EQ(kernel_config(spec.nodes[0]).device_resident_outputs, std::set<std::string>{"out"});

  const auto refused = [](BenchmarkSpec graph, const char* what) {
    try {
      keep_on_device(graph);
      ADD_FAILURE() << what << ": kept something on the device";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("no topic of h1 can stay on the device"),
                std::string::npos)
          << e.what();
    }
  };
  refused(hand_over_graph("cpu"), "on cpu");
  refused(hand_over_graph("test_device", "info"), "into a port that takes host data");
  BenchmarkSpec mixed = hand_over_graph("test_device");
  mixed.nodes[1].backend = "cpu";
  refused(mixed, "the taker on another backend");
  BenchmarkSpec also_watched = hand_over_graph("test_device");
  NodeSpec watcher = also_watched.nodes[1];
  watcher.name = "watcher";
  watcher.topics = {{"info", "/mid"}, {"out", "/other"}};
  also_watched.nodes.push_back(watcher);
  refused(also_watched, "a second taker that needs the data on the host");
}

TEST(BenchmarkSpec, MissingFileIsReported) {
  TestPackage p("missing", relay_graph(""));
  std::filesystem::remove(p.dir() / "graph.yaml");
  EXPECT_NE(error_of(p.dir()).find("graph.yaml: file not found"), std::string::npos);
}

TEST(Dataset, BuiltInCameraLoadsWholeAndHashesStably) {
  const Dataset a = load_dataset("perception/image");
  EXPECT_EQ(a.frames, 68u);
  EXPECT_EQ(a.stream("image").messages.size(), 68u);
  EXPECT_EQ(a.stream("camera_info").messages.size(), 68u);
  EXPECT_EQ(a.hash, load_dataset("perception/image").hash);
  EXPECT_EQ(a.hash.rfind("fnv1a64:", 0), 0u);
  EXPECT_THROW(a.stream("lidar"), std::invalid_argument);
  EXPECT_THROW(load_dataset("nope"), std::invalid_argument);
}

}  // namespace
}  // namespace robotperf::harness
