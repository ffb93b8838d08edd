// A category's kernels and evaluators as tests build them: registered through the category's own
// functions, a node run in an intra-process context beside a probe node that publishes its inputs
// and collects its outputs.
#pragma once

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <functional>
#include <initializer_list>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "robotperf/graph/executor.hpp"
#include "robotperf/graph/node.hpp"
#include "robotperf/plugin.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::testing {

// The kernels (with their implementations on further backends) and evaluators the given
// registration functions add (datasets, output comparisons and backends are left out).
class CategoryUnderTest final : public plugin::Registrar {
 public:
  CategoryUnderTest(std::initializer_list<void (*)(plugin::Registrar&)> registrations) {
    for (auto* add : registrations) add(*this);
  }
  void add_kernel(plugin::KernelInfo info, plugin::KernelFactory factory) override {
    const std::string name = info.name;
    kernels_[name] = {std::move(info), std::move(factory)};
  }
  void add_kernel_backend(plugin::KernelBackendInfo info, plugin::KernelFactory factory) override {
    implementations_[{info.kernel, info.backend}] = std::move(factory);
  }
  void add_dataset(plugin::DatasetInfo, plugin::DatasetGenerator) override {}
  void add_output_comparison(plugin::OutputComparisonInfo, plugin::OutputComparison) override {}
  void add_backend(plugin::BackendInfo, plugin::BackendHooks) override {}
  void add_evaluator(plugin::EvaluatorInfo info, plugin::EvaluatorFactory factory) override {
    const std::string name = info.name;
    evaluators_[name] = {std::move(info), std::move(factory)};
  }

  // `kernel`'s config with these parameters, its ports on topics named after them.
  plugin::KernelConfig config_of(const std::string& kernel,
                                 const std::map<std::string, std::string>& parameters) const {
    const plugin::KernelInfo& info = kernels_.at(kernel).first;
    plugin::KernelConfig config;
    config.node_name = "under_test";
    config.parameters = plugin::Parameters(info.parameters, parameters, config.node_name);
    for (const auto& ports : {info.inputs, info.outputs})
      for (const auto& port : ports) config.topics[port.name] = "/test/" + port.name;
    return config;
  }
  // The node of `kernel` on config.backend: its implementation there, else the kernel's factory.
  std::shared_ptr<graph::Node> build(graph::Context& context, const std::string& kernel,
                                     const plugin::KernelConfig& config) const {
    const auto it = implementations_.find({kernel, config.backend});
    if (it != implementations_.end()) return it->second(context, config);
    return kernels_.at(kernel).second(context, config);
  }
  std::unique_ptr<plugin::FunctionalEvaluator> evaluator(
      const std::string& name, std::map<std::string, const plugin::DatasetStream*> truth) const {
    const auto& [info, factory] = evaluators_.at(name);
    return factory(plugin::TruthStreams(name, std::move(truth)),
                   plugin::Parameters(info.parameters, {}, "test"));
  }

 private:
  std::map<std::string, std::pair<plugin::KernelInfo, plugin::KernelFactory>> kernels_;
  std::map<std::pair<std::string, std::string>, plugin::KernelFactory> implementations_;
  std::map<std::string, std::pair<plugin::EvaluatorInfo, plugin::EvaluatorFactory>> evaluators_;
};

// Messages a node published on one port, in order.
template <class T>
class Collected {
 public:
  void add(const T& message) {
    std::lock_guard lock(mutex_);
    messages_.push_back(message);
    arrived_.notify_all();
  }
  // Waits (60 s at most) until `done` holds of the messages so far; false on time out.
  bool wait(const std::function<bool(const std::vector<T>&)>& done) {
    std::unique_lock lock(mutex_);
    return arrived_.wait_for(lock, std::chrono::seconds(60), [&] { return done(messages_); });
  }
  std::vector<T> messages() const {
    std::lock_guard lock(mutex_);
    return messages_;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::vector<T> messages_;
};

// One node of `kernel`, with a probe beside it: declare its inputs and outputs, start(), publish,
// wait for what comes out.
class NodeUnderTest {
 public:
  NodeUnderTest(const CategoryUnderTest& category, const std::string& kernel,
                const std::map<std::string, std::string>& parameters = {})
      : config_(category.config_of(kernel, parameters)),
        context_(rmw::make_transport("intra")),
        node_(category.build(context_, kernel, config_)),
        probe_(std::make_shared<graph::Node>(context_, "probe")) {}
  ~NodeUnderTest() { executor_.stop(); }

  template <class T>
  std::shared_ptr<graph::Publisher<T>> input(const std::string& port) {
    return probe_->create_publisher<T>(config_.topics.at(port), config_.qos);
  }
  template <class T>
  Collected<T>& output(const std::string& port) {
    auto collected = std::make_shared<Collected<T>>();
    subscriptions_.push_back(probe_->create_subscription<T>(
        config_.topics.at(port), config_.qos,
        [collected](std::shared_ptr<const T> m) { collected->add(*m); }));
    collectors_.push_back(collected);
    return *collected;
  }
  void start() {
    executor_.add_node(node_);
    executor_.add_node(probe_);
    executor_.start();
  }
  void stop() { executor_.stop(); }
  std::map<std::string, uint64_t> counters() const {
    return dynamic_cast<const plugin::NodeCounters&>(*node_).counters();
  }

 private:
  plugin::KernelConfig config_;
  graph::Context context_;
  std::shared_ptr<graph::Node> node_;
  std::shared_ptr<graph::Node> probe_;
  std::vector<std::shared_ptr<graph::GenericSubscription>> subscriptions_;
  std::vector<std::shared_ptr<void>> collectors_;
  graph::Executor executor_{1};
};

}  // namespace robotperf::testing
