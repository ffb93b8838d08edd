// Path search over a traced graph and path latency from publish/take/callback events
// (docs/design.md §3.13).
#include "robotperf/tracing/paths.hpp"

#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>
#include <unordered_map>

namespace robotperf::tracing {

const TracedGraph::Topic* TracedGraph::find(const std::string& topic) const {
  auto it = std::lower_bound(topics.begin(), topics.end(), topic,
                             [](const Topic& t, const std::string& name) { return t.name < name; });
  return it != topics.end() && it->name == topic ? &*it : nullptr;
}

std::string TopicPath::text() const {
  std::string s;
  for (std::size_t i = 0; i < topics.size(); ++i) {
    if (i > 0) s += " -> [" + nodes[i - 1] + "] -> ";
    s += topics[i];
  }
  if (cut) s += " -> ...";
  return s;
}

namespace {

// A node's edges: the topics it publishes, for each topic it subscribes.
struct NodeEdges {
  std::vector<std::size_t> subscribed, published;  // topic numbers
};

}  // namespace

PathSearch find_paths(const TracedGraph& graph, const PathSearchLimits& limits) {
  PathSearch result;
  const std::size_t n = graph.topics.size();
  std::map<std::string, NodeEdges> nodes;
  for (std::size_t t = 0; t < n; ++t) {
    for (const auto& p : graph.topics[t].publishers) nodes[p].published.push_back(t);
    for (const auto& s : graph.topics[t].subscribers) nodes[s].subscribed.push_back(t);
  }
  // next[t]: (topic, the nodes that carry t to it), topics in name order.
  std::vector<std::vector<std::pair<std::size_t, std::string>>> next(n);
  for (std::size_t t = 0; t < n; ++t) {
    std::map<std::size_t, std::string> to;
    for (const auto& s : graph.topics[t].subscribers) {
      for (const std::size_t b : nodes[s].published) {
        if (b == t) continue;
        std::string& names = to[b];
        names += (names.empty() ? "" : ", ") + s;
      }
    }
    next[t].assign(to.begin(), to.end());
  }
  std::vector<std::size_t> sources;
  for (std::size_t t = 0; t < n; ++t) {
    const auto& topic = graph.topics[t];
    const bool from_source_node =
        std::any_of(topic.publishers.begin(), topic.publishers.end(),
                    [&](const std::string& p) { return nodes[p].subscribed.empty(); });
    if (from_source_node || (topic.publishers.empty() && !topic.subscribers.empty()))
      sources.push_back(t);
  }

  // Depth first with an explicit stack: frame = (topic, the next of its edges to look at).
  std::vector<std::pair<std::size_t, std::size_t>> stack;
  std::vector<char> on_path(n, 0);
  auto emit = [&](bool cut) {
    TopicPath p;
    for (std::size_t i = 0; i < stack.size(); ++i) {
      p.topics.push_back(graph.topics[stack[i].first].name);
      if (i > 0) {
        const auto& edges = next[stack[i - 1].first];
        p.nodes.push_back(edges[stack[i - 1].second - 1].second);
      }
    }
    p.cut = cut;
    result.paths.push_back(std::move(p));
  };
  for (const std::size_t source : sources) {
    stack.assign(1, {source, 0});
    on_path[source] = 1;
    bool extended = false;  // whether the top of the stack was extended by some edge
    while (!stack.empty()) {
      if (result.paths.size() >= limits.max_paths) {
        result.stopped = "stopped at " + std::to_string(limits.max_paths) + " paths";
        break;
      }
      if (result.steps >= limits.max_steps) {
        result.stopped = "stopped after " + std::to_string(limits.max_steps) + " search steps";
        break;
      }
      auto& [topic, edge] = stack.back();
      if (stack.size() >= limits.max_topics) {
        emit(true);
        on_path[topic] = 0;
        stack.pop_back();
        extended = true;
        continue;
      }
      if (edge < next[topic].size()) {
        ++result.steps;
        const std::size_t to = next[topic][edge++].first;
        if (on_path[to]) continue;
        on_path[to] = 1;
        stack.push_back({to, 0});
        extended = false;
        continue;
      }
      // Every edge looked at: a sink when none led anywhere new.
      if (!extended) emit(false);
      on_path[topic] = 0;
      stack.pop_back();
      extended = true;
    }
    std::fill(on_path.begin(), on_path.end(), 0);
    if (!result.stopped.empty()) break;
  }
  return result;
}

namespace {

constexpr int64_t kNone = -1;

struct Message {
  int64_t publish_ts;
  std::size_t publish;  // index of the publish in the event list
};

}  // namespace

PathLatency path_latency(const PathEvents& in) {
  const std::size_t k = in.topics.size();
  if (k < 2) throw std::invalid_argument("a path needs at least two topics");
  PathLatency out;
  out.topics = in.topics;
  out.stopped_at.assign(k, 0);

  // Events in thread order: callback causality is read along each thread.
  std::vector<std::size_t> order(in.events.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const PathEvent& x = in.events[a];
    const PathEvent& y = in.events[b];
    if (x.vpid != y.vpid) return x.vpid < y.vpid;
    if (x.vtid != y.vtid) return x.vtid < y.vtid;
    if (x.ts != y.ts) return x.ts < y.ts;
    return a < b;
  });
  // The take whose callback each publish ran in (kNone outside a callback, or in one no take
  // started: a timer's).
  std::vector<int64_t> callback_input(in.events.size(), kNone);
  {
    int32_t vpid = 0, vtid = 0;
    bool first = true;
    int64_t pending = kNone, input = kNone;
    bool in_callback = false;
    for (const std::size_t i : order) {
      const PathEvent& e = in.events[i];
      if (first || e.vpid != vpid || e.vtid != vtid) {
        first = false;
        vpid = e.vpid;
        vtid = e.vtid;
        pending = input = kNone;
        in_callback = false;
      }
      switch (e.kind) {
        case PathEvent::Kind::kTake:
          pending = static_cast<int64_t>(i);
          break;
        case PathEvent::Kind::kCallbackStart:
          input = pending;
          pending = kNone;
          in_callback = true;
          break;
        case PathEvent::Kind::kCallbackEnd:
          input = kNone;
          in_callback = false;
          break;
        case PathEvent::Kind::kPublish:
          if (in_callback) callback_input[i] = input;
          break;
      }
    }
  }

