// The node runtime: a small rclcpp-like layer over a Transport.
//
// A Context owns the transport of one process; Nodes create Publishers,
// Subscriptions and Timers in it; an Executor runs their callbacks. Callbacks
// of one node never run concurrently (rclcpp's default mutually exclusive
// callback group), callbacks of different nodes may, on a multi-threaded executor.
#pragma once

#include <atomic>
#include <chrono>
#include <climits>
#include <concepts>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <typeinfo>
#include <vector>

#include "robotperf/msgs/type_support.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::graph {

using rmw::MessageInfo;
using rmw::QoS;

class Context {
 public:
  // Emits ros2:rcl_init.
  explicit Context(std::unique_ptr<rmw::Transport> transport);
  rmw::Transport& transport() { return *transport_; }

 private:
  std::unique_ptr<rmw::Transport> transport_;
};

// How an executor's idle threads wait for work: asleep on a condition variable (each message
// then costs a thread wake-up, several microseconds), or spinning on the signal's generation
// (no wake-up, but each waiting thread keeps a core busy the whole time).
enum class WaitMode { kSleep, kSpin };

// How an executor is told that an entity may have work. Shared between the
// executor and the nodes it runs; transports call it from their own threads.
class WakeSignal {
 public:
  void notify();
  // Current generation; a waiter that saw generation g sleeps until it changes.
  uint64_t generation() const { return generation_.load(std::memory_order_acquire); }
  // Waits until the generation differs from `seen`, `deadline_ns` (steady
  // clock) passes, or stop() is called. Returns false once stopped.
  bool wait(uint64_t seen, int64_t deadline_ns);
  // The same wait without sleeping: checks the generation in a loop.
  bool spin_wait(uint64_t seen, int64_t deadline_ns);
  void stop();
  bool stopped() const { return stopped_.load(std::memory_order_acquire); }

 private:
  std::mutex mutex_;  // with cv_: a sleeping waiter cannot miss a notify between check and sleep
  std::condition_variable cv_;
  std::atomic<uint64_t> generation_{0};
  std::atomic<bool> stopped_{false};
};

class Node;

// The signal of the executor a node has joined, if any. A node's subscriptions share it with
// their transports, whose threads may call notify() until a subscription's handle is gone: that
// can be while the node itself is being destroyed, so the link outlives the node as needed.
class ExecutorLink {
 public:
  void join(std::shared_ptr<WakeSignal> signal);
  void notify();

 private:
  std::mutex mutex_;
  std::shared_ptr<WakeSignal> signal_;
};

// A publisher, subscription or timer: something an executor runs.
class Entity {
 public:
  virtual ~Entity() = default;
  // Runs at most one callback; returns whether it did.
  virtual bool execute() = 0;
  // Steady-clock time at which the entity wants to run next (timers only).
  virtual int64_t next_deadline_ns() const { return INT64_MAX; }
};

struct EndpointStatus {
  std::string topic;
  std::string type;
  bool is_publisher = false;
  std::size_t matched = 0;
};

// Publishes messages of a type known only at run time.
class GenericPublisher {
 public:
  GenericPublisher(std::unique_ptr<rmw::PublisherHandle> handle, std::string topic,
                   const msgs::TypeSupport& type, std::string node_name)
      : handle_(std::move(handle)),
        topic_(std::move(topic)),
        type_(type.ros_type),
        type_support_(&type),
        node_name_(std::move(node_name)) {}

  // Emits the robotperf:publish and ros2 rclcpp/rcl_publish events (when enabled).
  void publish(rmw::MessagePtr msg);
  std::size_t matched_subscriptions() const { return handle_->matched_subscriptions(); }
  const std::string& topic() const { return topic_; }
  const std::string& type() const { return type_; }
  const void* rmw_handle() const { return handle_.get(); }

 private:
  std::unique_ptr<rmw::PublisherHandle> handle_;
  std::string topic_;
  std::string type_;
  const msgs::TypeSupport* type_support_;
  std::string node_name_;
};

template <class T>
class Publisher : public GenericPublisher {
 public:
  using GenericPublisher::GenericPublisher;
  void publish(std::shared_ptr<const T> msg) { GenericPublisher::publish(std::move(msg)); }
  void publish(T&& msg) { publish(std::make_shared<const T>(std::move(msg))); }
  void publish(const T& msg) { publish(std::make_shared<const T>(msg)); }
};

// Receives messages of a type known only at run time.
class GenericSubscription final : public Entity {
 public:
  using Callback = std::function<void(rmw::MessagePtr, const MessageInfo&)>;
  GenericSubscription(std::string topic, const msgs::TypeSupport& type, std::string node_name,
                      Callback callback)
      : topic_(std::move(topic)),
        type_(type.ros_type),
        type_support_(&type),
        node_name_(std::move(node_name)),
        callback_(std::move(callback)) {}

  void attach(std::unique_ptr<rmw::SubscriptionHandle> handle) { handle_ = std::move(handle); }
  // Runs the callback on one taken message, between the callback start/end tracepoints.
  bool execute() override;
  std::size_t matched_publishers() const { return handle_->matched_publishers(); }
  const std::string& topic() const { return topic_; }
  const std::string& type() const { return type_; }
  const void* rmw_handle() const { return handle_.get(); }
  const void* callback_handle() const { return &callback_; }

