#include "robotperf/plugin/registry.hpp"

#include <dlfcn.h>
#include <link.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstring>
#include <deque>
#include <fstream>
#include <map>
#include <optional>
#include <set>

#include "robotperf/msgs/known_types.hpp"
#include "robotperf/plugin/version.hpp"

namespace robotperf::plugin {
namespace {

namespace fs = std::filesystem;

// Reads `size` bytes at `offset` of the file; false when the file is shorter.
bool read_at(std::ifstream& in, uint64_t offset, void* out, std::size_t size) {
  in.clear();
  in.seekg(static_cast<std::streamoff>(offset));
  in.read(static_cast<char*>(out), static_cast<std::streamsize>(size));
  return in && static_cast<std::size_t>(in.gcount()) == size;
}

// The API version ROBOTPERF_PLUGIN recorded in the file's ROBOTPERF_PLUGIN_API_SECTION, read
// without loading it. Nullopt when there is none to read (not an ELF file of this machine's
// class and byte order, a malformed one, or a plug-in built before the section was recorded):
// then dlopen and the version function decide.
std::optional<int> recorded_api_version(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  ElfW(Ehdr) header{};
  if (!read_at(in, 0, &header, sizeof header)) return std::nullopt;
  const unsigned char native_class = sizeof(void*) == 8 ? ELFCLASS64 : ELFCLASS32;
  const unsigned char native_data =
      std::endian::native == std::endian::little ? ELFDATA2LSB : ELFDATA2MSB;
  if (std::memcmp(header.e_ident, ELFMAG, SELFMAG) != 0 ||
      header.e_ident[EI_CLASS] != native_class || header.e_ident[EI_DATA] != native_data ||
      header.e_shentsize != sizeof(ElfW(Shdr)) || header.e_shstrndx >= header.e_shnum) {
    return std::nullopt;
  }
  std::vector<ElfW(Shdr)> sections(header.e_shnum);
  if (!read_at(in, header.e_shoff, sections.data(), sections.size() * sizeof(ElfW(Shdr))))
    return std::nullopt;
  const ElfW(Shdr)& names = sections[header.e_shstrndx];
  constexpr uint64_t kMostNameBytes = 1 << 20;
  if (names.sh_size > kMostNameBytes) return std::nullopt;
  std::string name_table(names.sh_size, '\0');
  if (!read_at(in, names.sh_offset, name_table.data(), name_table.size())) return std::nullopt;
  for (const auto& section : sections) {
    if (section.sh_name >= name_table.size() ||
        std::strcmp(name_table.c_str() + section.sh_name, ROBOTPERF_PLUGIN_API_SECTION) != 0)
      continue;
    int version = 0;
    if (section.sh_type != SHT_PROGBITS || section.sh_size != sizeof version ||
        !read_at(in, section.sh_offset, &version, sizeof version))
      return std::nullopt;
    return version;
  }
  return std::nullopt;
}

std::string version_error(const std::string& where, int version) {
  return where + ": built against plug-in API version " + std::to_string(version) +
         ", this robotperf has version " + std::to_string(ROBOTPERF_PLUGIN_API_VERSION) +
         ": rebuild it against this robotperf";
}

bool known_type(const std::string& ros_type) {
  return msgs::with_message_type(ros_type, []<class T>() {});
}

void check_name(const std::string& what, const std::string& name) {
  if (name.empty()) throw std::invalid_argument(what + " without a name");
  for (unsigned char c : name) {
    if (std::isspace(c) || !std::isprint(c))
      throw std::invalid_argument(what + " '" + name + "': names are printable, without spaces");
  }
}

void check_type(const std::string& who, const std::string& type) {
  if (!known_type(type)) {
    throw std::invalid_argument(who + ": message type '" + type +
                                "' is not one robotperf knows (robotperf/msgs/known_types.hpp)");
  }
}

void check_parameters(const std::string& who, const std::vector<ParameterInfo>& parameters) {
  std::set<std::string> names;
  for (const auto& p : parameters) {
    check_name(who + ": parameter", p.name);
    if (!names.insert(p.name).second)
      throw std::invalid_argument(who + ": parameter '" + p.name + "' declared twice");
    if (p.default_value) {
      try {
        check_value(p, *p.default_value);
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(who + ": default of parameter '" + p.name + "': " + e.what());
      }
    }
  }
}

void check_kernel(const KernelInfo& info, const KernelFactory& factory) {
  check_name("kernel", info.name);
  const std::string who = "kernel " + info.name;
  if (!factory) throw std::invalid_argument(who + ": no factory");
  if (info.backends.empty()) throw std::invalid_argument(who + ": no backend");
  std::set<std::string> ports;
  for (const auto* list : {&info.inputs, &info.outputs}) {
    for (const auto& port : *list) {
      check_name(who + ": port", port.name);
      if (!ports.insert(port.name).second)
        throw std::invalid_argument(who + ": port '" + port.name + "' declared twice");
      if (!port.type.empty()) check_type(who + " port " + port.name, port.type);
    }
  }
  check_parameters(who, info.parameters);
  if (info.control_loop) {
    const auto rate =
        std::ranges::find(info.parameters, info.control_loop->rate_parameter, &ParameterInfo::name);
    if (rate == info.parameters.end() || rate->type != ParameterType::kDouble ||
        !rate->default_value) {
      throw std::invalid_argument(who + ": control loop rate parameter '" +
                                  info.control_loop->rate_parameter +
                                  "' is not a declared double parameter with a default");
    }
  }
}

void check_dataset(const DatasetInfo& info, const DatasetGenerator& generator) {
  check_name("dataset", info.name);
  const std::string who = "dataset " + info.name;
  if (!generator) throw std::invalid_argument(who + ": no generator");
  if (!(info.rate_hz > 0)) throw std::invalid_argument(who + ": rate_hz must be positive");
  if (info.streams.empty()) throw std::invalid_argument(who + ": no stream");
  std::set<std::string> names;
  for (const auto& s : info.streams) {
    check_name(who + ": stream", s.name);
    if (!names.insert(s.name).second)
      throw std::invalid_argument(who + ": stream '" + s.name + "' declared twice");
    check_type(who + " stream " + s.name, s.type);
    try {
      rmw::dds_topic_name(s.topic);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(who + " stream " + s.name + ": " + e.what());
    }
  }
  check_parameters(who, info.workload);
}

void check_evaluator(const EvaluatorInfo& info, const EvaluatorFactory& factory) {
  check_name("evaluator", info.name);
  const std::string who = "evaluator " + info.name;
  if (!factory) throw std::invalid_argument(who + ": no factory");
  check_type(who + " output", info.output_type);
  if (!info.observed_truth_type.empty())
    check_type(who + " observed truth", info.observed_truth_type);
  if (info.truth_roles.empty()) throw std::invalid_argument(who + ": no truth role");
  std::set<std::string> roles, metrics;
  for (const auto& r : info.truth_roles) {
    check_name(who + ": truth role", r);
    if (!roles.insert(r).second)
      throw std::invalid_argument(who + ": truth role '" + r + "' declared twice");
  }
  if (info.metrics.empty()) throw std::invalid_argument(who + ": no metric");
  for (const auto& m : info.metrics) {
    check_name(who + ": metric", m.name);
    if (!metrics.insert(m.name).second)
      throw std::invalid_argument(who + ": metric '" + m.name + "' declared twice");
  }
  check_parameters(who, info.parameters);
}

void check_output_comparison(const OutputComparisonInfo& info, const OutputComparison& compare) {
  check_type("output comparison", info.ros_type);
  if (!compare)
    throw std::invalid_argument("output comparison of " + info.ros_type + ": no comparison");
}

void check_backend(const BackendInfo& info) {
  check_name("backend", info.name);
  if (info.name == kHostBackend) {
    throw std::invalid_argument(std::string("backend '") + kHostBackend +
                                "' is the host's, there without registering it");
  }
}

void check_kernel_backend(const KernelBackendInfo& info, const KernelFactory& factory) {
  check_name("kernel", info.kernel);
  check_name("kernel " + info.kernel + ": backend", info.backend);
  if (!factory) {
    throw std::invalid_argument("kernel " + info.kernel + " on backend " + info.backend +
                                ": no factory");
  }
}

struct StagedKernelBackend {
  KernelBackendInfo info;
  KernelFactory factory;
};

// Collects what one registration adds, checking each description as it comes.
class StagingRegistrar final : public Registrar {
 public:
  void add_kernel(KernelInfo info, KernelFactory factory) override {
    check_kernel(info, factory);
    kernels.push_back({std::move(info), std::move(factory), {}});
  }
  void add_kernel_backend(KernelBackendInfo info, KernelFactory factory) override {
    check_kernel_backend(info, factory);
    kernel_backends.push_back({std::move(info), std::move(factory)});
  }
  void add_dataset(DatasetInfo info, DatasetGenerator generator) override {
    check_dataset(info, generator);
    datasets.push_back({std::move(info), std::move(generator), {}});
  }
  void add_evaluator(EvaluatorInfo info, EvaluatorFactory factory) override {
    check_evaluator(info, factory);
    evaluators.push_back({std::move(info), std::move(factory), {}});
  }
  void add_output_comparison(OutputComparisonInfo info, OutputComparison compare) override {
    check_output_comparison(info, compare);
    output_comparisons.push_back({std::move(info), std::move(compare), {}});
  }
  void add_backend(BackendInfo info, BackendHooks hooks) override {
    check_backend(info);
    backends.push_back({std::move(info), std::move(hooks), {}});
  }

