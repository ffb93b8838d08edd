// rosbag2's offered_qos_profiles: a YAML sequence of QoS profiles.
//
// Two encodings exist: Humble and Iron write the policies as integers of the
// rmw enums (history: 1), Jazzy writes their names (history: keep_last), and
// metadata.yaml version 9 stores the sequence as YAML instead of a string.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace robotperf::bag {

struct QosDuration {
  int64_t sec = 0;
  int64_t nsec = 0;
  friend bool operator==(const QosDuration&, const QosDuration&) = default;
};

// Values of the rmw enums (rmw/types.h), which the integer encoding stores.
struct QosProfile {
  int history = 0;  // 0 system_default, 1 keep_last, 2 keep_all, 3 unknown
  int64_t depth = 0;
  int reliability = 0;  // 0 system_default, 1 reliable, 2 best_effort, 3 unknown, 4 best_available
  int durability =
      0;  // 0 system_default, 1 transient_local, 2 volatile, 3 unknown, 4 best_available
  QosDuration deadline;
  QosDuration lifespan;
  int liveliness =
      0;  // 0 system_default, 1 automatic, 3 manual_by_topic, 4 unknown, 5 best_available
  QosDuration liveliness_lease_duration;
  bool avoid_ros_namespace_conventions = false;
  friend bool operator==(const QosProfile&, const QosProfile&) = default;
};

// Parses YAML text of either encoding; throws std::invalid_argument saying what
// is wrong. An empty string is an empty list.
std::vector<QosProfile> parse_qos_profiles(const std::string& yaml);

// The integer encoding, as Humble writes it.
std::string qos_profiles_to_yaml(const std::vector<QosProfile>& profiles);

// True when the text uses the integer encoding throughout (Humble can read it).
bool qos_uses_integer_enums(const std::string& yaml);

// `yaml` unchanged when it already uses integers, else re-encoded with integers.
std::string qos_with_integer_enums(const std::string& yaml);

// "reliable, transient_local, keep_last 10" for `bag info`.
std::string describe_qos(const QosProfile& profile);

}  // namespace robotperf::bag
