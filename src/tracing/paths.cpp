// Path search over a traced graph and path latency from publish/take/callback events
// (docs/design.md §3.13).
#include "robotperf/tracing/paths.hpp"

#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>
#include <tuple>
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
constexpr uint32_t kNoMessage = UINT32_MAX;

// A message of one of the path's topics: its first publish, its first take, and (beyond the first
// topic) the take on the topic before that it is linked to.
struct Message {
  int64_t publish_ts;
  std::size_t publish;         // index of the publish event
  int64_t first_take = kNone;  // index of its first take event
  int64_t parent = kNone;      // index of the take it is linked to
  uint32_t uses = 0;           // outputs on the next topic linked to it
};

// The messages of one topic, found by source timestamp.
struct TopicMessages {
  std::vector<Message> messages;
  std::unordered_map<int64_t, uint32_t> by_stamp;
  uint32_t find(int64_t stamp) const {
    auto it = by_stamp.find(stamp);
    return it == by_stamp.end() ? kNoMessage : it->second;
  }
};

// An event's place in thread order (its thread, then its time): compact keys to sort, rather
// than indices through the events, which millions of them make slow.
struct Order {
  uint64_t thread;
  int64_t ts;
  std::size_t index;
};

// The links of a path's messages (docs/design.md §3.13), found in steps.
class PathLinks {
 public:
  explicit PathLinks(const PathEvents& events)
      : in(events), ev(events.events), k(events.topics.size()) {
    const std::vector<Order> order = thread_order();
    find_callback_inputs(order);
    collect_messages(order);
  }

  // Each message on topic i+1 linked to its input on topic i, with the hop's counts.
  void link_hop(std::size_t i, PathHop& hop);
  // Each message traced back to the first topic: how far each source message got, and its first
  // arrival at the end.
  struct Arrivals {
    std::vector<std::size_t> furthest;  // per message of topic 0: the furthest topic reached
    std::vector<int64_t> ts;            // its first arrival at the end, or kNone
    std::vector<uint32_t> message;      // the message of the last topic that arrived first
  };
  Arrivals first_arrivals(bool ends_at_take) const;
  bool last_topic_taken() const;
  // End to end and per-hop times along the chains that reached the end, and the counts.
  void measure(const Arrivals& arrivals, PathLatency& out) const;

 private:
  std::vector<Order> thread_order() const;
  void find_callback_inputs(const std::vector<Order>& order);
  void collect_messages(const std::vector<Order>& order);
  // The message of topic 0 a message of `topic` comes from (kNoMessage when a link is missing).
  uint32_t source_of(std::size_t topic, uint32_t m) const;

  const PathEvents& in;
  const std::vector<PathEvent>& ev;
  const std::size_t k;
  std::vector<int64_t> callback_input;  // per event; see find_callback_inputs
  std::vector<TopicMessages> topics;
  std::map<std::pair<uint32_t, uint32_t>, std::vector<std::size_t>> takes_of;
};

// Events in thread order, each thread's by time: callback causality is read along each thread.
std::vector<Order> PathLinks::thread_order() const {
  std::vector<Order> order(ev.size());
  for (std::size_t i = 0; i < ev.size(); ++i) {
    order[i] = {static_cast<uint64_t>(static_cast<uint32_t>(ev[i].vpid)) << 32 |
                    static_cast<uint32_t>(ev[i].vtid),
                ev[i].ts, i};
  }
  std::sort(order.begin(), order.end(), [](const Order& x, const Order& y) {
    return std::tie(x.thread, x.ts, x.index) < std::tie(y.thread, y.ts, y.index);
  });
  return order;
}

// The take whose callback each publish ran in (kNone outside a callback, or in one no take
// started: a timer's).
void PathLinks::find_callback_inputs(const std::vector<Order>& order) {
  callback_input.assign(ev.size(), kNone);
  uint64_t thread = 0;
  bool first = true;
  int64_t pending = kNone, input = kNone;
  bool in_callback = false;
  for (const Order& o : order) {
    const PathEvent& e = ev[o.index];
    if (first || o.thread != thread) {
      first = false;
      thread = o.thread;
      pending = input = kNone;
      in_callback = false;
    }
    switch (e.kind) {
      case PathEvent::Kind::kTake:
        pending = static_cast<int64_t>(o.index);
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
        if (in_callback) callback_input[o.index] = input;
        break;
    }
  }
}

