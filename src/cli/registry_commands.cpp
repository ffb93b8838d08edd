#include "registry_commands.hpp"

#include <algorithm>
#include <cstdlib>
#include <sstream>

#include "robotperf/plugin/registry.hpp"
#include "robotperf/report/run_store.hpp"

namespace robotperf::cli {
namespace {

namespace fs = std::filesystem;

std::string ports(const std::vector<plugin::PortInfo>& list) {
  std::string out;
  for (const auto& p : list) {
    out += (out.empty() ? "" : ", ") + p.name + " [" +
           (p.type.empty() ? std::string("any: set by a parameter") : p.type) + "]";
  }
  return out.empty() ? "-" : out;
}

void parameters(std::ostream& out, const std::vector<plugin::ParameterInfo>& list,
                const char* heading) {
  if (list.empty()) return;
  out << "  " << heading << ":\n";
  for (const auto& p : list) {
    out << "    " << p.name << " (" << plugin::type_name(p.type);
    if (p.default_value)
      out << ", default " << (p.default_value->empty() ? "\"\"" : *p.default_value);
    if (const std::string range = plugin::bounds_text(p.bounds); !range.empty())
      out << ", " << range;
    out << "): " << p.doc << "\n";
  }
}

std::string origin(const std::string& where) {
  return "from " + where;
}

}  // namespace

int list_kernels(std::ostream& out) {
  for (const auto* k : plugin::registry().kernels()) {
    const auto& i = k->info;
    const std::string backends = report::joined(i.backends, ", ");
    out << i.name << "  (" << origin(k->origin) << "; backends: " << backends << ")\n";
    out << "  " << i.description << "\n";
    // Implementations another plug-in brought (Registrar::add_kernel_backend).
    for (const auto& [backend, implementation] : k->implementations) {
      if (implementation.origin != k->origin)
        out << "  on " << backend << ": " << origin(implementation.origin) << "\n";
    }
    out << "  in:  " << ports(i.inputs) << "\n";
    out << "  out: " << ports(i.outputs) << "\n";
    if (!i.device_resident_backends.empty()) {
      std::string handed;
      for (const auto* list : {&i.inputs, &i.outputs}) {
        for (const auto& p : *list) {
          if (p.device_resident)
            handed += std::string(handed.empty() ? "" : ", ") +
                      (list == &i.inputs ? "in " : "out ") + p.name;
        }
      }
      out << "  device-resident on " << report::joined(i.device_resident_backends, ", ") << ": "
          << handed << " (run --device-resident)\n";
    }
    if (i.control_loop) {
      out << "  runs a control loop at parameter " << i.control_loop->rate_parameter
          << " (run --update-rate)\n";
    }
    parameters(out, i.parameters, "parameters");
    out << "\n";
  }
  return 0;
}

int list_datasets(std::ostream& out) {
  for (const auto* d : plugin::registry().datasets()) {
    const auto& i = d->info;
    out << i.name << "  (" << origin(d->origin) << "; " << i.rate_hz << " Hz, " << i.frames
        << " frames" << (i.workload.empty() ? "" : " with the default workload") << ")\n";
    out << "  " << i.description << "\n";
    out << "  streams:\n";
    std::size_t name_width = 0, topic_width = 0, type_width = 0;
    for (const auto& s : i.streams) {
      name_width = std::max(name_width, s.name.size());
      topic_width = std::max(topic_width, s.topic.size());
      type_width = std::max(type_width, s.type.size());
    }
    for (const auto& s : i.streams) {
      out << "    " << s.name << std::string(name_width - s.name.size() + 2, ' ') << s.topic
          << std::string(topic_width - s.topic.size() + 2, ' ') << s.type
          << std::string(type_width - s.type.size() + 2, ' ') << (s.truth ? "[truth] " : "")
          << s.doc << "\n";
    }
    parameters(out, i.workload, "workload (benchmark.yaml workload:)");
    out << "\n";
  }
  return 0;
}

int list_evaluators(std::ostream& out) {
  for (const auto* e : plugin::registry().evaluators()) {
    const auto& i = e->info;
    out << i.name << "  (" << origin(e->origin) << "; reads " << i.output_type << ")\n";
    out << "  " << i.description << "\n";
    std::string roles;
    for (const auto& r : i.truth_roles) roles += (roles.empty() ? "" : ", ") + r;
    out << "  truth roles: " << roles << "\n";
    if (!i.observed_truth_type.empty())
      out << "  observed truth: " << i.observed_truth_type << " (functional.observed_truth)\n";
    out << "  metrics:\n";
    for (const auto& m : i.metrics)
      out << "    " << m.name << " (" << m.unit << "): " << m.description << "\n";
    parameters(out, i.parameters, "parameters (graph.yaml functional: parameters:)");
    out << "\n";
  }
  return 0;
}

void describe_node(std::ostream& out, const harness::NodeSpec& node) {
  const plugin::KernelEntry& k = harness::kernel_of(node);
  out << "  " << node.name << ": " << node.kernel << " (" << node.backend << "; "
      << origin(k.origin) << ")" << (node.host.empty() ? "" : " on host " + node.host) << "\n";
  for (const auto* list : {&k.info.inputs, &k.info.outputs}) {
    for (const auto& p : *list) {
      auto topic = node.topics.find(p.name);
      out << "      " << (list == &k.info.inputs ? "in  " : "out ") << p.name << " = "
          << (topic == node.topics.end() ? std::string("(not wired)") : topic->second)
          << (p.type.empty() ? "" : "  [" + p.type + "]") << "\n";
    }
  }
  for (const auto& p : k.info.parameters) {
    auto given = node.parameters.find(p.name);
    if (given != node.parameters.end()) {
      out << "      param " << p.name << " = " << given->second << "\n";
    } else if (p.default_value) {
      out << "      param " << p.name << " = " << *p.default_value << " (default)\n";
    } else {
      out << "      param " << p.name << " computed: " << p.doc << "\n";
    }
  }
}

void load_plugins(const std::vector<std::string>& files) {
  auto& registry = plugin::registry();
  if (const char* env = std::getenv("ROBOTPERF_PLUGIN_PATH"); env && *env) {
    std::stringstream entries(env);
    std::string entry;
    while (std::getline(entries, entry, ':')) {
      if (entry.empty()) continue;
      std::error_code ec;
      if (!fs::is_directory(entry, ec)) {
        registry.load(entry);
        continue;
      }
      std::vector<fs::path> libraries;
      for (const auto& f : fs::directory_iterator(entry)) {
        if (f.path().extension() == ".so") libraries.push_back(f.path());
      }
      std::ranges::sort(libraries);
      for (const auto& f : libraries) registry.load(f);
    }
  }
  for (const auto& f : files) registry.load(f);
}

}  // namespace robotperf::cli
