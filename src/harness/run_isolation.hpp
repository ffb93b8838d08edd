// Private to the harness: telling this run's traffic from another run's on the same DDS domain
// (docs/design.md §3.10). Every participant of a run carries the run's token in its USER_DATA, and
// the Playback's and Monitor's participant also its message-ID space, so that a Monitor can tell
//  - outputs written by another run's participants (its graph processed our inputs, or its own),
//  - outputs our graph made from another run's inputs (their stamps are that run's IDs)
// from this run's outputs and from stamps nobody sent (a graph defect).
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "robotperf/rmw/transport.hpp"

namespace robotperf::harness {

// Message k of a run carries the header stamp base + k·period: unique within
// the run even when the dataset loops, increasing like a real clock (so
// time-based pairing in nodes still works), and exactly invertible.
struct MessageIds {
  int64_t base_ns = 0;
  int64_t period_ns = 1;
  std::size_t count = 0;

  int64_t stamp_ns(uint64_t id) const { return base_ns + static_cast<int64_t>(id) * period_ns; }
  std::optional<uint64_t> id_of(int64_t stamp_ns) const;
};

// The IDs of a run starting now at the given period: the base is the wall clock in whole
// milliseconds plus a random offset below the period (at most 1 s), so that another run's stamps
// fall on this run's IDs with a probability of about one in period_ns per message, where whole
// milliseconds alone would make every stamp of a 1 kHz run a valid ID of another.
MessageIds make_message_ids(int64_t period_ns, std::size_t count);

// A random token naming one run (16 hex digits).
std::string make_run_token();

// The USER_DATA of a run's participants: "robotperf_run=<token>;" and, for the participant
// that sends and receives the IDs, "robotperf_ids=<base>,<period>,<count>;".
std::string run_user_data(const std::string& token, const MessageIds* ids = nullptr);

// What the USER_DATA of a participant says about its run.
struct PeerRun {
  std::string token;  // empty: not a robotperf participant
  std::optional<MessageIds> ids;
};
PeerRun parse_run_user_data(const std::string& user_data);

class RunIsolation {
 public:
  // `transport` must outlive this.
  RunIsolation(const rmw::Transport& transport, std::string token);

  // Whether a reception belongs to another run: written by a participant of another run, or
  // carrying a stamp that is one of another run's IDs and none of this run's.
  bool foreign(const rmw::ParticipantId& sender, int64_t stamp, bool own_id);

  // The participants on the domain that are not this run's, as discovered until now.
  std::vector<rmw::PeerParticipant> others() const;

 private:
  void refresh_locked();

  const rmw::Transport& transport_;
  rmw::ParticipantId self_;  // the Monitor's own participant: the graph's writers in one process
  std::string token_;
  mutable std::mutex mutex_;
  std::map<rmw::ParticipantId, bool> is_other_;  // by participant, as last refreshed
  std::vector<MessageIds> other_ids_;            // ID spaces other runs announced
};

// Of `peers`, those that are no part of an external graph whose boundary topics (inputs, output,
// and the topics of robotperf's own nodes beside it) are `graph_topics`: a participant is the
// graph's when one of its topics is one of these or one of another of the graph's participants
// (a launched pipeline's inner nodes). Another robotperf run's participants, and those whose
// topics are not known yet, are never the graph's.
std::vector<rmw::PeerParticipant> outside_graph(const std::vector<rmw::PeerParticipant>& peers,
                                                std::set<std::string> graph_topics);

// One line naming the participants (name, addresses, topics), at most `max_listed` of them.
std::string describe_peers(const std::vector<rmw::PeerParticipant>& peers, std::size_t max_listed);

}  // namespace robotperf::harness
