// In-process transport: publishers hand the same immutable message object to
// every subscription on the topic. No serialization, no copies, but between a
// serialized (SerializedMessage) and a typed endpoint of one type, which the
// subscription converts through CDR as it takes, as rclcpp does between generic
// and typed endpoints. Endpoints match as DDS matches them (requested versus
// offered QoS), and a transient-local publisher keeps its last messages for the
// transient-local subscriptions that join later.
#include "intra_transport.hpp"

#include <algorithm>
#include <cstring>
#include <deque>
#include <exception>
#include <map>
#include <mutex>
#include <vector>

#include "robotperf/tracing/tracepoints.hpp"

namespace robotperf::rmw {
namespace {

class IntraPublisher;
class IntraSubscription;

struct Topic {
  std::string type;
  std::vector<IntraPublisher*> publishers;
  std::vector<IntraSubscription*> subscriptions;
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

// ROS 2 reads depth 0 as "system default", which both DDS transports take as 1.
QoS effective(QoS qos) {
  if (qos.depth == 0) qos.depth = 1;
  return qos;
}

// A message as published: the TypeSupport of its publisher, and when (DDS's source timestamp).
struct Published {
  MessagePtr msg;
  const msgs::TypeSupport* type;
  int64_t published_ns;
};

// Appends `message`, dropping the oldest beyond a KEEP_LAST depth; KEEP_ALL grows without bound as
// DDS would with unlimited resource limits.
void keep(std::deque<Published>& queue, const QoS& qos, Published message) {
  if (qos.history == History::kKeepLast && queue.size() >= qos.depth) queue.pop_front();
  queue.push_back(std::move(message));
}

// `msg` of type `from` as a message of type `to` (one typed, the other serialized), through its
// CDR bytes; nullptr when they do not decode as `to`, which drops it as a DDS reader drops a
// malformed sample.
MessagePtr convert(const Published& published, const msgs::TypeSupport& to) {
  const msgs::TypeSupport& from = *published.type;
  std::vector<uint8_t> cdr(from.serialized_size(published.msg.get()));
  from.serialize(published.msg.get(), cdr);
  std::shared_ptr<void> out = to.create();
  try {
    to.deserialize(cdr, out.get());
  } catch (const std::exception&) {
    return nullptr;
  }
  return out;
}

class IntraSubscription final : public SubscriptionHandle {
 public:
  IntraSubscription(std::shared_ptr<Registry> registry, std::string topic,
                    const msgs::TypeSupport& type, const QoS& qos, std::function<void()> on_ready)
      : registry_(std::move(registry)),
        topic_(std::move(topic)),
        type_(type),
        qos_(effective(qos)),
        on_ready_(std::move(on_ready)) {}

  ~IntraSubscription() override {
    std::lock_guard lock(registry_->mutex);
    std::erase(registry_->topics[topic_].subscriptions, this);
  }

  const QoS& qos() const { return qos_; }

  // Called with the registry lock held.
  void deliver(const Published& message) {
    {
      std::lock_guard lock(mutex_);
      keep(queue_, qos_, message);
    }
    if (on_ready_) on_ready_();
  }

  MessagePtr take(MessageInfo* info) override;
  std::size_t matched_publishers() const override;

 private:
  std::shared_ptr<Registry> registry_;
  std::string topic_;
  const msgs::TypeSupport& type_;
  QoS qos_;
  std::function<void()> on_ready_;
  std::mutex mutex_;
  std::deque<Published> queue_;
};

class IntraPublisher final : public PublisherHandle {
 public:
  IntraPublisher(std::shared_ptr<Registry> registry, std::string topic,
                 const msgs::TypeSupport& type, const QoS& qos)
      : registry_(std::move(registry)),
        topic_(std::move(topic)),
        type_(type),
        qos_(effective(qos)) {}

  ~IntraPublisher() override {
    std::lock_guard lock(registry_->mutex);
    std::erase(registry_->topics[topic_].publishers, this);
  }

  const QoS& qos() const { return qos_; }

