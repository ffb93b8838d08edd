// One-way latency of the "fastdds" transport against a plain Fast DDS
// DataWriter/DataReader pair carrying the same number of bytes.
//
// "plain" writes raw byte vectors (FastddsRawBytesType); "ours" publishes a
// sensor_msgs/Image through the Transport interface, whose serialized size is
// the same. Both use the same QoS (ROS 2 default: RELIABLE, KEEP_LAST 10,
// VOLATILE). The sender stamps each message with CLOCK_MONOTONIC just before
// writing; the receiver, woken by its listener through a condition variable,
// subtracts that stamp from the clock right after taking (and deserializing)
// the message. Across processes the sender is this program re-executed with
// --child; both processes read the same host clock.
//
// usage: bench_transport [--count N] [--rate HZ]
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <functional>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "fastdds_participant_qos.hpp"
#include "fastdds_raw_bytes_type.hpp"
#include "fastdds_transport.hpp"
#include "robotperf/metrics/latency_stats.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/rmw/transport.hpp"

extern char** environ;

namespace robotperf::bench {
namespace {

namespace dds = eprosima::fastdds::dds;
using rmw::FastddsRawBytesType;
using rmw::steady_now_ns;
using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

constexpr int kWarmupMessages = 10;
constexpr std::chrono::seconds kDiscoveryTimeout{30};
// After the last scheduled send, how long the receiver waits for stragglers.
constexpr std::chrono::seconds kDrainTimeout{10};

// Wakes a waiting receiver each time its listener reports data.
class Doorbell {
 public:
  void ring() {
    {
      std::lock_guard lock(mutex_);
      ++rings_;
    }
    rung_.notify_one();
  }
  uint64_t rings() {
    std::lock_guard lock(mutex_);
    return rings_;
  }
  // Waits until the bell rings after `seen`; false at the deadline.
  bool wait(uint64_t& seen, std::chrono::steady_clock::time_point deadline) {
    std::unique_lock lock(mutex_);
    if (!rung_.wait_until(lock, deadline, [&] { return rings_ != seen; })) return false;
    seen = rings_;
    return true;
  }

 private:
  std::mutex mutex_;
  std::condition_variable rung_;
  uint64_t rings_ = 0;
};

class Sender {
 public:
  virtual ~Sender() = default;
  virtual std::size_t matched() const = 0;
  // Stamps the message with the monotonic clock and writes it.
  virtual void send() = 0;
};

class Receiver {
 public:
  virtual ~Receiver() = default;
  virtual std::size_t matched() const = 0;
  // Takes one message and returns its send stamp; false when none is pending.
  virtual bool take(int64_t* send_ns) = 0;
};

// A participant (plain) or a transport (ours) that makes both kinds of endpoint.
class Endpoints {
 public:
  virtual ~Endpoints() = default;
  virtual std::unique_ptr<Sender> sender(const std::string& topic, std::size_t payload_size) = 0;
  virtual std::unique_ptr<Receiver> receiver(const std::string& topic, Doorbell& bell) = 0;
};

// ---- plain Fast DDS, raw bytes ----------------------------------------------

constexpr char kRawTypeName[] = "robotperf::bench::dds_::RawBytes_";
constexpr std::size_t kRawStampOffset = msgs::kEncapsulationSize;

// The same endpoint QoS the fastdds transport derives from QoS::ros_default().
template <class EndpointQos>
EndpointQos plain_qos(EndpointQos qos) {
  qos.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
  qos.durability().kind = dds::VOLATILE_DURABILITY_QOS;
  qos.history().kind = dds::KEEP_LAST_HISTORY_QOS;
  qos.history().depth = 10;
  qos.resource_limits().max_instances = 1;
  qos.resource_limits().max_samples_per_instance = 10;
  qos.resource_limits().max_samples = 10;
  qos.resource_limits().allocated_samples = 10;
  qos.endpoint().history_memory_policy =
      eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  qos.data_sharing().off();
  return qos;
}

class PlainSender final : public Sender {
 public:
  PlainSender(dds::Publisher& publisher, dds::Topic& topic, std::size_t payload_size)
      : publisher_(publisher), sample_(payload_size, 0xab) {
    std::copy(msgs::kCdrLittleEndianHeader.begin(), msgs::kCdrLittleEndianHeader.end(),
              sample_.begin());
    dds::DataWriterQos qos = plain_qos(publisher.get_default_datawriter_qos());
    qos.publish_mode().kind = dds::SYNCHRONOUS_PUBLISH_MODE;
    writer_ = publisher.create_datawriter(&topic, qos);
    if (writer_ == nullptr) throw std::runtime_error("cannot create the plain DataWriter");
  }
  ~PlainSender() override { publisher_.delete_datawriter(writer_); }
  std::size_t matched() const override {
    dds::PublicationMatchedStatus status;
    writer_->get_publication_matched_status(status);
    return static_cast<std::size_t>(status.current_count);
  }
  void send() override {
    const int64_t now = steady_now_ns();
    std::memcpy(sample_.data() + kRawStampOffset, &now, sizeof now);
    if (!writer_->write(&sample_)) throw std::runtime_error("plain write failed");
  }