// Per topic: its messages (the first publish of each source timestamp) and their first takes;
// per (node, topic): its takes in time order, for the latest-input link.
void PathLinks::collect_messages(const std::vector<Order>& order) {
  topics.resize(k);
  {
    std::vector<std::size_t> publishes(k, 0);
    for (const PathEvent& e : ev)
      if (e.kind == PathEvent::Kind::kPublish && e.topic < k) ++publishes[e.topic];
    for (std::size_t t = 0; t < k; ++t) {
      topics[t].messages.reserve(publishes[t]);
      topics[t].by_stamp.reserve(publishes[t]);
    }
  }
  for (const Order& o : order) {
    const PathEvent& e = ev[o.index];
    if (e.topic >= k || e.kind != PathEvent::Kind::kPublish) continue;
    TopicMessages& tm = topics[e.topic];
    auto [it, inserted] =
        tm.by_stamp.try_emplace(e.stamp, static_cast<uint32_t>(tm.messages.size()));
    if (inserted) {
      tm.messages.push_back({e.ts, o.index});
    } else if (e.ts < tm.messages[it->second].publish_ts) {
      tm.messages[it->second].publish_ts = e.ts;
      tm.messages[it->second].publish = o.index;
    }
  }
  for (const Order& o : order) {
    const PathEvent& e = ev[o.index];
    if (e.topic >= k || e.kind != PathEvent::Kind::kTake) continue;
    takes_of[{e.node, e.topic}].push_back(o.index);
    const uint32_t m = topics[e.topic].find(e.stamp);
    if (m == kNoMessage) continue;
    int64_t& first_take = topics[e.topic].messages[m].first_take;
    if (first_take == kNone || e.ts < ev[static_cast<std::size_t>(first_take)].ts)
      first_take = static_cast<int64_t>(o.index);
  }
  for (auto& [key, takes] : takes_of) {
    std::stable_sort(takes.begin(), takes.end(),
                     [&](std::size_t a, std::size_t b) { return ev[a].ts < ev[b].ts; });
  }
}

// Each message on topic i+1 linked to its input on topic i: the take of the callback that
// published it, or else the publishing node's latest take of topic i before the publish.
void PathLinks::link_hop(std::size_t i, PathHop& hop) {
  hop.from = in.topics[i];
  hop.to = in.topics[i + 1];
  std::set<std::string> hop_nodes;
  std::set<uint32_t> publishers;  // of topic i+1
  for (Message& m : topics[i + 1].messages) {
    const PathEvent& pub = ev[m.publish];
    publishers.insert(pub.node);
    const int64_t direct = callback_input[m.publish];
    int64_t take = kNone;
    if (direct != kNone && ev[static_cast<std::size_t>(direct)].topic == i &&
        ev[static_cast<std::size_t>(direct)].node == pub.node) {
      take = direct;
      ++hop.by_callback;
    } else if (auto t = takes_of.find({pub.node, static_cast<uint32_t>(i)}); t != takes_of.end()) {
      auto it = std::partition_point(t->second.begin(), t->second.end(),
                                     [&](std::size_t x) { return ev[x].ts <= pub.ts; });
      if (it != t->second.begin()) {
        take = static_cast<int64_t>(*std::prev(it));
        ++hop.by_latest;
      }
    }
    if (take == kNone) {
      ++hop.unlinked;
      continue;
    }
    hop_nodes.insert(in.nodes[pub.node]);
    m.parent = take;
    if (const uint32_t input = topics[i].find(ev[static_cast<std::size_t>(take)].stamp);
        input != kNoMessage)
      ++topics[i].messages[input].uses;
  }
  for (const auto& [node_topic, takes] : takes_of) {
    if (node_topic.second != i || !publishers.contains(node_topic.first)) continue;
    hop.inputs += takes.size();
    for (const std::size_t t : takes) {
      const uint32_t m = topics[i].find(ev[t].stamp);
      if (m == kNoMessage || topics[i].messages[m].uses == 0) ++hop.unused;
    }
  }
  for (const Message& m : topics[i].messages) hop.reused += m.uses > 1 ? 1 : 0;
  hop.outputs = topics[i + 1].messages.size();
  for (const auto& name : hop_nodes) hop.node += (hop.node.empty() ? "" : ", ") + name;
}

