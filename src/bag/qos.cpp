#include "robotperf/bag/qos.hpp"

#include <yaml-cpp/yaml.h>

#include <array>
#include <sstream>
#include <stdexcept>
#include <string_view>

namespace robotperf::bag {
namespace {

struct EnumName {
  int value;
  std::string_view name;
};

constexpr std::array kHistory{EnumName{0, "system_default"}, EnumName{1, "keep_last"},
                              EnumName{2, "keep_all"}, EnumName{3, "unknown"}};
constexpr std::array kReliability{EnumName{0, "system_default"}, EnumName{1, "reliable"},
                                  EnumName{2, "best_effort"}, EnumName{3, "unknown"},
                                  EnumName{4, "best_available"}};
constexpr std::array kDurability{EnumName{0, "system_default"}, EnumName{1, "transient_local"},
                                 EnumName{2, "volatile"}, EnumName{3, "unknown"},
                                 EnumName{4, "best_available"}};
constexpr std::array kLiveliness{EnumName{0, "system_default"}, EnumName{1, "automatic"},
                                 EnumName{2, "manual_by_node"}, EnumName{3, "manual_by_topic"},
                                 EnumName{4, "unknown"},        EnumName{5, "best_available"}};

template <std::size_t N>
int parse_enum(const YAML::Node& node, const char* key, const std::array<EnumName, N>& names) {
  const YAML::Node v = node[key];
  if (!v) return 0;
  if (!v.IsScalar())
    throw std::invalid_argument(std::string("QoS ") + key + " is not a name or a number");
  const std::string& text = v.Scalar();
  for (const auto& e : names) {
    if (text == e.name || text == std::to_string(e.value)) return e.value;
  }
  throw std::invalid_argument(std::string("QoS ") + key + ": unknown value '" + text + "'");
}

template <std::size_t N>
std::string_view enum_name(int value, const std::array<EnumName, N>& names) {
  for (const auto& e : names) {
    if (e.value == value) return e.name;
  }
  return "unknown";
}

QosDuration parse_duration(const YAML::Node& node, const char* key) {
  const YAML::Node v = node[key];
  if (!v) return {};
  if (!v.IsMap()) throw std::invalid_argument(std::string("QoS ") + key + " is not {sec, nsec}");
  return {v["sec"] ? v["sec"].as<int64_t>() : 0, v["nsec"] ? v["nsec"].as<int64_t>() : 0};
}

bool is_integer(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

YAML::Node load_profiles(const std::string& yaml) {
  try {
    return YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument("offered_qos_profiles is not valid YAML: " + e.msg);
  }
}

}  // namespace

std::vector<QosProfile> parse_qos_profiles(const std::string& yaml) {
  std::vector<QosProfile> out;
  const YAML::Node root = load_profiles(yaml);
  if (!root || root.IsNull()) return out;
  if (!root.IsSequence())
    throw std::invalid_argument("offered_qos_profiles is not a YAML sequence of profiles");
  try {
    for (const auto& node : root) {
      if (!node.IsMap()) throw std::invalid_argument("a QoS profile is not a YAML map");
      QosProfile p;
      p.history = parse_enum(node, "history", kHistory);
      p.depth = node["depth"] ? node["depth"].as<int64_t>() : 0;
      p.reliability = parse_enum(node, "reliability", kReliability);
      p.durability = parse_enum(node, "durability", kDurability);
      p.deadline = parse_duration(node, "deadline");
      p.lifespan = parse_duration(node, "lifespan");
      p.liveliness = parse_enum(node, "liveliness", kLiveliness);
      p.liveliness_lease_duration = parse_duration(node, "liveliness_lease_duration");
      p.avoid_ros_namespace_conventions = node["avoid_ros_namespace_conventions"] &&
                                          node["avoid_ros_namespace_conventions"].as<bool>();
      out.push_back(p);
    }
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument("offered_qos_profiles: " + e.msg);
  }
  return out;
}

std::string qos_profiles_to_yaml(const std::vector<QosProfile>& profiles) {
  // The layout rosbag2 (Humble) writes: block sequence, two-space indent, no
  // trailing newline.
  std::ostringstream out;
  auto duration = [&](const char* key, const QosDuration& d) {
    out << "  " << key << ":\n    sec: " << d.sec << "\n    nsec: " << d.nsec << "\n";
  };
  for (std::size_t i = 0; i < profiles.size(); ++i) {
    const QosProfile& p = profiles[i];
    if (i) out << "\n";
    out << "- history: " << p.history << "\n  depth: " << p.depth
        << "\n  reliability: " << p.reliability << "\n  durability: " << p.durability << "\n";
    duration("deadline", p.deadline);
    duration("lifespan", p.lifespan);
    out << "  liveliness: " << p.liveliness << "\n";
    duration("liveliness_lease_duration", p.liveliness_lease_duration);
    out << "  avoid_ros_namespace_conventions: "
        << (p.avoid_ros_namespace_conventions ? "true" : "false");
  }
  return out.str();
}

bool qos_uses_integer_enums(const std::string& yaml) {
  const YAML::Node root = load_profiles(yaml);
  if (!root || root.IsNull()) return true;
  if (!root.IsSequence()) return false;
  for (const auto& node : root) {
    if (!node.IsMap()) return false;
    for (const char* key : {"history", "reliability", "durability", "liveliness"}) {
      const YAML::Node v = node[key];
      if (v && !(v.IsScalar() && is_integer(v.Scalar()))) return false;
    }
  }
  return true;
}

std::string qos_with_integer_enums(const std::string& yaml) {
  if (qos_uses_integer_enums(yaml)) return yaml;
  return qos_profiles_to_yaml(parse_qos_profiles(yaml));
}

std::string describe_qos(const QosProfile& p) {
  std::string s = std::string(enum_name(p.reliability, kReliability)) + ", " +
                  std::string(enum_name(p.durability, kDurability)) + ", " +
                  std::string(enum_name(p.history, kHistory));
  if (p.history == 1) s += " " + std::to_string(p.depth);
  return s;
}

}  // namespace robotperf::bag
