// The middleware category (n1, n2): ping-pong as RobotPerf defines it. The Playback is the ping
// side's sender, a relay node (util/relay) the pong, and the Monitor the ping side's receiver, so
// the latency robotperf measures is the round trip on the ping side's clock. The payload is a
// sensor_msgs/Image of one row of pseudo-random bytes (encoding 8UC1), any size from a few bytes
// to many MiB; the evaluator checks that every echo is byte-identical to what was sent.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>

#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/plugin.hpp"

namespace robotperf::middleware {
namespace {

using plugin::DatasetStream;

constexpr double kRateHz = 100.0;
constexpr int64_t kMaxPayloadBytes = int64_t{256} << 20;
// Every frame's payload is held in memory for the run.
constexpr int64_t kMaxDatasetBytes = int64_t{1} << 30;

struct PayloadWorkload {
  int64_t payload_bytes = 0;
  int64_t frames = 0;
  // As given: a negative seed is accepted as it always was, its bits seeding the generator.
  int64_t seed = 0;
};

const plugin::ParameterStruct<PayloadWorkload> kPayloadWorkload{
    plugin::field(&PayloadWorkload::payload_bytes, "payload_bytes", 64,
                  "bytes of payload (the Image's data), up to 256 MiB",
                  {.minimum = 1, .maximum = kMaxPayloadBytes}),
    plugin::field(&PayloadWorkload::frames, "frames", 100,
                  "distinct payloads (the run loops over them); "
                  "payload_bytes x frames at most 1 GiB",
                  {.minimum = 1, .maximum = 100000}),
    plugin::field(&PayloadWorkload::seed, "seed", 1, "seed of the payload bytes")};

// Each parameter's own range is its bounds; together they must fit in memory.
void check_payload_workload(const plugin::Parameters& p) {
  const PayloadWorkload w = kPayloadWorkload.read(p);
  const int64_t bytes = w.payload_bytes;
  const int64_t frames = w.frames;
  if (bytes * frames > kMaxDatasetBytes) {
    throw std::invalid_argument(
        "payload_bytes x frames is " + std::to_string((bytes * frames) >> 20) +
        " MiB of payloads held in memory, above the " + std::to_string(kMaxDatasetBytes >> 20) +
        " MiB bound: give fewer frames (--workload frames=" +
        std::to_string(std::max<int64_t>(1, kMaxDatasetBytes / bytes)) + ")");
  }
}

std::vector<DatasetStream> payload_streams(const plugin::Parameters& p) {
  const PayloadWorkload w = kPayloadWorkload.read(p);
  const int64_t bytes = w.payload_bytes;
  const int64_t frames = w.frames;
  std::mt19937_64 random(static_cast<uint64_t>(w.seed));
  auto stream = plugin::make_stream<msgs::Image>("payload", "/ping");
  for (int64_t i = 0; i < frames; ++i) {
    msgs::Image ping;
    ping.header.stamp = msgs::Time{static_cast<int32_t>(i), 0};
    ping.header.frame_id = "ping";
    ping.height = 1;
    ping.width = static_cast<uint32_t>(bytes);
    ping.encoding = "8UC1";
    ping.step = static_cast<uint32_t>(bytes);
    ping.data.resize(static_cast<std::size_t>(bytes));
    for (std::size_t b = 0; b < ping.data.size(); b += 8) {
      const uint64_t word = random();
      std::copy_n(reinterpret_cast<const uint8_t*>(&word),
                  std::min<std::size_t>(8, ping.data.size() - b),
                  ping.data.begin() + static_cast<std::ptrdiff_t>(b));
    }
    plugin::append(stream, std::move(ping));
  }
  return {std::move(stream)};
}

// Every echo against the payload sent in its frame: all fields but the header stamp (which
// carries the message ID) must be equal, the data byte for byte.
class EchoEvaluator final : public plugin::FunctionalEvaluator {
 public:
  explicit EchoEvaluator(const DatasetStream& sent) : sent_(sent) {
    plugin::require_type<msgs::Image>(sent, "payload_echo");
  }
  void add(const void* output, std::size_t frame) override {
    const auto& echo = *static_cast<const msgs::Image*>(output);
    const auto& sent = *static_cast<const msgs::Image*>(sent_.messages[frame].get());
    ++checked_;
    const bool same = echo.header.frame_id == sent.header.frame_id && echo.height == sent.height &&
                      echo.width == sent.width && echo.encoding == sent.encoding &&
                      echo.is_bigendian == sent.is_bigendian && echo.step == sent.step &&
                      echo.data == sent.data;
    if (same) {
      ++identical_;
    } else if (echo.data.size() != sent.data.size()) {
      problem("an echo carries " + std::to_string(echo.data.size()) + " payload bytes, " +
              std::to_string(sent.data.size()) + " were sent");
    }
  }
  std::map<std::string, double> metrics() const override {
    return {
        {"identical_fraction",
         checked_ ? static_cast<double>(identical_) / static_cast<double>(checked_) : std::nan("")},
        {"echoes_checked", static_cast<double>(checked_)}};
  }

 private:
  const DatasetStream& sent_;
  std::size_t checked_ = 0, identical_ = 0;
};

}  // namespace

void register_category(plugin::Registrar& registrar) {
  registrar.add_dataset(
      {.name = "middleware/payload",
       .description = "ping payloads: sensor_msgs/Image, one row of pseudo-random bytes (8UC1)",
       .rate_hz = kRateHz,
       .frames = 100,
       .streams = {{"payload", "/ping", "sensor_msgs/msg/Image", false,
                    "what the ping side sends; the pong echoes it"}},
       .workload = kPayloadWorkload.declarations(),
       .check_workload = check_payload_workload},
      payload_streams);
  registrar.add_evaluator(
      {.name = "payload_echo",
       .description = "every echo byte-identical to the payload sent (all fields but the stamp)",
       .output_type = "sensor_msgs/msg/Image",
       .truth_roles = {"sent"},
       .metrics = {{"identical_fraction", "fraction", "echoes equal to what was sent"},
                   {"echoes_checked", "echoes", "echoes compared"}},
       .on_arrival = true},
      [](const plugin::TruthStreams& t, const plugin::Parameters&) {
        return std::make_unique<EchoEvaluator>(t["sent"]);
      });
}

}  // namespace robotperf::middleware