  std::vector<KernelEntry> kernels;
  std::vector<StagedKernelBackend> kernel_backends;
  std::vector<DatasetEntry> datasets;
  std::vector<EvaluatorEntry> evaluators;
  std::vector<OutputComparisonEntry> output_comparisons;
  std::vector<BackendEntry> backends;
};

// What an entry is registered under: its name, or for a comparison its message type.
template <class Entry>
const std::string& key_of(const Entry& e) {
  return e.info.name;
}
const std::string& key_of(const OutputComparisonEntry& e) {
  return e.info.ros_type;
}

template <class Entry>
const Entry* find_in(const std::map<std::string, Entry>& entries, const std::string& name) {
  auto it = entries.find(name);
  return it == entries.end() ? nullptr : &it->second;
}

template <class Entry>
std::vector<const Entry*> all_of(const std::map<std::string, Entry>& entries) {
  std::vector<const Entry*> out;
  for (const auto& [name, e] : entries) out.push_back(&e);
  return out;
}

// The registered name clashes with one already there or with another of the same registration.
template <class Entry>
void check_unique(const char* what, const std::vector<Entry>& staged,
                  const std::map<std::string, Entry>& existing) {
  std::set<std::string> names;
  for (const auto& e : staged) {
    const std::string& key = key_of(e);
    if (auto it = existing.find(key); it != existing.end()) {
      throw std::invalid_argument(std::string(what) + " '" + key + "' is already registered by " +
                                  it->second.origin);
    }
    if (!names.insert(key).second)
      throw std::invalid_argument(std::string(what) + " '" + key + "' registered twice");
  }
}

template <class Entry>
void commit(std::vector<Entry>& staged, std::map<std::string, Entry>& into,
            const std::string& origin) {
  for (auto& e : staged) {
    e.origin = origin;
    std::string key = key_of(e);
    into.emplace(std::move(key), std::move(e));
  }
}

// The entry of the kernel an implementation is for: staged in the same registration (committed
// before the implementations) or registered already. Throws when there is none, or when it has the
// backend already.
const KernelEntry& kernel_for(const KernelBackendInfo& info, const std::vector<KernelEntry>& staged,
                              const std::map<std::string, KernelEntry>& existing) {
  const KernelEntry* kernel = nullptr;
  const auto named = [&](const KernelEntry& e) { return e.info.name == info.kernel; };
  if (auto it = std::ranges::find_if(staged, named); it != staged.end()) {
    kernel = &*it;
  } else if (auto found = existing.find(info.kernel); found != existing.end()) {
    kernel = &found->second;
  }
  if (kernel == nullptr) {
    throw std::invalid_argument("an implementation of kernel '" + info.kernel + "' on backend '" +
                                info.backend + "': no such kernel is registered");
  }
  if (std::ranges::count(kernel->info.backends, info.backend) > 0) {
    throw std::invalid_argument("kernel '" + info.kernel + "' already has backend '" +
                                info.backend + "' (" +
                                (kernel->origin.empty() ? std::string("this registration")
                                                        : kernel->origin_on(info.backend)) +
                                ")");
  }
  return *kernel;
}

// Checks the staged implementations against the kernels they extend (and each other).
void check_kernel_backends(const std::vector<StagedKernelBackend>& staged,
                           const std::vector<KernelEntry>& staged_kernels,
                           const std::map<std::string, KernelEntry>& existing) {
  std::set<std::pair<std::string, std::string>> seen;
  for (const auto& s : staged) {
    kernel_for(s.info, staged_kernels, existing);
    if (!seen.emplace(s.info.kernel, s.info.backend).second) {
      throw std::invalid_argument("kernel '" + s.info.kernel + "' on backend '" + s.info.backend +
                                  "' registered twice");
    }
  }
}

// Adds the implementations to their kernels' entries, which then list their backends.
void commit_kernel_backends(std::vector<StagedKernelBackend>& staged,
                            std::map<std::string, KernelEntry>& kernels,
                            const std::string& origin) {
  for (auto& s : staged) {
    KernelEntry& kernel = kernels.at(s.info.kernel);
    kernel.info.backends.push_back(s.info.backend);
    if (s.info.device_resident) kernel.info.device_resident_backends.push_back(s.info.backend);
    kernel.implementations.emplace(s.info.backend,
                                   KernelImplementation{std::move(s.factory), origin});
  }
}

}  // namespace

const KernelFactory& KernelEntry::factory_on(const std::string& backend) const {
  const auto it = implementations.find(backend);
  return it == implementations.end() ? factory : it->second.factory;
}

const std::string& KernelEntry::origin_on(const std::string& backend) const {
  const auto it = implementations.find(backend);
  return it == implementations.end() ? origin : it->second.origin;
}

struct Registry::State {
  // std::map: entries never move, so the pointers handed out stay valid.
  std::map<std::string, KernelEntry> kernels;
  std::map<std::string, DatasetEntry> datasets;
  std::map<std::string, EvaluatorEntry> evaluators;
  std::map<std::string, OutputComparisonEntry> output_comparisons;  // by message type
  std::map<std::string, BackendEntry> backends;
  std::vector<fs::path> plugins;
};

Registrar::~Registrar() = default;

Registry::Registry() : state_(std::make_unique<State>()) {}
Registry::~Registry() = default;

void Registry::add(const std::string& origin, const std::function<void(Registrar&)>& register_all) {
  add_as(origin, origin, register_all);
}

void Registry::add_as(const std::string& origin, const std::string& label,
                      const std::function<void(Registrar&)>& register_all) {
  StagingRegistrar staged;
  try {
    register_all(staged);
  } catch (const std::exception& e) {
    throw PluginError(label + ": registration failed: " + e.what());
  } catch (...) {
    throw PluginError(label +
                      ": registration failed with an exception that is not a "
                      "std::exception");
  }
  std::lock_guard lock(mutex_);
  try {
    check_unique("kernel", staged.kernels, state_->kernels);
    check_kernel_backends(staged.kernel_backends, staged.kernels, state_->kernels);
    check_unique("dataset", staged.datasets, state_->datasets);
    check_unique("evaluator", staged.evaluators, state_->evaluators);
    check_unique("output comparison of", staged.output_comparisons, state_->output_comparisons);
    check_unique("backend", staged.backends, state_->backends);
  } catch (const std::invalid_argument& e) {
    throw PluginError(label + ": " + e.what());
  }
  commit(staged.kernels, state_->kernels, origin);
  commit_kernel_backends(staged.kernel_backends, state_->kernels, origin);
  commit(staged.datasets, state_->datasets, origin);
  commit(staged.evaluators, state_->evaluators, origin);
  commit(staged.output_comparisons, state_->output_comparisons, origin);
  commit(staged.backends, state_->backends, origin);
}

void Registry::load(const fs::path& file) {
  std::error_code ec;
  const fs::path path = fs::canonical(file, ec);
  if (ec) throw PluginError("plug-in " + file.string() + ": file not found");
  {
    std::lock_guard lock(mutex_);
    if (std::ranges::count(state_->plugins, path)) return;
  }
  const std::string where = "plug-in " + path.string();
  // Before loading: a plug-in of another version may need symbols this robotperf lacks (dlopen
  // would fail on one) or run code at load.
  if (const auto v = recorded_api_version(path); v && *v != ROBOTPERF_PLUGIN_API_VERSION)
    throw PluginError(version_error(where, *v));
  // RTLD_LOCAL: two plug-ins may define the same internal names without clashing.
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* why = dlerror();
    throw PluginError(where +
                      ": cannot be loaded as a shared library: " + (why ? why : "unknown error"));
  }
  using VersionFunction = int (*)();
  using RegisterFunction = void (*)(Registrar&);
  auto version = reinterpret_cast<VersionFunction>(dlsym(handle, "robotperf_plugin_api_version"));
  auto register_all =
      reinterpret_cast<RegisterFunction>(dlsym(handle, "robotperf_plugin_register"));
  if (version == nullptr || register_all == nullptr) {
    dlclose(handle);
    throw PluginError(where +
                      ": not a robotperf plug-in (it has no robotperf_plugin_api_version and "
                      "robotperf_plugin_register; define them with ROBOTPERF_PLUGIN from "
                      "robotperf/plugin.hpp)");
  }
  if (const int v = version(); v != ROBOTPERF_PLUGIN_API_VERSION) {
    dlclose(handle);
    throw PluginError(version_error(where, v));
  }
  // The library stays loaded for the life of the process: its factories and the code of the
  // nodes they build live in it.
  add_as(path.string(), where, [&](Registrar& r) { register_all(r); });
  std::lock_guard lock(mutex_);
  state_->plugins.push_back(path);
}

