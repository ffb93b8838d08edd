// Two hosts on one machine: network namespaces joined by a veth pair, made for a run (--netns),
// with the link shaped by tc (a rate limit, and netem's delay, jitter and loss where the kernel
// has it). The runner's host is one namespace; the graph's other hosts share the other.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace robotperf::harness {

// What cannot be set up (no privilege, no `ip`/`tc`, no sch_netem): one line saying what to do.
class NetworkSetupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LinkShaping {
  std::string rate;   // tc tbf rate, e.g. "1gbit"; empty: unshaped (a veth runs at memory speed)
  std::string netem;  // tc netem arguments, e.g. "delay 1ms 0.1ms loss 0.1%"; empty: none
};

class NetworkLink {
 public:
  // Makes the namespaces robotperf-<pid>-a and -b, the veth pair between them (10.200.0.1/24 and
  // .2/24, default routes through it so that DDS's multicast discovery crosses it too) and the
  // shaping on both ends, so that each direction is shaped once. Removes the namespaces of
  // robotperf processes that no longer exist first. Throws NetworkSetupError.
  explicit NetworkLink(const LinkShaping& shaping);
  ~NetworkLink();  // removes both namespaces (and with them the link)
  NetworkLink(const NetworkLink&) = delete;
  NetworkLink& operator=(const NetworkLink&) = delete;

  // Moves the calling thread into the runner's namespace: the sockets, threads and processes it
  // makes afterwards are there. Call it before any participant or thread that uses the network.
  void enter_runner_side();
  // The launcher of the other side's processes: {"ip", "netns", "exec", <namespace>}.
  std::vector<std::string> launcher() const;

  // The runner's end of the link, since it was made: out is toward the other hosts.
  struct Counters {
    uint64_t bytes_out = 0, bytes_in = 0;
    uint64_t packets_out = 0, packets_in = 0;
    uint64_t dropped = 0;  // by the qdiscs of both ends (tbf queue full, netem loss)
    // What was counted between `before` and this reading.
    friend Counters operator-(const Counters& after, const Counters& before) {
      return {after.bytes_out - before.bytes_out, after.bytes_in - before.bytes_in,
              after.packets_out - before.packets_out, after.packets_in - before.packets_in,
              after.dropped - before.dropped};
    }
  };
  Counters counters() const;

  struct Description {
    std::string runner_namespace, remote_namespace;
    std::string runner_address, remote_address;
    int mtu = 0;
    LinkShaping shaping;
  };
  const Description& description() const { return description_; }

 private:
  Description description_;
  std::string runner_device_, remote_device_;
};

}  // namespace robotperf::harness
