// The harness around a node robotperf did not build, against a plain DDS round trip through the
// same node. Run on demand: ./build/bench/external/bench_external [--count N]
//
//   plain:     a Cyclone DDS C-API client (the node's own IDL types) publishes 640x480 rgb8
//              images on /camera/image_raw at 30 Hz and times each echo on /foreign/image
//   robotperf: `run` of an external graph that launches the same node (graph.yaml `launch:`), its
//              Playback and Monitor on the cyclonedds transport, the same images, rate and QoS
//
// Both: one process for sender and receiver, reliable / volatile / keep last 10, the node
// (tests/foreign/foreign_image_node, copy mode) in a process of its own; the latency is from the
// send to the reception of the echo. Target (issue #17): robotperf's p50 within 1.1x of plain's.
#include <dds/dds.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_start.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/metrics/latency_stats.hpp"
#include "robotperf/rmw/transport.hpp"
#include "ros2_types.h"

extern char** environ;

namespace fs = std::filesystem;
using namespace robotperf;

namespace {

constexpr double kRateHz = 30;
constexpr uint32_t kWidth = 640, kHeight = 480;

// The foreign node in a process of its own, stopped with SIGINT as a launcher stops it.
class ForeignNode {
 public:
  ForeignNode(int domain, const std::string& in, const std::string& out) {
    const std::string d = std::to_string(domain);
    std::vector<const char*> argv = {ROBOTPERF_FOREIGN_IMAGE_NODE,
                                     d.c_str(),
                                     in.c_str(),
                                     out.c_str(),
                                     "copy",
                                     "bench_echo",
                                     nullptr};
    if (posix_spawn(&pid_, argv[0], nullptr, nullptr, const_cast<char* const*>(argv.data()),
                    environ) != 0) {
      throw std::runtime_error(std::string("cannot start ") + argv[0]);
    }
  }
  ~ForeignNode() {
    kill(pid_, SIGINT);
    waitpid(pid_, nullptr, 0);
  }

 private:
  pid_t pid_ = -1;
};

void sleep_until(int64_t ns) {
  const timespec t{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &t, nullptr) == EINTR) {
  }
}

void check(dds_entity_t e, const char* what) {
  if (e < 0) throw std::runtime_error(std::string(what) + ": " + dds_strretcode(e));
}

// Round trips of `count` images through the node (after `warmup` more), in microseconds.
std::vector<double> plain_round_trips(int domain, std::size_t count, std::size_t warmup) {
  ForeignNode node(domain, "/camera/image_raw", "/foreign/image");
  const dds_entity_t participant = dds_create_participant(domain, nullptr, nullptr);
  check(participant, "participant");
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 10);
  const dds_entity_t in = dds_create_topic(participant, &sensor_msgs_msg_dds__Image__desc,
                                           "rt/camera/image_raw", nullptr, nullptr);
  const dds_entity_t out = dds_create_topic(participant, &sensor_msgs_msg_dds__Image__desc,
                                            "rt/foreign/image", nullptr, nullptr);
  check(in, "topic");
  check(out, "topic");
  const dds_entity_t writer = dds_create_writer(participant, in, qos, nullptr);
  const dds_entity_t reader = dds_create_reader(participant, out, qos, nullptr);
  dds_delete_qos(qos);
  check(writer, "writer");
  check(reader, "reader");
  const dds_entity_t waitset = dds_create_waitset(participant);
  const dds_entity_t readable = dds_create_readcondition(reader, DDS_ANY_STATE);
  dds_waitset_attach(waitset, readable, 0);

  std::vector<uint8_t> pixels(std::size_t{kWidth} * kHeight * 3);
  for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<uint8_t>(i * 7);
  sensor_msgs_msg_dds__Image_ image{};
  image.header.frame_id = const_cast<char*>("camera");
  image.height = kHeight;
  image.width = kWidth;
  image.encoding = const_cast<char*>("rgb8");
  image.step = kWidth * 3;
  image.data._buffer = pixels.data();
  image.data._length = image.data._maximum = static_cast<uint32_t>(pixels.size());

  // As the harness, until the node delivers: one image per period until one comes back.
  const int64_t period = static_cast<int64_t>(1e9 / kRateHz);
  for (int64_t deadline = rmw::steady_now_ns();; deadline += period) {
    sleep_until(deadline);
    image.header.stamp.sec = -1;
    dds_write(writer, &image);
    if (dds_waitset_wait(waitset, nullptr, 0, period) > 0) break;
  }
  void* samples[1] = {nullptr};
  dds_sample_info_t info;
  while (dds_take(reader, samples, &info, 1, 1) == 1) dds_return_loan(reader, samples, 1);

  std::vector<double> trips;
  int64_t deadline = rmw::steady_now_ns() + period;
  for (std::size_t k = 0; k < warmup + count; ++k, deadline += period) {
    sleep_until(deadline);
    image.header.stamp.sec = static_cast<int32_t>(k);
    const int64_t sent = rmw::steady_now_ns();
    dds_write(writer, &image);
    bool back = false;
    while (!back && dds_waitset_wait(waitset, nullptr, 0, DDS_SECS(1)) > 0) {
      samples[0] = nullptr;
      while (dds_take(reader, samples, &info, 1, 1) == 1) {
        const auto* echo = static_cast<const sensor_msgs_msg_dds__Image_*>(samples[0]);
        if (info.valid_data && echo->header.stamp.sec == static_cast<int32_t>(k)) {
          back = true;
          if (k >= warmup) trips.push_back(static_cast<double>(rmw::steady_now_ns() - sent) / 1e3);
        }
        dds_return_loan(reader, samples, 1);
        samples[0] = nullptr;
      }
    }
  }
  dds_delete(participant);
  return trips;
}

