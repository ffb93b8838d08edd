// Where kernels, dataset generators, evaluators, output comparisons and backends are registered:
// by the built-in categories at start-up and by plug-ins (shared libraries) loaded with --plugin,
// ROBOTPERF_PLUGIN_PATH or a benchmark's `plugins:`. Both go through the same Registrar.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "robotperf/plugin/backend.hpp"
#include "robotperf/plugin/dataset.hpp"
#include "robotperf/plugin/evaluator.hpp"
#include "robotperf/plugin/kernel.hpp"
#include "robotperf/plugin/output_comparison.hpp"

namespace robotperf::plugin {

// What a plug-in registers through (see ROBOTPERF_PLUGIN in robotperf/plugin.hpp). Each call
// throws std::invalid_argument when the description is not usable; nothing a plug-in registers
// is kept unless all of it is.
class Registrar {
 public:
  virtual ~Registrar();
  // `factory` builds the kernel's node on each of info.backends.
  virtual void add_kernel(KernelInfo info, KernelFactory factory) = 0;
  // `factory` builds the node of a kernel registered with add_kernel (by this registration or an
  // earlier one) on info.backend, which the kernel's entry then lists.
  virtual void add_kernel_backend(KernelBackendInfo info, KernelFactory factory) = 0;
  virtual void add_dataset(DatasetInfo info, DatasetGenerator generator) = 0;
  virtual void add_evaluator(EvaluatorInfo info, EvaluatorFactory factory) = 0;
  // One comparison per message type, whoever registers it.
  virtual void add_output_comparison(OutputComparisonInfo info, OutputComparison compare) = 0;
  // Any backend but cpu, which is implicit (robotperf/plugin/backend.hpp).
  virtual void add_backend(BackendInfo info, BackendHooks hooks) = 0;
};

// A plug-in that cannot be used; the message is one line naming the file and the problem.
class PluginError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// `origin` is "built-in" or the plug-in file the entry came from.
struct KernelImplementation {
  KernelFactory factory;
  std::string origin;
};
struct KernelEntry {
  KernelInfo info;
  KernelFactory factory;  // on the backends add_kernel gave
  std::string origin;
  // What add_kernel_backend registered, by backend.
  std::map<std::string, KernelImplementation> implementations{};

  // The factory of the node on `backend` (one of info.backends), and where it came from.
  const KernelFactory& factory_on(const std::string& backend) const;
  const std::string& origin_on(const std::string& backend) const;
};
struct DatasetEntry {
  DatasetInfo info;
  DatasetGenerator generate;
  std::string origin;
};
struct EvaluatorEntry {
  EvaluatorInfo info;
  EvaluatorFactory make;
  std::string origin;
};
struct OutputComparisonEntry {
  OutputComparisonInfo info;
  OutputComparison compare;
  std::string origin;
};
struct BackendEntry {
  BackendInfo info;
  BackendHooks hooks;
  std::string origin;
};

class Registry {
 public:
  Registry();
  ~Registry();
  Registry(const Registry&) = delete;
  Registry& operator=(const Registry&) = delete;

  // Calls `register_all` with a Registrar and adds what it registered, all of it or, when it
  // throws or registers a name already taken, nothing (PluginError naming `origin`).
  void add(const std::string& origin, const std::function<void(Registrar&)>& register_all);

  // Loads a plug-in shared library and adds what it registers; a file already loaded is not
  // loaded again. Throws PluginError: not found, not a shared library, not a robotperf plug-in,
  // built against another API version, or its registration failed.
  void load(const std::filesystem::path& file);

  // Entries live as long as the registry; null when no such name (message type).
  const KernelEntry* find_kernel(const std::string& name) const;
  const DatasetEntry* find_dataset(const std::string& name) const;
  const EvaluatorEntry* find_evaluator(const std::string& name) const;
  const OutputComparisonEntry* find_output_comparison(const std::string& ros_type) const;
  const BackendEntry* find_backend(const std::string& name) const;

  // Sorted by name (message type).
  std::vector<const KernelEntry*> kernels() const;
  std::vector<const DatasetEntry*> datasets() const;
  std::vector<const EvaluatorEntry*> evaluators() const;
  std::vector<const OutputComparisonEntry*> output_comparisons() const;
  std::vector<const BackendEntry*> backends() const;

  // The plug-in files loaded, in load order.
  std::vector<std::filesystem::path> plugins() const;

 private:
  // `label` names the origin in error messages.
  void add_as(const std::string& origin, const std::string& label,
              const std::function<void(Registrar&)>& register_all);

  struct State;
  mutable std::mutex mutex_;
  std::unique_ptr<State> state_;
};

// The registry of this process.
Registry& registry();

// Comma-separated names, for "unknown X (known: ...)" messages.
template <class Entry>
std::string names_of(const std::vector<const Entry*>& entries) {
  std::string out;
  for (const auto* e : entries) out += (out.empty() ? "" : ", ") + e->info.name;
  return out;
}

}  // namespace robotperf::plugin
