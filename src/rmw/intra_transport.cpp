// In-process transport: publishers hand the same immutable message object to
// every subscription on the topic. No serialization, no copies.
#include "intra_transport.hpp"

#include <cstring>
#include <deque>
#include <map>
#include <mutex>
#include <vector>

#include "robotperf/tracing/tracepoints.hpp"

namespace robotperf::rmw {
namespace {

class IntraSubscription;

struct Topic {
  std::string type;
  std::vector<IntraSubscription*> subscriptions;
  std::size_t publishers = 0;
};

// Topics and their endpoints, shared by a transport's publishers and subscriptions.
struct Registry {
  std::mutex mutex;
  std::map<std::string, Topic> topics;

  Topic& topic(const std::string& name, const msgs::TypeSupport& type) {
    auto [it, inserted] = topics.try_emplace(name);
    if (inserted) {
      it->second.type = type.ros_type;
    } else if (it->second.type != type.ros_type) {
      throw TransportError("topic '" + name + "' already carries " + it->second.type +
                           ", cannot use it for " + type.ros_type);
    }
    return it->second;
  }
};

class IntraSubscription final : public SubscriptionHandle {
 public:
  IntraSubscription(std::shared_ptr<Registry> registry, std::string topic, const QoS& qos,
                    std::function<void()> on_ready)
      : registry_(std::move(registry)),
        topic_(std::move(topic)),
        qos_(qos),
        on_ready_(std::move(on_ready)) {
    // ROS 2 reads depth 0 as "system default", which both DDS transports take as 1.
    if (qos_.depth == 0) qos_.depth = 1;
  }

  ~IntraSubscription() override {
    std::lock_guard lock(registry_->mutex);
    auto& subs = registry_->topics[topic_].subscriptions;
    std::erase(subs, this);
  }

  // Called with the registry lock held.
  void deliver(const MessagePtr& msg, int64_t published_ns) {
    {
      std::lock_guard lock(mutex_);
      // KEEP_LAST drops the oldest; KEEP_ALL grows without bound as DDS would
      // with unlimited resource limits.
      if (qos_.history == History::kKeepLast && queue_.size() >= qos_.depth) queue_.pop_front();
      queue_.push_back({msg, published_ns});
    }
    if (on_ready_) on_ready_();
  }

  MessagePtr take(MessageInfo* info) override {
    std::lock_guard lock(mutex_);
    if (queue_.empty()) return nullptr;
    Pending p = std::move(queue_.front());
    queue_.pop_front();
    lttng_ust_tracepoint(ros2, rmw_take, this, p.msg.get(), p.published_ns, 1);
    if (info != nullptr) {
      info->source_timestamp_ns = p.published_ns;
      info->reception_timestamp_ns = p.published_ns;
      info->from_intra_process = true;
    }
    return std::move(p.msg);
  }

  std::size_t matched_publishers() const override {
    std::lock_guard lock(registry_->mutex);
    return registry_->topics[topic_].publishers;
  }

 private:
  struct Pending {
    MessagePtr msg;
    int64_t published_ns;
  };
  std::shared_ptr<Registry> registry_;
  std::string topic_;
  QoS qos_;
  std::function<void()> on_ready_;
  std::mutex mutex_;
  std::deque<Pending> queue_;
};

class IntraPublisher final : public PublisherHandle {
 public:
  IntraPublisher(std::shared_ptr<Registry> registry, std::string topic)
      : registry_(std::move(registry)), topic_(std::move(topic)) {}

  ~IntraPublisher() override {
    std::lock_guard lock(registry_->mutex);
    --registry_->topics[topic_].publishers;
  }

  void publish(MessagePtr msg) override {
    // The source timestamp subscriptions see in rmw_take, on DDS's clock as fastdds's.
    const int64_t now = wall_now_ns();
    lttng_ust_tracepoint(ros2, rmw_publish, this, msg.get(), now);
    std::lock_guard lock(registry_->mutex);
    for (IntraSubscription* sub : registry_->topics[topic_].subscriptions) sub->deliver(msg, now);
  }

  std::size_t matched_subscriptions() const override {
    std::lock_guard lock(registry_->mutex);
    return registry_->topics[topic_].subscriptions.size();
  }

 private:
  std::shared_ptr<Registry> registry_;
  std::string topic_;
};

// In-process endpoints have no DDS GUID: the endpoint's address stands for it.
void trace_endpoint_init(const void* endpoint, bool publisher) {
  uint8_t gid[ROBOTPERF_ROS2_GID_STORAGE_SIZE] = {};
  const auto address = reinterpret_cast<uintptr_t>(endpoint);
  std::memcpy(gid, &address, sizeof address);
  if (publisher) {
    lttng_ust_tracepoint(ros2, rmw_publisher_init, endpoint, gid);
  } else {
    lttng_ust_tracepoint(ros2, rmw_subscription_init, endpoint, gid);
  }
}

class IntraTransport final : public Transport {
 public:
  std::string name() const override { return "intra"; }

  // Without DDS there is no ROS 2 graph to announce the nodes on.
  using Transport::create_publisher;
  using Transport::create_subscription;
  std::unique_ptr<PublisherHandle> create_publisher(const std::string& topic,
                                                    const msgs::TypeSupport& type, const QoS&,
                                                    const NodeName&) override {
    dds_topic_name(topic);  // validates the name as the DDS transport would
    std::lock_guard lock(registry_->mutex);
    ++registry_->topic(topic, type).publishers;
    auto pub = std::make_unique<IntraPublisher>(registry_, topic);
    trace_endpoint_init(pub.get(), true);
    return pub;
  }

  std::unique_ptr<SubscriptionHandle> create_subscription(const std::string& topic,
                                                          const msgs::TypeSupport& type,
                                                          const QoS& qos,
                                                          std::function<void()> on_ready,
                                                          const NodeName&) override {
    dds_topic_name(topic);
    auto sub = std::make_unique<IntraSubscription>(registry_, topic, qos, std::move(on_ready));
    std::lock_guard lock(registry_->mutex);
    registry_->topic(topic, type).subscriptions.push_back(sub.get());
    trace_endpoint_init(sub.get(), false);
    return sub;
  }

 private:
  std::shared_ptr<Registry> registry_ = std::make_shared<Registry>();
};

}  // namespace

std::unique_ptr<Transport> make_intra_transport() {
  return std::make_unique<IntraTransport>();
}

}  // namespace robotperf::rmw
