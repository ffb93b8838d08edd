#include "robotperf/graph/executor.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::graph {
namespace {

using msgs::Image;

// Counts events and lets a test wait for a number of them.
class Counter {
 public:
  void add() {
    {
      std::lock_guard lock(m_);
      ++n_;
    }
    cv_.notify_all();
  }
  bool wait_for(int n, std::chrono::seconds timeout = std::chrono::seconds(10)) {
    std::unique_lock lock(m_);
    return cv_.wait_for(lock, timeout, [&] { return n_ >= n; });
  }
  int value() {
    std::lock_guard lock(m_);
    return n_;
  }

 private:
  std::mutex m_;
  std::condition_variable cv_;
  int n_ = 0;
};

// A node's name is split as rcl splits it: that is the name ROS 2 tools see (ros_discovery_info).
TEST(Node, ANamespacedNameIsSplitAndABadOneRefused) {
  Context ctx(rmw::make_transport("intra"));
  Node relay(ctx, "ns/relay");
  EXPECT_EQ(relay.ros_name().namespace_, "/ns");
  EXPECT_EQ(relay.ros_name().name, "relay");
  EXPECT_EQ(relay.name(), "ns/relay");
  EXPECT_THROW(Node(ctx, "my-relay"), std::invalid_argument);
}

TEST(Executor, RunsSubscriptionCallbacksOnItsThread) {
  Context ctx(rmw::make_transport("intra"));
  auto node = std::make_shared<Node>(ctx, "n");
  Counter received;
  std::thread::id callback_thread;
  auto sub = node->create_subscription<Image>("/in", QoS{}, [&](std::shared_ptr<const Image>) {
    callback_thread = std::this_thread::get_id();
    received.add();
  });
  auto pub = node->create_publisher<Image>("/in");
  Executor exec(1);
  exec.add_node(node);
  exec.start();
  for (int i = 0; i < 5; ++i) pub->publish(Image{});
  ASSERT_TRUE(received.wait_for(5));
  exec.stop();
  EXPECT_NE(callback_thread, std::this_thread::get_id());
  EXPECT_EQ(received.value(), 5);
}

// Whether its threads sleep or spin while idle, an executor runs the same callbacks in order.
class ExecutorWait : public ::testing::TestWithParam<WaitMode> {};

TEST_P(ExecutorWait, PipelineAcrossNodesPreservesOrder) {
  Context ctx(rmw::make_transport("intra"));
  auto a = std::make_shared<Node>(ctx, "a");
  auto b = std::make_shared<Node>(ctx, "b");
  auto a_out = a->create_publisher<Image>("/mid");
  auto a_in = a->create_subscription<Image>(
      "/in", QoS{}, [&](std::shared_ptr<const Image> m) { a_out->publish(m); });
  std::vector<int32_t> order;
  Counter done;
  auto b_in = b->create_subscription<Image>("/mid", QoS{}, [&](std::shared_ptr<const Image> m) {
    order.push_back(m->header.stamp.sec);
    done.add();
  });
  auto source = a->create_publisher<Image>("/in");
  Executor exec(2, GetParam());
  exec.add_node(a);
  exec.add_node(b);
  exec.start();
  for (int i = 0; i < 8; ++i) {
    Image m;
    m.header.stamp.sec = i;
    source->publish(std::move(m));
  }
  ASSERT_TRUE(done.wait_for(8));
  exec.stop();
  EXPECT_EQ(order, (std::vector<int32_t>{0, 1, 2, 3, 4, 5, 6, 7}));
}

TEST_P(ExecutorWait, TimerFiresPeriodically) {
  Context ctx(rmw::make_transport("intra"));
  auto node = std::make_shared<Node>(ctx, "n");
  Counter ticks;
  const int64_t start = rmw::steady_now_ns();
  auto timer = node->create_timer(std::chrono::milliseconds(10), [&] { ticks.add(); });
  Executor exec(1, GetParam());
  exec.add_node(node);
  exec.start();
  ASSERT_TRUE(ticks.wait_for(5));
  exec.stop();
  // Five ticks of a 10 ms timer take at least 50 ms (absolute deadlines).
  EXPECT_GE(rmw::steady_now_ns() - start, 50'000'000);
  EXPECT_THROW(node->create_timer(std::chrono::milliseconds(0), [] {}), std::invalid_argument);
}

INSTANTIATE_TEST_SUITE_P(SleepAndSpin, ExecutorWait,
                         ::testing::Values(WaitMode::kSleep, WaitMode::kSpin),
                         [](const auto& info) {
                           return info.param == WaitMode::kSpin ? "spin" : "sleep";
                         });

TEST(Executor, CallbacksOfOneNodeNeverOverlapOnManyThreads) {
  Context ctx(rmw::make_transport("intra"));
  auto node = std::make_shared<Node>(ctx, "n");
  std::atomic<int> inside{0};
  std::atomic<int> max_inside{0};
  Counter done;
  auto body = [&](std::shared_ptr<const Image>) {
    const int now = ++inside;
    int prev = max_inside.load();
    while (now > prev && !max_inside.compare_exchange_weak(prev, now)) {
    }
    std::this_thread::yield();
    --inside;
    done.add();
  };
  auto s1 = node->create_subscription<Image>("/a", QoS{}, body);
  auto s2 = node->create_subscription<Image>("/b", QoS{}, body);
  auto pa = node->create_publisher<Image>("/a");
  auto pb = node->create_publisher<Image>("/b");
  Executor exec(4);
  exec.add_node(node);
  exec.start();
  for (int i = 0; i < 5; ++i) {
    pa->publish(Image{});
    pb->publish(Image{});
  }
  ASSERT_TRUE(done.wait_for(10));
  exec.stop();
  EXPECT_EQ(max_inside.load(), 1);
}

TEST(Executor, ACallbackExceptionStopsSpinAndNamesTheNode) {
  Context ctx(rmw::make_transport("intra"));
  auto node = std::make_shared<Node>(ctx, "faulty");
  auto sub = node->create_subscription<Image>(
      "/in", QoS{}, [](std::shared_ptr<const Image>) { throw std::runtime_error("bad frame"); });
  auto pub = node->create_publisher<Image>("/in");
  pub->publish(Image{});
  Executor exec(1);
  exec.add_node(node);
  try {
    exec.spin();
    FAIL() << "spin() should rethrow";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("faulty"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("bad frame"), std::string::npos);
  }
}

// The process's CPU time (user + system), in seconds.
double process_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-6;
}