uint32_t PathLinks::source_of(std::size_t topic, uint32_t m) const {
  for (std::size_t i = topic; i > 0 && m != kNoMessage; --i) {
    const int64_t parent = topics[i].messages[m].parent;
    if (parent == kNone) return kNoMessage;
    m = topics[i - 1].find(ev[static_cast<std::size_t>(parent)].stamp);
  }
  return m;
}

bool PathLinks::last_topic_taken() const {
  return std::any_of(topics[k - 1].messages.begin(), topics[k - 1].messages.end(),
                     [](const Message& m) { return m.first_take != kNone; });
}

PathLinks::Arrivals PathLinks::first_arrivals(bool ends_at_take) const {
  const std::size_t sources = topics[0].messages.size();
  Arrivals arrivals{std::vector<std::size_t>(sources, 0), std::vector<int64_t>(sources, kNone),
                    std::vector<uint32_t>(sources, kNoMessage)};
  auto& furthest = arrivals.furthest;
  auto& arrival_ts = arrivals.ts;
  auto& arrival_message = arrivals.message;
  for (std::size_t i = 1; i < k; ++i) {
    const auto& messages = topics[i].messages;
    for (uint32_t m = 0; m < messages.size(); ++m) {
      const uint32_t source = source_of(i, m);
      if (source == kNoMessage) continue;
      furthest[source] = std::max(furthest[source], i);
      if (i != k - 1) continue;
      const int64_t at = !ends_at_take ? messages[m].publish_ts
                         : messages[m].first_take == kNone
                             ? kNone
                             : ev[static_cast<std::size_t>(messages[m].first_take)].ts;
      if (at == kNone) continue;
      if (arrival_ts[source] == kNone || at < arrival_ts[source]) {
        arrival_ts[source] = at;
        arrival_message[source] = m;
      }
    }
  }
  return arrivals;
}

void PathLinks::measure(const Arrivals& arrivals, PathLatency& out) const {
  const std::size_t sources = topics[0].messages.size();
  std::vector<double> end_to_end;
  std::vector<std::vector<double>> transport(k - 1), in_node(k - 1);
  for (uint32_t s = 0; s < sources; ++s) {
    const Message& source = topics[0].messages[s];
    if (source.publish_ts < in.since) continue;
    ++out.sources;
    if (arrivals.ts[s] == kNone) {
      ++out.stopped_at[arrivals.furthest[s]];
      continue;
    }
    ++out.reached;
    end_to_end.push_back(static_cast<double>(arrivals.ts[s] - source.publish_ts));
    const PathEvent& publish = ev[source.publish];
    out.instances.push_back({source.publish_ts, arrivals.ts[s], publish.vpid, publish.vtid});
    // The chain's hops, walked back from the end.
    uint32_t m = arrivals.message[s];
    for (std::size_t i = k - 1; i > 0; --i) {
      const Message& message = topics[i].messages[m];
      const PathEvent& take = ev[static_cast<std::size_t>(message.parent)];
      const uint32_t input = topics[i - 1].find(take.stamp);
      transport[i - 1].push_back(
          static_cast<double>(take.ts - topics[i - 1].messages[input].publish_ts));
      in_node[i - 1].push_back(static_cast<double>(message.publish_ts - take.ts));
      m = input;
    }
  }
  std::sort(out.instances.begin(), out.instances.end(),
            [](const auto& x, const auto& y) { return x.start < y.start; });
  if (!end_to_end.empty()) out.end_to_end = metrics::compute_stats(end_to_end);
  for (std::size_t i = 0; i + 1 < k; ++i) {
    if (!transport[i].empty()) out.hops[i].transport = metrics::compute_stats(transport[i]);
    if (!in_node[i].empty()) out.hops[i].in_node = metrics::compute_stats(in_node[i]);
  }
}

}  // namespace

PathLatency path_latency(const PathEvents& in) {
  const std::size_t k = in.topics.size();
  if (k < 2) throw std::invalid_argument("a path needs at least two topics");
  PathLatency out;
  out.topics = in.topics;
  out.stopped_at.assign(k, 0);
  PathLinks links(in);
  out.hops.resize(k - 1);
  for (std::size_t i = 0; i + 1 < k; ++i) links.link_hop(i, out.hops[i]);
  out.ends_at_take = links.last_topic_taken();
  links.measure(links.first_arrivals(out.ends_at_take), out);
  return out;
}

}  // namespace robotperf::tracing