  // Called with the registry lock held: what it kept for a transient-local subscription that
  // joined after it published.
  void deliver_kept(IntraSubscription& subscription) const {
    for (const Published& message : kept_) subscription.deliver(message);
  }

  void publish(MessagePtr msg) override;
  std::size_t matched_subscriptions() const override;

 private:
  std::shared_ptr<Registry> registry_;
  std::string topic_;
  const msgs::TypeSupport& type_;
  QoS qos_;
  std::deque<Published> kept_;  // transient local: its last messages; guarded by the registry
};

// Whether a publisher offers what a subscription requests: DDS's rules, which ROS 2 follows.
bool matches(const IntraPublisher& publisher, const IntraSubscription& subscription) {
  return qos_incompatibility(publisher.qos(), subscription.qos()).empty();
}

MessagePtr IntraSubscription::take(MessageInfo* info) {
  std::lock_guard lock(mutex_);
  while (!queue_.empty()) {
    Published p = std::move(queue_.front());
    queue_.pop_front();
    MessagePtr msg = p.type == &type_ ? std::move(p.msg) : convert(p, type_);
    if (!msg) continue;
    lttng_ust_tracepoint(ros2, rmw_take, this, msg.get(), p.published_ns, 1);
    if (info != nullptr) {
      info->source_timestamp_ns = p.published_ns;
      info->reception_timestamp_ns = p.published_ns;
      info->from_intra_process = true;
    }
    return msg;
  }
  return nullptr;
}

std::size_t IntraSubscription::matched_publishers() const {
  std::lock_guard lock(registry_->mutex);
  const auto& publishers = registry_->topics[topic_].publishers;
  return static_cast<std::size_t>(std::ranges::count_if(
      publishers, [&](const IntraPublisher* p) { return matches(*p, *this); }));
}

void IntraPublisher::publish(MessagePtr msg) {
  // The source timestamp subscriptions see in rmw_take, on DDS's clock as fastdds's.
  const int64_t now = wall_now_ns();
  lttng_ust_tracepoint(ros2, rmw_publish, this, msg.get(), now);
  const Published message{std::move(msg), &type_, now};
  std::lock_guard lock(registry_->mutex);
  for (IntraSubscription* sub : registry_->topics[topic_].subscriptions) {
    if (matches(*this, *sub)) sub->deliver(message);
  }
  if (qos_.durability == Durability::kTransientLocal) keep(kept_, qos_, message);
}

std::size_t IntraPublisher::matched_subscriptions() const {
  std::lock_guard lock(registry_->mutex);
  const auto& subscriptions = registry_->topics[topic_].subscriptions;
  return static_cast<std::size_t>(std::ranges::count_if(
      subscriptions, [&](const IntraSubscription* s) { return matches(*this, *s); }));
}

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
                                                    const msgs::TypeSupport& type, const QoS& qos,
                                                    const NodeName&) override {
    dds_topic_name(topic);  // validates the name as the DDS transport would
    auto pub = std::make_unique<IntraPublisher>(registry_, topic, type, qos);
    std::lock_guard lock(registry_->mutex);
    registry_->topic(topic, type).publishers.push_back(pub.get());
    trace_endpoint_init(pub.get(), true);
    return pub;
  }

  std::unique_ptr<SubscriptionHandle> create_subscription(const std::string& topic,
                                                          const msgs::TypeSupport& type,
                                                          const QoS& qos,
                                                          std::function<void()> on_ready,
                                                          const NodeName&) override {
    dds_topic_name(topic);
    auto sub =
        std::make_unique<IntraSubscription>(registry_, topic, type, qos, std::move(on_ready));
    std::lock_guard lock(registry_->mutex);
    Topic& entry = registry_->topic(topic, type);
    entry.subscriptions.push_back(sub.get());
    trace_endpoint_init(sub.get(), false);
    // A volatile subscription gets nothing published before it; a transient-local one matches
    // transient-local publishers only, which kept their last messages for it.
    if (sub->qos().durability == Durability::kTransientLocal) {
      for (const IntraPublisher* pub : entry.publishers) {
        if (matches(*pub, *sub)) pub->deliver_kept(*sub);
      }
    }
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