 private:
  dds::Publisher& publisher_;
  FastddsRawBytesType::Sample sample_;
  dds::DataWriter* writer_ = nullptr;
};

class PlainReceiver final : public Receiver, private dds::DataReaderListener {
 public:
  PlainReceiver(dds::Subscriber& subscriber, dds::Topic& topic, Doorbell& bell)
      : subscriber_(subscriber), bell_(bell) {
    reader_ =
        subscriber.create_datareader(&topic, plain_qos(subscriber.get_default_datareader_qos()),
                                     this, dds::StatusMask::data_available());
    if (reader_ == nullptr) throw std::runtime_error("cannot create the plain DataReader");
  }
  ~PlainReceiver() override {
    reader_->set_listener(nullptr);
    subscriber_.delete_datareader(reader_);
  }
  std::size_t matched() const override {
    dds::SubscriptionMatchedStatus status;
    reader_->get_subscription_matched_status(status);
    return static_cast<std::size_t>(status.current_count);
  }
  // Like the transport, which hands out each message as a new object, take
  // into a fresh buffer rather than reusing one.
  bool take(int64_t* send_ns) override {
    FastddsRawBytesType::Sample sample;
    dds::SampleInfo info;
    while (reader_->take_next_sample(&sample, &info) == ReturnCode::RETCODE_OK) {
      if (!info.valid_data) continue;
      std::memcpy(send_ns, sample.data() + kRawStampOffset, sizeof *send_ns);
      return true;
    }
    return false;
  }

 private:
  void on_data_available(dds::DataReader*) override { bell_.ring(); }

  dds::Subscriber& subscriber_;
  Doorbell& bell_;
  dds::DataReader* reader_ = nullptr;
};

class PlainEndpoints final : public Endpoints {
 public:
  explicit PlainEndpoints(int domain_id) {
    auto* factory = dds::DomainParticipantFactory::get_instance();
    // The transport's participant settings, so only the endpoints differ.
    dds::DomainParticipantQos qos = rmw::fastdds_participant_qos();
    qos.name("robotperf_bench_plain");
    participant_ = factory->create_participant(domain_id, qos);
    if (participant_ == nullptr) throw std::runtime_error("cannot create a DomainParticipant");
    type_ = dds::TypeSupport(new FastddsRawBytesType(kRawTypeName));
    type_.register_type(participant_);
    publisher_ = participant_->create_publisher(participant_->get_default_publisher_qos());
    subscriber_ = participant_->create_subscriber(participant_->get_default_subscriber_qos());
  }
  ~PlainEndpoints() override {
    participant_->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }
  std::unique_ptr<Sender> sender(const std::string& topic, std::size_t payload_size) override {
    return std::make_unique<PlainSender>(*publisher_, this->topic(topic), payload_size);
  }
  std::unique_ptr<Receiver> receiver(const std::string& topic, Doorbell& bell) override {
    return std::make_unique<PlainReceiver>(*subscriber_, this->topic(topic), bell);
  }

