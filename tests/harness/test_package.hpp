// Writes throw-away benchmark packages for the harness tests.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace robotperf::harness::testing {

class TestPackage {
 public:
  // `graph_yaml` is the whole graph.yaml; the package is <tmp>/test/<name>.
  TestPackage(const std::string& name, const std::string& graph_yaml,
              const std::string& id = "t1") {
    root_ = std::filesystem::temp_directory_path() /
            ("robotperf-test-" + std::to_string(getpid()) + "-" + name);
    dir_ = root_ / "test" / (id + "_" + name);
    std::filesystem::create_directories(dir_);
    std::ofstream(dir_ / "benchmark.yaml")
        << "id: " << id << "\nname: " << id << "_" << name
        << "\nshort: test\ndescription: test package\nresults: []\n";
    std::ofstream(dir_ / "graph.yaml") << graph_yaml;
  }
  ~TestPackage() { std::filesystem::remove_all(root_); }
  const std::filesystem::path& dir() const { return dir_; }
  const std::filesystem::path& root() const { return root_; }

 private:
  std::filesystem::path root_, dir_;
};

// A graph of relays between the camera image stream and the monitor.
inline std::string relay_graph(const std::string& relay_parameters, const std::string& extra = "") {
  std::string nodes = relay_parameters == "none" ? "nodes: []\n"
                                                 : "nodes:\n"
                                                   "  - name: relay\n"
                                                   "    kernel: util/relay\n"
                                                   "    parameters: {" +
                                                       relay_parameters +
                                                       "}\n"
                                                       "    topics: {input: /in, output: /out}\n";
  return "dataset: perception/image\n"
         "rate_hz: 100\n"
         "warmup: 0\n"
         "drain_s: 2.0\n" +
         extra +
         "validity: {min_samples: 5, max_loss_percent: 0.0}\n"
         "inputs:\n"
         "  - {topic: /in, type: sensor_msgs/msg/Image, stream: image}\n"
         "output: {topic: " +
         std::string(relay_parameters == "none" ? "/in" : "/out") +
         ", type: sensor_msgs/msg/Image}\n" + nodes;
}

}  // namespace robotperf::harness::testing
