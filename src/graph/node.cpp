#include "robotperf/graph/node.hpp"

#include <cxxabi.h>

#include <cstdlib>
#include <memory>
#include <stdexcept>

#include "robotperf/tracing/tracepoints.hpp"

namespace robotperf::graph {
namespace {

// The message ID (header stamp) of a message, or kNoMessageId for types without a header.
int64_t message_id(const msgs::TypeSupport& type, const void* msg) {
  return type.stamped() ? type.stamp_ns(msg) : tracing::kNoMessageId;
}

// Records the symbol of a callback (ros2:rclcpp_callback_register): the demangled name of its
// callable's type. Demangling allocates, so only while traced.
void trace_callback_register(const void* callback, const std::type_info& callable) {
  if (!lttng_ust_tracepoint_enabled(ros2, rclcpp_callback_register)) return;
  int status = 0;
  const std::unique_ptr<char, decltype(&std::free)> demangled(
      abi::__cxa_demangle(callable.name(), nullptr, nullptr, &status), &std::free);
  lttng_ust_do_tracepoint(ros2, rclcpp_callback_register, callback,
                          status == 0 && demangled ? demangled.get() : callable.name());
}

}  // namespace

Context::Context(std::unique_ptr<rmw::Transport> transport) : transport_(std::move(transport)) {
  // ros2_tracing records its tracetools version here; ours names the runtime.
  lttng_ust_tracepoint(ros2, rcl_init, this, "robotperf");
}

void WakeSignal::notify() {
  {
    std::lock_guard lock(mutex_);
    generation_.fetch_add(1, std::memory_order_release);
  }
  cv_.notify_all();
}

bool WakeSignal::wait(uint64_t seen, int64_t deadline_ns) {
  std::unique_lock lock(mutex_);
  auto changed = [&] { return stopped() || generation() != seen; };
  if (deadline_ns == INT64_MAX) {
    cv_.wait(lock, changed);
  } else {
    const auto deadline =
        std::chrono::steady_clock::time_point(std::chrono::nanoseconds(deadline_ns));
    cv_.wait_until(lock, deadline, changed);
  }
  return !stopped();
}

bool WakeSignal::spin_wait(uint64_t seen, int64_t deadline_ns) {
  // The clock is read once every 64 checks: a check costs a few ns, a clock read tens.
  for (unsigned checks = 0;; ++checks) {
    if (stopped()) return false;
    if (generation() != seen) return true;
    if (deadline_ns != INT64_MAX && checks % 64 == 0 &&
        std::chrono::duration_cast<std::chrono::nanoseconds>(
            std::chrono::steady_clock::now().time_since_epoch())
                .count() >= deadline_ns)
      return true;
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();  // lets the sibling hyperthread run, and saves power
#elif defined(__aarch64__)
    asm volatile("yield");
#endif
  }
}

void WakeSignal::stop() {
  {
    std::lock_guard lock(mutex_);
    stopped_.store(true, std::memory_order_release);
  }
  cv_.notify_all();
}

bool Timer::execute() {
  {
    std::lock_guard lock(mutex_);
    const int64_t now = rmw::steady_now_ns();
    if (cancelled_ || now < next_ns_) return false;
    // Absolute deadlines; a timer that fell behind skips the periods it missed
    // instead of firing a burst to catch up.
    next_ns_ += period_ns_;
    if (next_ns_ <= now) next_ns_ += ((now - next_ns_) / period_ns_ + 1) * period_ns_;
  }
  lttng_ust_tracepoint(ros2, callback_start, &callback_, 0);
  callback_();
  lttng_ust_tracepoint(ros2, callback_end, &callback_);
  return true;
}

int64_t Timer::next_deadline_ns() const {
  std::lock_guard lock(mutex_);
  return cancelled_ ? INT64_MAX : next_ns_;
}

void Timer::cancel() {
  std::lock_guard lock(mutex_);
  cancelled_ = true;
}

void GenericPublisher::publish(rmw::MessagePtr msg) {
  lttng_ust_tracepoint(ros2, rclcpp_publish, msg.get());
  if (lttng_ust_tracepoint_enabled(robotperf, publish)) {
    // Sizing walks the message without writing it, and only while traced.
    lttng_ust_do_tracepoint(robotperf, publish, node_name_.c_str(), topic_.c_str(),
                            message_id(*type_support_, msg.get()),
                            type_support_->serialized_size(msg.get()));
  }
  lttng_ust_tracepoint(ros2, rcl_publish, this, msg.get());
  handle_->publish(std::move(msg));
}

bool GenericSubscription::execute() {
  MessageInfo info;
  rmw::MessagePtr msg = handle_->take(&info);
  if (!msg) return false;
  lttng_ust_tracepoint(ros2, rcl_take, msg.get());
  lttng_ust_tracepoint(ros2, rclcpp_take, msg.get());
  lttng_ust_tracepoint(ros2, callback_start, &callback_, info.from_intra_process ? 1 : 0);
  const bool traced = lttng_ust_tracepoint_enabled(robotperf, callback_entry);
  const int64_t id = traced ? message_id(*type_support_, msg.get()) : tracing::kNoMessageId;
  if (traced) {
    lttng_ust_do_tracepoint(robotperf, callback_entry, node_name_.c_str(), topic_.c_str(), id,
                            type_support_->serialized_size(msg.get()));
  }
  callback_(std::move(msg), info);
  lttng_ust_tracepoint(robotperf, callback_exit, node_name_.c_str(), topic_.c_str(), id);
  lttng_ust_tracepoint(ros2, callback_end, &callback_);
  return true;
}

Node::Node(Context& context, std::string name)
    : context_(context), name_(std::move(name)), ros_name_(rmw::parse_node_name(name_)) {
  lttng_ust_tracepoint(ros2, rcl_node_init, this, &context_.transport(), ros_name_.name.c_str(),
                       ros_name_.namespace_.c_str());
}

std::shared_ptr<Timer> Node::create_timer(std::chrono::nanoseconds period,
                                          std::function<void()> callback) {
  if (period.count() <= 0)
    throw std::invalid_argument("timer period must be positive in node " + name_);
  const std::type_info& callable = callable_type(callback);
  auto timer =
      std::make_shared<Timer>(period, std::move(callback), rmw::steady_now_ns() + period.count());
  lttng_ust_tracepoint(ros2, rcl_timer_init, timer.get(), static_cast<int64_t>(period.count()));
  lttng_ust_tracepoint(ros2, rclcpp_timer_callback_added, timer.get(), timer->callback_handle());
  lttng_ust_tracepoint(ros2, rclcpp_timer_link_node, timer.get(), this);
  trace_callback_register(timer->callback_handle(), callable);
  add_entity(timer);
  return timer;
}

std::vector<EndpointStatus> Node::endpoints() const {
  std::lock_guard lock(mutex_);
  std::vector<EndpointStatus> out;
  for (const auto& p : publishers_) {
    out.push_back({p->topic(), p->type(), true, p->matched_subscriptions()});
  }
  for (const auto& e : entities_) {
    if (auto* sub = dynamic_cast<const GenericSubscription*>(e.get())) {
      out.push_back({sub->topic(), sub->type(), false, sub->matched_publishers()});
    }
  }
  return out;
}

void ExecutorLink::join(std::shared_ptr<WakeSignal> signal) {
  std::lock_guard lock(mutex_);
  signal_ = std::move(signal);
}

void ExecutorLink::notify() {
  std::shared_ptr<WakeSignal> signal;
  {
    std::lock_guard lock(mutex_);
    signal = signal_;
  }
  if (signal) signal->notify();
}

void Node::set_wake_signal(std::shared_ptr<WakeSignal> signal) {
  executor_->join(std::move(signal));
  notify();  // data may have arrived before the node joined an executor
}

std::vector<std::shared_ptr<Entity>> Node::entities() const {
  std::lock_guard lock(mutex_);
  return entities_;
}

void Node::notify() {
  executor_->notify();
}

std::shared_ptr<GenericPublisher> Node::create_generic_publisher(const std::string& topic,
                                                                 const msgs::TypeSupport& type,
                                                                 const QoS& qos) {
  auto pub = std::make_shared<GenericPublisher>(
      context_.transport().create_publisher(topic, type, qos, ros_name()), topic, type, name_);
  add_publisher(pub, qos);
  return pub;
}

std::shared_ptr<GenericSubscription> Node::create_generic_subscription(
    const std::string& topic, const msgs::TypeSupport& type, const QoS& qos,
    GenericSubscription::Callback callback, const std::type_info* callable) {
  const std::type_info& callable_or_held = callable ? *callable : callable_type(callback);
  auto sub = std::make_shared<GenericSubscription>(topic, type, name_, std::move(callback));
  sub->attach(context_.transport().create_subscription(
      topic, type, qos, [executor = executor_] { executor->notify(); }, ros_name()));
  // One object stands for both of ROS 2's layers: rcl handle = rclcpp subscription.
  lttng_ust_tracepoint(ros2, rcl_subscription_init, sub.get(), this, sub->rmw_handle(),
                       topic.c_str(), qos.depth);
  lttng_ust_tracepoint(ros2, rclcpp_subscription_init, sub.get(), sub.get());
  lttng_ust_tracepoint(ros2, rclcpp_subscription_callback_added, sub.get(), sub->callback_handle());
  trace_callback_register(sub->callback_handle(), callable_or_held);
  add_entity(sub);
  return sub;
}

void Node::add_publisher(std::shared_ptr<GenericPublisher> publisher, const QoS& qos) {
  lttng_ust_tracepoint(ros2, rcl_publisher_init, publisher.get(), this, publisher->rmw_handle(),
                       publisher->topic().c_str(), qos.depth);
  std::lock_guard lock(mutex_);
  publishers_.push_back(std::move(publisher));
}

void Node::add_entity(std::shared_ptr<Entity> entity) {
  {
    std::lock_guard lock(mutex_);
    entities_.push_back(std::move(entity));
  }
  // An executor already spinning must scan it: a timer's deadline, or data that arrived (and was
  // signalled) while the entity was being created, before the executor could see it.
  notify();
}

}  // namespace robotperf::graph