 private:
  dds::Topic& topic(const std::string& ros_topic) {
    const std::string name = rmw::dds_topic_name(ros_topic);
    auto* found = dynamic_cast<dds::Topic*>(participant_->lookup_topicdescription(name));
    if (found != nullptr) return *found;
    dds::Topic* created =
        participant_->create_topic(name, kRawTypeName, participant_->get_default_topic_qos());
    if (created == nullptr) throw std::runtime_error("cannot create topic " + name);
    return *created;
  }

  dds::DomainParticipant* participant_ = nullptr;
  dds::TypeSupport type_;
  dds::Publisher* publisher_ = nullptr;
  dds::Subscriber* subscriber_ = nullptr;
};

// ---- ours: sensor_msgs/Image through the fastdds transport ------------------

// An Image whose serialized size (header included) is exactly `payload_size`.
msgs::Image image_of_serialized_size(std::size_t payload_size) {
  msgs::Image image;
  image.header.frame_id = "camera";
  image.encoding = "mono8";
  const std::size_t overhead = msgs::type_support<msgs::Image>().serialized_size(&image);
  if (payload_size < overhead) throw std::invalid_argument("payload smaller than an empty Image");
  image.width = static_cast<uint32_t>(payload_size - overhead);
  image.height = 1;
  image.step = image.width;
  image.data.assign(image.width, 0xab);
  return image;
}

class OurSender final : public Sender {
 public:
  OurSender(rmw::Transport& transport, const std::string& topic, std::size_t payload_size)
      : image_(std::make_shared<msgs::Image>(image_of_serialized_size(payload_size))),
        publisher_(transport.create_publisher(topic, msgs::type_support<msgs::Image>(),
                                              rmw::QoS::ros_default())) {}
  std::size_t matched() const override { return publisher_->matched_subscriptions(); }
  void send() override {
    // The transport serializes during publish() and keeps no reference, so
    // one image is reused rather than copying megabytes before each send.
    image_->header.stamp = msgs::Time::from_ns(steady_now_ns());
    publisher_->publish(image_);
  }

 private:
  std::shared_ptr<msgs::Image> image_;
  std::unique_ptr<rmw::PublisherHandle> publisher_;
};

class OurReceiver final : public Receiver {
 public:
  OurReceiver(rmw::Transport& transport, const std::string& topic, Doorbell& bell)
      : subscription_(transport.create_subscription(topic, msgs::type_support<msgs::Image>(),
                                                    rmw::QoS::ros_default(),
                                                    [&bell] { bell.ring(); })) {}
  std::size_t matched() const override { return subscription_->matched_publishers(); }
  bool take(int64_t* send_ns) override {
    rmw::MessagePtr msg = subscription_->take(nullptr);
    if (!msg) return false;
    *send_ns = static_cast<const msgs::Image*>(msg.get())->header.stamp.to_ns();
    return true;
  }

 private:
  std::unique_ptr<rmw::SubscriptionHandle> subscription_;
};

class OurEndpoints final : public Endpoints {
 public:
  explicit OurEndpoints(int domain_id) : transport_(rmw::make_fastdds_transport({domain_id})) {}
  std::unique_ptr<Sender> sender(const std::string& topic, std::size_t payload_size) override {
    return std::make_unique<OurSender>(*transport_, topic, payload_size);
  }
  std::unique_ptr<Receiver> receiver(const std::string& topic, Doorbell& bell) override {
    return std::make_unique<OurReceiver>(*transport_, topic, bell);
  }