  // Per topic: its messages by source timestamp (the first publish of each), and the first take
  // of each; per (node, topic): its takes in time order, for the latest-input link.
  std::vector<std::unordered_map<int64_t, Message>> messages(k);
  std::vector<std::unordered_map<int64_t, std::size_t>> first_take(k);
  std::map<std::pair<uint32_t, uint32_t>, std::vector<std::size_t>> takes_of;
  for (const std::size_t i : order) {
    const PathEvent& e = in.events[i];
    if (e.topic >= k) continue;
    if (e.kind == PathEvent::Kind::kPublish) {
      auto [it, inserted] = messages[e.topic].try_emplace(e.stamp, Message{e.ts, i});
      if (!inserted && e.ts < it->second.publish_ts) it->second = {e.ts, i};
    } else if (e.kind == PathEvent::Kind::kTake) {
      auto [it, inserted] = first_take[e.topic].try_emplace(e.stamp, i);
      if (!inserted && e.ts < in.events[it->second].ts) it->second = i;
      takes_of[{e.node, e.topic}].push_back(i);
    }
  }
  for (auto& [key, takes] : takes_of) {
    std::stable_sort(takes.begin(), takes.end(), [&](std::size_t a, std::size_t b) {
      return in.events[a].ts < in.events[b].ts;
    });
  }

  // Each message on topic i+1 linked to its input on topic i: the take of the callback that
  // published it, or else the publishing node's latest take of topic i before the publish.
  std::vector<std::unordered_map<int64_t, std::size_t>> parent(k);  // stamp -> the take
  std::vector<std::unordered_map<int64_t, uint64_t>> uses(k);       // stamp on i -> outputs
  out.hops.resize(k - 1);
  for (std::size_t i = 0; i + 1 < k; ++i) {
    PathHop& hop = out.hops[i];
    hop.from = in.topics[i];
    hop.to = in.topics[i + 1];
    std::set<std::string> hop_nodes;
    std::set<uint32_t> publishers;  // of topic i+1
    for (const auto& [stamp, m] : messages[i + 1]) publishers.insert(in.events[m.publish].node);
    for (const auto& [stamp, m] : messages[i + 1]) {
      const PathEvent& pub = in.events[m.publish];
      const int64_t direct = callback_input[m.publish];
      std::size_t take = 0;
      bool linked = false;
      if (direct != kNone && in.events[static_cast<std::size_t>(direct)].topic == i &&
          in.events[static_cast<std::size_t>(direct)].node == pub.node) {
        take = static_cast<std::size_t>(direct);
        linked = true;
        ++hop.by_callback;
      } else if (auto t = takes_of.find({pub.node, static_cast<uint32_t>(i)});
                 t != takes_of.end()) {
        auto it = std::partition_point(t->second.begin(), t->second.end(),
                                       [&](std::size_t x) { return in.events[x].ts <= pub.ts; });
        if (it != t->second.begin()) {
          take = *std::prev(it);
          linked = true;
          ++hop.by_latest;
        }
      }
      if (!linked) {
        ++hop.unlinked;
        continue;
      }
      hop_nodes.insert(in.nodes[pub.node]);
      parent[i + 1][stamp] = take;
      ++uses[i][in.events[take].stamp];
    }
    for (const auto& [node_topic, takes] : takes_of) {
      if (node_topic.second != i || !publishers.contains(node_topic.first)) continue;
      hop.inputs += takes.size();
      for (const std::size_t t : takes) {
        auto u = uses[i].find(in.events[t].stamp);
        if (u == uses[i].end()) ++hop.unused;
      }
    }
    for (const auto& [stamp, n] : uses[i]) hop.reused += n > 1 ? 1 : 0;
    hop.outputs = messages[i + 1].size();
    for (const auto& name : hop_nodes) hop.node += (hop.node.empty() ? "" : ", ") + name;
  }