const KernelEntry* Registry::find_kernel(const std::string& name) const {
  std::lock_guard lock(mutex_);
  return find_in(state_->kernels, name);
}

const DatasetEntry* Registry::find_dataset(const std::string& name) const {
  std::lock_guard lock(mutex_);
  return find_in(state_->datasets, name);
}

const EvaluatorEntry* Registry::find_evaluator(const std::string& name) const {
  std::lock_guard lock(mutex_);
  return find_in(state_->evaluators, name);
}

const OutputComparisonEntry* Registry::find_output_comparison(const std::string& ros_type) const {
  std::lock_guard lock(mutex_);
  return find_in(state_->output_comparisons, ros_type);
}

const BackendEntry* Registry::find_backend(const std::string& name) const {
  std::lock_guard lock(mutex_);
  return find_in(state_->backends, name);
}

std::vector<const KernelEntry*> Registry::kernels() const {
  std::lock_guard lock(mutex_);
  return all_of(state_->kernels);
}

std::vector<const DatasetEntry*> Registry::datasets() const {
  std::lock_guard lock(mutex_);
  return all_of(state_->datasets);
}

std::vector<const EvaluatorEntry*> Registry::evaluators() const {
  std::lock_guard lock(mutex_);
  return all_of(state_->evaluators);
}

std::vector<const OutputComparisonEntry*> Registry::output_comparisons() const {
  std::lock_guard lock(mutex_);
  return all_of(state_->output_comparisons);
}

std::vector<const BackendEntry*> Registry::backends() const {
  std::lock_guard lock(mutex_);
  return all_of(state_->backends);
}

std::vector<fs::path> Registry::plugins() const {
  std::lock_guard lock(mutex_);
  return state_->plugins;
}

Registry& registry() {
  static Registry instance;
  return instance;
}

}  // namespace robotperf::plugin