TEST(Executor, OnlyASpinningExecutorKeepsACoreBusyWhileIdle) {
  // Over the same idle 300 ms, a sleeping executor's process uses next to no CPU and a spinning
  // one's about a core (at least 30 % of one, even beside another busy test on two cores).
  for (const WaitMode mode : {WaitMode::kSleep, WaitMode::kSpin}) {
    Context ctx(rmw::make_transport("intra"));
    auto node = std::make_shared<Node>(ctx, "idle");
    auto sub = node->create_subscription<Image>("/in", QoS{}, [](std::shared_ptr<const Image>) {});
    Executor exec(1, mode);
    exec.add_node(node);
    const double before = process_cpu_s();
    exec.start();
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the idle span measured
    exec.stop();
    const double used = process_cpu_s() - before;
    if (mode == WaitMode::kSpin) {
      EXPECT_GT(used, 0.09) << "spinning";
    } else {
      EXPECT_LT(used, 0.04) << "sleeping";
    }
  }
}

// A transport whose second subscription already holds a sample when it is created and signals it
// at once (a transient-local late joiner, or a message that arrives within microseconds), then
// returns only once the executor has scanned its node again: that pass cannot have seen the new
// subscription, which its node adds after the transport returns it. The first subscription, a
// probe, counts the executor's scans.
class ReadyAtCreationTransport final : public rmw::Transport {
 public:
  std::string name() const override { return "ready"; }
  Counter& scans() { return scans_; }
  std::unique_ptr<rmw::PublisherHandle> create_publisher(const std::string&,
                                                         const msgs::TypeSupport&, const QoS&,
                                                         const rmw::NodeName&) override {
    throw rmw::TransportError("ready: no publishers");
  }
  std::unique_ptr<rmw::SubscriptionHandle> create_subscription(const std::string&,
                                                               const msgs::TypeSupport&, const QoS&,
                                                               std::function<void()> on_ready,
                                                               const rmw::NodeName&) override {
    if (!probe_created_) {
      probe_created_ = true;
      return std::make_unique<Handle>(false, &scans_);
    }
    const int before = scans_.value();
    on_ready();
    EXPECT_TRUE(scans_.wait_for(before + 1)) << "the executor did not scan the node";
    return std::make_unique<Handle>(true, nullptr);
  }

 private:
  // Holds at most one sample; `scans`, when given, counts the takes the executor tries.
  class Handle final : public rmw::SubscriptionHandle {
   public:
    Handle(bool pending, Counter* scans) : pending_(pending), scans_(scans) {}
    rmw::MessagePtr take(MessageInfo*) override {
      if (scans_ != nullptr) scans_->add();
      if (!pending_.exchange(false)) return nullptr;
      return std::make_shared<const Image>();
    }
    std::size_t matched_publishers() const override { return 1; }

   private:
    std::atomic<bool> pending_;
    Counter* scans_;
  };
  bool probe_created_ = false;
  Counter scans_;
};

