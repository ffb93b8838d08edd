#include "run_isolation.hpp"

#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <random>

namespace robotperf::harness {

std::optional<uint64_t> MessageIds::id_of(int64_t stamp) const {
  const int64_t offset = stamp - base_ns;
  if (offset < 0 || offset % period_ns != 0) return std::nullopt;
  const auto id = static_cast<uint64_t>(offset / period_ns);
  if (id >= count) return std::nullopt;
  return id;
}

MessageIds make_message_ids(int64_t period_ns, std::size_t count) {
  const auto wall_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::chrono::system_clock::now().time_since_epoch());
  std::random_device entropy;
  std::uniform_int_distribution<int64_t> offset(0, std::min<int64_t>(period_ns, 1'000'000'000) - 1);
  const int64_t base =
      std::chrono::duration_cast<std::chrono::nanoseconds>(wall_ms).count() + offset(entropy);
  return MessageIds{base, period_ns, count};
}

std::string make_run_token() {
  std::random_device entropy;
  const uint64_t value = (uint64_t{entropy()} << 32) | entropy();
  char text[17];
  std::snprintf(text, sizeof text, "%016" PRIx64, value);
  return text;
}

std::string run_user_data(const std::string& token, const MessageIds* ids) {
  std::string out = "robotperf_run=" + token + ";";
  if (ids != nullptr) {
    out += "robotperf_ids=" + std::to_string(ids->base_ns) + "," + std::to_string(ids->period_ns) +
           "," + std::to_string(ids->count) + ";";
  }
  return out;
}

PeerRun parse_run_user_data(const std::string& user_data) {
  PeerRun run;
  run.token = rmw::user_data_value(user_data, "robotperf_run");
  const std::string ids = rmw::user_data_value(user_data, "robotperf_ids");
  long long base = 0, period = 0;
  unsigned long long count = 0;
  char end = 0;
  // Another process's announcement: taken only when it is well formed.
  if (std::sscanf(ids.c_str(), "%lld,%lld,%llu%c", &base, &period, &count, &end) == 3 &&
      period > 0) {
    run.ids = MessageIds{base, period, static_cast<std::size_t>(count)};
  }
  return run;
}

RunIsolation::RunIsolation(const rmw::Transport& transport, std::string token)
    : transport_(transport), self_(transport.participant()), token_(std::move(token)) {}

void RunIsolation::refresh_locked() {
  other_ids_.clear();
  for (const auto& peer : transport_.peers()) {
    const PeerRun run = parse_run_user_data(peer.user_data);
    // Another robotperf run's participant. One without a token (a ROS 2 node of an external
    // graph, or any other program) is judged by the stamps it writes instead.
    const bool other = !run.token.empty() && run.token != token_;
    is_other_[peer.id] = other;
    if (other && run.ids) other_ids_.push_back(*run.ids);
  }
}

bool RunIsolation::foreign(const rmw::ParticipantId& sender, int64_t stamp, bool own_id) {
  static constexpr rmw::ParticipantId kNone{};
  std::lock_guard lock(mutex_);
  if (sender != kNone && sender != self_) {
    auto it = is_other_.find(sender);
    if (it == is_other_.end()) {
      refresh_locked();
      it = is_other_.find(sender);
    }
    // A sender not announced yet (its discovery callback may trail its first sample) is taken as
    // this run's for now, so that a defect of our own graph is never explained away.
    if (it != is_other_.end() && it->second) return true;
  }
  if (own_id) return false;
  auto in_other_run = [&] {
    return std::ranges::any_of(other_ids_,
                               [&](const MessageIds& ids) { return ids.id_of(stamp).has_value(); });
  };
  if (in_other_run()) return true;
  refresh_locked();
  return in_other_run();
}

std::vector<rmw::PeerParticipant> RunIsolation::others() const {
  std::vector<rmw::PeerParticipant> out;
  for (auto& peer : transport_.peers()) {
    if (parse_run_user_data(peer.user_data).token != token_) out.push_back(std::move(peer));
  }
  return out;
}

std::vector<rmw::PeerParticipant> outside_graph(const std::vector<rmw::PeerParticipant>& peers,
                                                std::set<std::string> graph_topics) {
  std::vector<bool> in_graph(peers.size(), false);
  // Grows until no participant joins: a pass adds those touching a topic known to be the graph's.
  for (bool grew = true; grew;) {
    grew = false;
    for (std::size_t i = 0; i < peers.size(); ++i) {
      const auto& peer = peers[i];
      if (in_graph[i] || !parse_run_user_data(peer.user_data).token.empty()) continue;
      if (std::ranges::none_of(peer.topics,
                               [&](const std::string& t) { return graph_topics.contains(t); }))
        continue;
      in_graph[i] = grew = true;
      graph_topics.insert(peer.topics.begin(), peer.topics.end());
    }
  }
  std::vector<rmw::PeerParticipant> out;
  for (std::size_t i = 0; i < peers.size(); ++i) {
    if (!in_graph[i]) out.push_back(peers[i]);
  }
  return out;
}

std::string describe_peers(const std::vector<rmw::PeerParticipant>& peers, std::size_t max_listed) {
  std::string out;
  for (std::size_t i = 0; i < peers.size() && i < max_listed; ++i) {
    const auto& peer = peers[i];
    if (i > 0) out += "; ";
    out += "'" + (peer.name.empty() ? std::string("unnamed") : peer.name) + "'";
    if (!peer.nodes.empty()) {
      out += " (node";
      for (std::size_t n = 0; n < peer.nodes.size(); ++n) {
        out += (n == 0 ? " " : ", ") + peer.nodes[n].path();
      }
      out += ")";
    }
    if (!parse_run_user_data(peer.user_data).token.empty()) out += " (another robotperf run)";
    if (!peer.addresses.empty()) out += " at " + peer.addresses.front();
    if (!peer.topics.empty()) {
      out += ", topics";
      std::size_t listed = 0;
      for (const auto& topic : peer.topics) {
        if (listed++ == 4) {
          out += " ...";
          break;
        }
        out += " " + topic;
      }
    }
  }
  if (peers.size() > max_listed)
    out += "; and " + std::to_string(peers.size() - max_listed) + " more";
  return out;
}

}  // namespace robotperf::harness