  // Each message of the last topic traced back to the first; the first arrival of each source
  // counts.
  out.ends_at_take = !first_take[k - 1].empty();
  auto arrival = [&](int64_t stamp, const Message& m) {
    if (!out.ends_at_take) return m.publish_ts;
    auto t = first_take[k - 1].find(stamp);
    return t != first_take[k - 1].end() ? in.events[t->second].ts : kNone;
  };
  struct Arrival {
    int64_t ts;
    int64_t end_stamp;
  };
  std::unordered_map<int64_t, Arrival> first_arrival;  // source stamp -> its first arrival
  // furthest[stamp on topic 0]: the furthest topic one of its descendants reached.
  std::unordered_map<int64_t, std::size_t> furthest;
  // The message of topic 0 a message of `topic` comes from (kNone when a link is missing).
  auto source_of = [&](std::size_t topic, int64_t stamp) -> int64_t {
    for (std::size_t i = topic; i > 0; --i) {
      auto p = parent[i].find(stamp);
      if (p == parent[i].end()) return kNone;
      stamp = in.events[p->second].stamp;
      if (!messages[i - 1].contains(stamp)) return kNone;
    }
    return stamp;
  };
  for (std::size_t i = 1; i < k; ++i) {
    for (const auto& [stamp, m] : messages[i]) {
      const int64_t source = source_of(i, stamp);
      if (source == kNone) continue;
      auto [it, inserted] = furthest.try_emplace(source, i);
      if (!inserted) it->second = std::max(it->second, i);
      if (i != k - 1) continue;
      const int64_t at = arrival(stamp, m);
      if (at == kNone) continue;
      auto [a, fresh] = first_arrival.try_emplace(source, Arrival{at, stamp});
      if (!fresh && at < a->second.ts) a->second = {at, stamp};
    }
  }

  std::vector<double> end_to_end;
  std::vector<std::vector<double>> transport(k - 1), in_node(k - 1);
  for (const auto& [stamp, m] : messages[0]) {
    if (m.publish_ts < in.since) continue;
    ++out.sources;
    auto a = first_arrival.find(stamp);
    if (a == first_arrival.end()) {
      auto f = furthest.find(stamp);
      const std::size_t reached = f != furthest.end() ? f->second : 0;
      ++out.stopped_at[reached];
      continue;
    }
    ++out.reached;
    end_to_end.push_back(static_cast<double>(a->second.ts - m.publish_ts));
    const PathEvent& source = in.events[m.publish];
    out.instances.push_back({m.publish_ts, a->second.ts, source.vpid, source.vtid});
    // The chain's hops, walked back from the end.
    int64_t s = a->second.end_stamp;
    for (std::size_t i = k - 1; i > 0; --i) {
      const std::size_t take = parent[i].at(s);
      const PathEvent& t = in.events[take];
      transport[i - 1].push_back(
          static_cast<double>(t.ts - messages[i - 1].at(t.stamp).publish_ts));
      in_node[i - 1].push_back(static_cast<double>(messages[i].at(s).publish_ts - t.ts));
      s = t.stamp;
    }
  }
  std::sort(out.instances.begin(), out.instances.end(),
            [](const auto& x, const auto& y) { return x.start < y.start; });
  if (!end_to_end.empty()) out.end_to_end = metrics::compute_stats(end_to_end);
  for (std::size_t i = 0; i + 1 < k; ++i) {
    if (!transport[i].empty()) out.hops[i].transport = metrics::compute_stats(transport[i]);
    if (!in_node[i].empty()) out.hops[i].in_node = metrics::compute_stats(in_node[i]);
  }
  return out;
}

}  // namespace robotperf::tracing