 private:
  std::unique_ptr<rmw::Transport> transport_;
};

std::unique_ptr<Endpoints> make_endpoints(const std::string& impl, int domain_id) {
  if (impl == "plain") return std::make_unique<PlainEndpoints>(domain_id);
  if (impl == "ours") return std::make_unique<OurEndpoints>(domain_id);
  throw std::invalid_argument("unknown implementation " + impl);
}

// ---- one run ----------------------------------------------------------------

struct RunConfig {
  int count = 150;       // measured messages, after kWarmupMessages
  double rate_hz = 100;  // paced to absolute deadlines
};

bool wait_matched(const std::function<std::size_t()>& matched) {
  const auto deadline = std::chrono::steady_clock::now() + kDiscoveryTimeout;
  while (matched() == 0) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

void send_paced(Sender& sender, const RunConfig& config) {
  const auto period = std::chrono::nanoseconds(static_cast<int64_t>(1e9 / config.rate_hz));
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < kWarmupMessages + config.count; ++i) {
    std::this_thread::sleep_until(start + i * period);
    sender.send();
  }
}

struct Latencies {
  std::vector<double> us;  // measured messages only
  int lost = 0;
};

Latencies receive(Receiver& receiver, Doorbell& bell, const RunConfig& config) {
  const int total = kWarmupMessages + config.count;
  const auto deadline = std::chrono::steady_clock::now() + kDrainTimeout +
                        std::chrono::duration_cast<std::chrono::nanoseconds>(
                            std::chrono::duration<double>(total / config.rate_hz));
  Latencies out;
  int received = 0;
  uint64_t seen = bell.rings();
  while (received < total) {
    int64_t send_ns = 0;
    while (received < total && receiver.take(&send_ns)) {
      const int64_t latency_ns = steady_now_ns() - send_ns;
      if (received++ >= kWarmupMessages) out.us.push_back(latency_ns / 1e3);
    }
    if (received < total && !bell.wait(seen, deadline)) break;
  }
  out.lost = total - received;
  return out;
}

Latencies run_in_process(const std::string& impl, int domain_id, const std::string& topic,
                         std::size_t payload_size, const RunConfig& config) {
  auto endpoints = make_endpoints(impl, domain_id);
  Doorbell bell;
  auto receiver = endpoints->receiver(topic, bell);
  auto sender = endpoints->sender(topic, payload_size);
  if (!wait_matched([&] { return sender->matched(); }) ||
      !wait_matched([&] { return receiver->matched(); })) {
    throw std::runtime_error("in-process endpoints did not match");
  }
  std::thread sending([&] { send_paced(*sender, config); });
  Latencies result = receive(*receiver, bell, config);
  sending.join();
  return result;
}

// The sender child: this program re-executed with --child. The parent writes
// one byte to the child's stdin when its reader has matched, and closes it
// when it has received everything, so the writer lives until then.
Latencies run_across_processes(const std::string& impl, int domain_id, const std::string& topic,
                               std::size_t payload_size, const RunConfig& config) {
  auto endpoints = make_endpoints(impl, domain_id);
  Doorbell bell;
  auto receiver = endpoints->receiver(topic, bell);

  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe2 failed");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[0], STDIN_FILENO);
  std::vector<std::string> args = {"/proc/self/exe",
                                   "--child",
                                   impl,
                                   std::to_string(domain_id),
                                   topic,
                                   std::to_string(payload_size),
                                   std::to_string(config.count),
                                   std::to_string(config.rate_hz)};
  std::vector<char*> argv;
  for (auto& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  pid_t child = -1;
  const int spawn_rc = posix_spawn(&child, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[0]);
  if (spawn_rc != 0) {
    close(fds[1]);
    throw std::runtime_error("cannot start the sender process");
  }

  Latencies result;
  if (wait_matched([&] { return receiver->matched(); })) {
    const char go = 'g';
    if (write(fds[1], &go, 1) != 1) throw std::runtime_error("cannot signal the sender process");
    result = receive(*receiver, bell, config);
  } else {
    result.lost = kWarmupMessages + config.count;
  }
  close(fds[1]);
  int status = 0;
  waitpid(child, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    throw std::runtime_error("the sender process failed");
  }
  return result;
}

int run_child(char** argv) {
  const std::string impl = argv[0];
  const int domain_id = std::atoi(argv[1]);
  const std::string topic = argv[2];
  const std::size_t payload_size = std::strtoull(argv[3], nullptr, 10);
  const RunConfig config{std::atoi(argv[4]), std::atof(argv[5])};

  auto endpoints = make_endpoints(impl, domain_id);
  auto sender = endpoints->sender(topic, payload_size);
  if (!wait_matched([&] { return sender->matched(); })) {
    std::fprintf(stderr, "bench_transport child: no reader matched\n");
    return 1;
  }
  char go;
  if (read(STDIN_FILENO, &go, 1) != 1) return 1;
  send_paced(*sender, config);
  while (read(STDIN_FILENO, &go, 1) > 0) {
  }
  return 0;
}

// ---- report -----------------------------------------------------------------

std::string size_label(std::size_t bytes) {
  if (bytes >= (1u << 20)) return std::to_string(bytes >> 20) + " MiB";
  return std::to_string(bytes >> 10) + " KiB";
}

int run_parent(const RunConfig& config) {
  const std::size_t sizes[] = {1u << 10, 1u << 20, 4u << 20};
  // A domain of its own, so concurrent runs and tests do not meet.
  const int domain_id = robotperf::rmw::reserved_domain();
  std::printf(
      "bench_transport: one-way latency in microseconds, %d messages per cell after %d warm-up, "
      "%.0f Hz,\nRELIABLE KEEP_LAST 10 VOLATILE, domain %d. plain = Fast DDS raw bytes, "
      "ours = fastdds transport with sensor_msgs/Image.\nTarget: ours/plain p50 <= 1.2x.\n\n",
      config.count, kWarmupMessages, config.rate_hz, domain_id);
  std::printf("%-14s %-7s %10s %10s %10s %10s %9s %9s %6s  %s\n", "mode", "size", "plain p50",
              "plain p99", "ours p50", "ours p99", "p50 ratio", "p99 ratio", "lost", "target");
  int run_index = 0;
  for (const bool across : {false, true}) {
    for (std::size_t size : sizes) {
      Latencies by_impl[2];
      const char* impls[] = {"plain", "ours"};
      for (int i = 0; i < 2; ++i) {
        const std::string topic = "/robotperf_bench/latency_" + std::to_string(getpid()) + "_" +
                                  std::to_string(run_index++);
        by_impl[i] = across ? run_across_processes(impls[i], domain_id, topic, size, config)
                            : run_in_process(impls[i], domain_id, topic, size, config);
      }
      const auto plain = robotperf::metrics::compute_stats(by_impl[0].us);
      const auto ours = robotperf::metrics::compute_stats(by_impl[1].us);
      const double plain_p50 = plain.p50, plain_p99 = plain.p99;
      const double ours_p50 = ours.p50, ours_p99 = ours.p99;
      const double ratio_p50 = ours_p50 / plain_p50;
      const double ratio_p99 = ours_p99 / plain_p99;
      // The target is on the median; p99 of 150 samples on a shared machine is
      // dominated by scheduling noise and is shown for information.
      const bool within = ratio_p50 <= 1.2;
      std::printf("%-14s %-7s %10.1f %10.1f %10.1f %10.1f %8.2fx %8.2fx %3d/%-3d %s\n",
                  across ? "two processes" : "one process", size_label(size).c_str(), plain_p50,
                  plain_p99, ours_p50, ours_p99, ratio_p50, ratio_p99, by_impl[0].lost,
                  by_impl[1].lost, within ? "p50 ok (<= 1.2x)" : "p50 OVER 1.2x");
      std::fflush(stdout);
    }
  }
  return 0;
}

}  // namespace
}  // namespace robotperf::bench

int main(int argc, char** argv) {
  using namespace robotperf::bench;
  try {
    if (argc == 8 && std::strcmp(argv[1], "--child") == 0) return run_child(argv + 2);
    RunConfig config;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--count" && i + 1 < argc) {
        config.count = std::atoi(argv[++i]);
      } else if (arg == "--rate" && i + 1 < argc) {
        config.rate_hz = std::atof(argv[++i]);
      } else {
        std::fprintf(stderr, "usage: %s [--count N] [--rate HZ]\n", argv[0]);
        return 2;
      }
    }
    if (config.count <= 0 || config.rate_hz <= 0) {
      std::fprintf(stderr, "bench_transport: --count and --rate must be positive\n");
      return 2;
    }
    return run_parent(config);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_transport: %s\n", e.what());
    return 1;
  }
}