// An executor already spinning, asleep (no timers, nothing to do), runs a node added to it. Its
// wake-up came before the node was in its list: the worker scanned without it, then slept for good
// (in about one try of three). Each try is a fresh executor, so that each can lose it.
TEST(Executor, NodeAddedWhileSpinningRunsItsTimer) {
  for (int attempt = 0; attempt < 8; ++attempt) {
    SCOPED_TRACE("attempt " + std::to_string(attempt));
    auto transport = std::make_unique<ReadyAtCreationTransport>();
    Counter& scans = transport->scans();
    Context ctx(std::move(transport));
    auto idle = std::make_shared<Node>(ctx, "idle");
    auto probe =
        idle->create_subscription<Image>("/probe", QoS{}, [](std::shared_ptr<const Image>) {});
    Executor exec(1);
    exec.add_node(idle);
    exec.start();
    ASSERT_TRUE(scans.wait_for(1));  // its first scan, after which it sleeps
    auto node = std::make_shared<Node>(ctx, "late");
    Counter ticks;
    auto timer = node->create_timer(std::chrono::milliseconds(10), [&] { ticks.add(); });
    exec.add_node(node);
    EXPECT_TRUE(ticks.wait_for(3, std::chrono::seconds(5))) << ticks.value() << " ticks";
    exec.stop();
  }
}

// A subscription whose data was signalled while it was being created, before its node listed it,
// gets its callback: adding it wakes the executor again.
TEST(Executor, SubscriptionCreatedWhileSpinningTakesAReadySample) {
  auto transport = std::make_unique<ReadyAtCreationTransport>();
  Counter& scans = transport->scans();
  Context ctx(std::move(transport));
  auto node = std::make_shared<Node>(ctx, "n");
  auto probe =
      node->create_subscription<Image>("/probe", QoS{}, [](std::shared_ptr<const Image>) {});
  Executor exec(1);
  exec.add_node(node);
  exec.start();
  // Its first scan, after which it sleeps until woken: the signal below wakes it for exactly one.
  ASSERT_TRUE(scans.wait_for(1));
  Counter received;
  auto sub = node->create_subscription<Image>(
      "/ready", QoS{}, [&](std::shared_ptr<const Image>) { received.add(); });
  EXPECT_TRUE(received.wait_for(1));
  exec.stop();
}

// The callable a subscription's callback is traced under is the one the node wrote, also when it
// comes in a std::function moved in: a moved-from std::function holds nothing.
TEST(Node, ASubscriptionCallbackIsNamedByTheCallableItHolds) {
  auto lambda = [](std::shared_ptr<const Image>) {};
  std::function<void(std::shared_ptr<const Image>)> held = lambda;
  const TypedCallback typed = typed_callback<Image>(std::move(held));
  ASSERT_NE(typed.callable, nullptr);
  EXPECT_EQ(*typed.callable, typeid(lambda)) << typed.callable->name();
  const TypedCallback plain = typed_callback<Image>(lambda);
  EXPECT_EQ(*plain.callable, typeid(lambda));
}

// A transport whose subscriptions, like a DDS reader's listener thread, signal data until their
// handle is gone: here once more, from the handle's destructor.
class LateSignallingTransport final : public rmw::Transport {
 public:
  explicit LateSignallingTransport(std::shared_ptr<std::atomic<int>> signalled)
      : signalled_(std::move(signalled)) {}
  std::string name() const override { return "late"; }
  std::unique_ptr<rmw::PublisherHandle> create_publisher(const std::string&,
                                                         const msgs::TypeSupport&, const QoS&,
                                                         const rmw::NodeName&) override {
    throw rmw::TransportError("late: no publishers");
  }
  std::unique_ptr<rmw::SubscriptionHandle> create_subscription(const std::string&,
                                                               const msgs::TypeSupport&, const QoS&,
                                                               std::function<void()> on_ready,
                                                               const rmw::NodeName&) override {
    return std::make_unique<Handle>(std::move(on_ready), signalled_);
  }

 private:
  class Handle final : public rmw::SubscriptionHandle {
   public:
    Handle(std::function<void()> on_ready, std::shared_ptr<std::atomic<int>> signalled)
        : on_ready_(std::move(on_ready)), signalled_(std::move(signalled)) {}
    ~Handle() override {
      on_ready_();
      ++*signalled_;
    }
    rmw::MessagePtr take(MessageInfo*) override { return nullptr; }
    std::size_t matched_publishers() const override { return 0; }

   private:
    std::function<void()> on_ready_;
    std::shared_ptr<std::atomic<int>> signalled_;
  };
  std::shared_ptr<std::atomic<int>> signalled_;
};

// A subscription signalled while its node is destroyed must reach a live executor signal, even
// when the node held the last reference to it (under ASan, a destroyed one is a use after free;
// two runs on one Fast DDS domain crashed on it at shutdown).
TEST(Node, ASubscriptionSignalledWhileItsNodeIsDestroyedReachesALiveSignal) {
  auto signalled = std::make_shared<std::atomic<int>>(0);
  Context ctx(std::make_unique<LateSignallingTransport>(signalled));
  std::weak_ptr<WakeSignal> weak;
  {
    Node node(ctx, "late");
    node.create_subscription<Image>("/late", QoS{}, [](std::shared_ptr<const Image>) {});
    auto signal = std::make_shared<WakeSignal>();
    weak = signal;
    node.set_wake_signal(std::move(signal));
  }
  EXPECT_EQ(signalled->load(), 1);
  EXPECT_TRUE(weak.expired());  // nothing keeps the signal once node and handle are gone
}

}  // namespace
}  // namespace robotperf::graph
