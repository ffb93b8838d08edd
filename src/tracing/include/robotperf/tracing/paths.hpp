// Paths through a traced ROS 2 graph, and their latency from the trace alone (docs/design.md
// §3.13): which topic chains the graph has, and how long a message takes along one, linked
// publish → take by topic and source timestamp and take → publish by callback causality. No
// message ID and no header copying is needed, so any graph's trace can be measured.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "robotperf/metrics/latency_stats.hpp"

namespace robotperf::tracing {

// The graph a trace shows (ros2:rcl_node_init, rcl_publisher_init, rcl_subscription_init):
// who publishes and who subscribes each topic. ROS 2's own /rosout and /parameter_events,
// which every node has, are left out.
struct TracedGraph {
  struct Topic {
    std::string name;
    std::vector<std::string> publishers, subscribers;  // node names, sorted, each once
  };
  std::vector<Topic> topics;  // by name
  const Topic* find(const std::string& topic) const;
};

// How far the path search goes: it ends after at most `max_steps` steps (one step: one node
// edge looked at) whatever the graph, so that it always ends quickly on large graphs.
struct PathSearchLimits {
  std::size_t max_paths = 1000;
  std::size_t max_topics = 32;  // a longer path is cut there
  uint64_t max_steps = 1'000'000;
};

// One chain of topics from a source to a sink: nodes[i] subscribes topics[i] and publishes
// topics[i + 1] (the nodes that do, joined by ", " when several).
struct TopicPath {
  std::vector<std::string> topics;
  std::vector<std::string> nodes;
  bool cut = false;          // ended at PathSearchLimits::max_topics, not at a sink
  std::string text() const;  // "/a -> [n1] -> /b -> [n2] -> /c"
};

struct PathSearch {
  std::vector<TopicPath> paths;
  uint64_t steps = 0;
  // Why the search stopped before it had every path ("" when it has them all).
  std::string stopped;
};

// The paths of `graph`: from each source topic (published by a node that subscribes to nothing,
// or with subscribers but no publisher in the trace) along node edges (a node subscribing A and
// publishing B) to a sink (a topic whose subscribers publish nothing further), never through a
// topic twice. Depth first, topics in name order: the same graph gives the same paths.
PathSearch find_paths(const TracedGraph& graph, const PathSearchLimits& limits = {});

// The events of a trace that path latency reads, reduced to what it needs.
struct PathEvent {
  enum class Kind : uint8_t { kPublish, kTake, kCallbackStart, kCallbackEnd };
  int64_t ts = 0;
  int64_t stamp = 0;  // publish and take: the source timestamp that pairs them
  int32_t vpid = 0, vtid = 0;
  uint32_t node = 0;   // publish and take: index into PathEvents::nodes
  uint32_t topic = 0;  // publish and take: index into PathEvents::topics (the path's)
  Kind kind = Kind::kPublish;
};

struct PathEvents {
  std::vector<std::string> topics;  // the path, in order
  std::vector<std::string> nodes;   // each traced node (process and handle) once, by name
  std::vector<PathEvent> events;    // any order
  // Messages published on the path's first topic before this are not measured (a run's warm-up).
  int64_t since = INT64_MIN;
};

// One hop of a path: the transport from topics[i] to the node, and the node to topics[i + 1].
struct PathHop {
  std::string from, node, to;
  // Along the messages that reached the path's end (their first arrival): the take after the
  // publish on `from`, and the publish on `to` after that take. Nanoseconds.
  metrics::SampleStats transport, in_node;
  // Counts over the whole trace (warm-up included).
  uint64_t inputs = 0;       // messages of `from` the node took
  uint64_t outputs = 0;      // messages published on `to`
  uint64_t by_callback = 0;  // outputs published in the callback of their input
  uint64_t by_latest = 0;    // outputs linked to the node's latest input before them
  uint64_t unlinked = 0;     // outputs with no input taken before them
  uint64_t unused = 0;       // inputs no output was linked to: dropped, or merged into another
  uint64_t reused = 0;       // inputs several outputs were linked to (one-to-many)
};

struct PathLatency {
  std::vector<std::string> topics;
  // Publish on the first topic to the first take on the last (its publish when nothing in the
  // trace takes it), once per message of the first topic that reached the end. Nanoseconds.
  metrics::SampleStats end_to_end;
  bool ends_at_take = false;
  uint64_t sources = 0;  // messages published on the first topic (from PathEvents::since on)
  uint64_t reached = 0;  // of them, those that reached the last topic
  // stopped_at[i]: messages of the first topic whose furthest descendant was on topics[i] and
  // went no further (dropped or merged by the node after it); for the last topic, published but
  // never taken. Sums to sources - reached.
  std::vector<uint64_t> stopped_at;
  std::vector<PathHop> hops;
  // Each message that reached the end: its publish on the first topic and its arrival, with the
  // publishing thread (for a timeline).
  struct Instance {
    int64_t start = 0, end = 0;
    int32_t vpid = 0, vtid = 0;
  };
  std::vector<Instance> instances;  // in order of start
};

// The latency of the path `events.topics` (docs/design.md §3.13 states the linking policy).
// Throws std::invalid_argument when the path has fewer than two topics.
PathLatency path_latency(const PathEvents& events);

}  // namespace robotperf::tracing