fs::path write_package(const fs::path& root, std::size_t count, std::size_t warmup) {
  const fs::path dir = root / "bench" / "x_external";
  fs::create_directories(dir);
  std::ofstream(dir / "benchmark.yaml") << "id: x_external\nname: x_external\n";
  std::ofstream(dir / "graph.yaml")
      << "dataset: perception/image\nrate_hz: " << kRateHz << "\ncount: " << count + warmup
      << "\nwarmup: " << warmup
      << "\ndrain_s: 2\nvalidity: {min_samples: 10, max_loss_percent: 0}\n"
         "inputs:\n  - {topic: /camera/image_raw, type: sensor_msgs/msg/Image, stream: image}\n"
         "output: {topic: /foreign/image, type: sensor_msgs/msg/Image}\n"
         "launch:\n  - name: foreign\n    command: [" ROBOTPERF_FOREIGN_IMAGE_NODE
         ", '${domain}', /camera/image_raw, /foreign/image, copy, bench_echo]\n";
  return dir;
}

void row(const char* label, const metrics::SampleStats& s) {
  std::printf("%-44s %6zu %10.1f %10.1f %10.1f\n", label, s.count, s.p50, s.p90, s.p99);
}

}  // namespace

int main(int argc, char** argv) {
  robotperf::bench::start_with_builtin_categories();
  std::size_t count = 300;
  if (argc == 3 && std::strcmp(argv[1], "--count") == 0) count = std::stoul(argv[2]);
  const std::size_t warmup = 30;
  const int domain = rmw::reserved_domain();
  std::printf(
      "Harness around a foreign echo node (Cyclone DDS C API), 640x480 rgb8 at %.0f Hz, "
      "%zu measured\n",
      kRateHz, count);
  std::printf("%-44s %6s %10s %10s %10s\n", "path", "n", "p50 (us)", "p90 (us)", "p99 (us)");

  const std::vector<double> plain = plain_round_trips(domain, count, warmup);
  const metrics::SampleStats p = metrics::compute_stats(plain);
  row("plain Cyclone DDS client -> node -> client", p);

  const fs::path root =
      fs::temp_directory_path() / ("robotperf-bench-external-" + std::to_string(getpid()));
  harness::RunOptions o;
  o.transport.rmw = "cyclonedds";
  o.transport.domain_id = domain;
  o.processes.log_dir = root;
  const harness::RunResult r =
      harness::run_benchmark(harness::load_benchmark(write_package(root, count, warmup)), o);
  metrics::SampleStats ours = r.latency_from_sent;
  ours.count = r.matched;
  ours.p50 /= 1e3;
  ours.p90 /= 1e3;
  ours.p99 /= 1e3;
  row("robotperf Playback -> node -> Monitor", ours);
  const double ratio = ours.p50 / p.p50;
  std::printf("robotperf / plain at p50: %.2fx   target <= 1.10x: %s\n", ratio,
              ratio <= 1.10 ? "met" : "NOT met");
  fs::remove_all(root);
  return 0;
}