 private:
  std::unique_ptr<rmw::SubscriptionHandle> handle_;
  std::string topic_;
  std::string type_;
  const msgs::TypeSupport* type_support_;
  std::string node_name_;
  Callback callback_;
};

class Timer final : public Entity {
 public:
  Timer(std::chrono::nanoseconds period, std::function<void()> callback, int64_t first_deadline_ns)
      : period_ns_(period.count()), next_ns_(first_deadline_ns), callback_(std::move(callback)) {}
  bool execute() override;
  int64_t next_deadline_ns() const override;
  void cancel();
  const void* callback_handle() const { return &callback_; }

 private:
  int64_t period_ns_;
  mutable std::mutex mutex_;
  int64_t next_ns_;
  bool cancelled_ = false;
  std::function<void()> callback_;
};

// The type of a callable a node registers (for a std::function, the callable it holds): its name
// is the callback's symbol in traces.
template <class F>
const std::type_info& callable_type(const F& callable) {
  if constexpr (requires { callable.target_type(); }) {
    return callable ? callable.target_type() : typeid(F);
  } else {
    return typeid(F);
  }
}

// A callback on messages of type T, as a GenericSubscription runs it, and the type of the callable
// the node wrote (callable_type).
struct TypedCallback {
  GenericSubscription::Callback callback;
  const std::type_info* callable = nullptr;
};

// `callback` takes (std::shared_ptr<const T>) or (std::shared_ptr<const T>, const MessageInfo&).
template <class T, class F>
TypedCallback typed_callback(F&& callback) {
  // Read before `callback` is moved into the wrapper: a moved-from std::function holds nothing.
  const std::type_info& callable = callable_type(callback);
  if constexpr (std::invocable<F, std::shared_ptr<const T>, const MessageInfo&>) {
    return {[f = std::forward<F>(callback)](rmw::MessagePtr m, const MessageInfo& info) {
              f(std::static_pointer_cast<const T>(std::move(m)), info);
            },
            &callable};
  } else {
    return {[f = std::forward<F>(callback)](rmw::MessagePtr m, const MessageInfo&) {
              f(std::static_pointer_cast<const T>(std::move(m)));
            },
            &callable};
  }
}

class Node {
 public:
  Node(Context& context, std::string name);
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;
  virtual ~Node() = default;

  const std::string& name() const { return name_; }
  Context& context() { return context_; }

  template <class T>
  std::shared_ptr<Publisher<T>> create_publisher(const std::string& topic, const QoS& qos = QoS{}) {
    const auto& ts = msgs::type_support<T>();
    auto pub = std::make_shared<Publisher<T>>(
        context_.transport().create_publisher(topic, ts, qos, ros_name()), topic, ts, name_);
    add_publisher(pub, qos);
    return pub;
  }

  // `callback` takes (std::shared_ptr<const T>) or (std::shared_ptr<const T>, const MessageInfo&).
  template <class T, class F>
  std::shared_ptr<GenericSubscription> create_subscription(const std::string& topic, const QoS& qos,
                                                           F&& callback) {
    TypedCallback typed = typed_callback<T>(std::forward<F>(callback));
    return create_generic_subscription(topic, msgs::type_support<T>(), qos,
                                       std::move(typed.callback), typed.callable);
  }

  std::shared_ptr<GenericPublisher> create_generic_publisher(const std::string& topic,
                                                             const msgs::TypeSupport& type,
                                                             const QoS& qos = QoS{});
  // `callable`: the type of the callback the node wrote, whose name ros2:rclcpp_callback_register
  // records (default: the type `callback` holds).
  std::shared_ptr<GenericSubscription> create_generic_subscription(
      const std::string& topic, const msgs::TypeSupport& type, const QoS& qos,
      GenericSubscription::Callback callback, const std::type_info* callable = nullptr);

  std::shared_ptr<Timer> create_timer(std::chrono::nanoseconds period,
                                      std::function<void()> callback);

  // The name ROS 2 tools show this node under (ros_discovery_info): the name given split as rcl
  // splits it ("ns/relay": relay in /ns).
  const rmw::NodeName& ros_name() const { return ros_name_; }

  // Topics this node publishes and subscribes, with their matched counts.
  std::vector<EndpointStatus> endpoints() const;

  // --- for executors ---
  void set_wake_signal(std::shared_ptr<WakeSignal> signal);
  std::mutex& callback_mutex() { return callback_mutex_; }
  std::vector<std::shared_ptr<Entity>> entities() const;
  void notify();

 private:
  // Records the publisher and emits ros2:rcl_publisher_init.
  void add_publisher(std::shared_ptr<GenericPublisher> publisher, const QoS& qos);
  void add_entity(std::shared_ptr<Entity> entity);

  Context& context_;
  std::string name_;
  rmw::NodeName ros_name_;
  mutable std::mutex mutex_;  // guards the lists
  std::vector<std::shared_ptr<GenericPublisher>> publishers_;
  std::vector<std::shared_ptr<Entity>> entities_;
  const std::shared_ptr<ExecutorLink> executor_ = std::make_shared<ExecutorLink>();
  std::mutex callback_mutex_;
};

}  // namespace robotperf::graph
