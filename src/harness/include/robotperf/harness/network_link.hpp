// Two hosts on one machine: network namespaces joined by a veth pair, made for a run (--netns),
// with the link shaped by tc (a rate limit, and netem's delay, jitter and loss where the kernel
// has it). The runner's host is one namespace; the graph's other hosts share the other. graph.yaml
// `network:` may put a router namespace between two subnets, and a WireGuard tunnel (the userspace
// wireguard-go) over the link (docs/benchmarks/middleware.md).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
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

// graph.yaml `network:`: the path between the runner's host and the other.
struct NetworkLayout {
  enum class Topology {
    kSameSubnet,  // one veth pair, one subnet
    kRouted,      // two subnets with a router namespace between them
  };
  enum class Vpn { kNone, kWireguard };
  Topology topology = Topology::kSameSubnet;
  Vpn vpn = Vpn::kNone;
  friend bool operator==(const NetworkLayout&, const NetworkLayout&) = default;
};
std::string to_string(NetworkLayout::Topology topology);  // "same-subnet", "routed"
std::string to_string(NetworkLayout::Vpn vpn);            // "none", "wireguard"
// "same-subnet"/"routed" and "none"/"wireguard"; nullopt for anything else.
std::optional<NetworkLayout::Topology> topology_from_name(const std::string& name);
std::optional<NetworkLayout::Vpn> vpn_from_name(const std::string& name);

// The version of the wireguard-go on PATH (e.g. "0.0.20220316"), once it is known that it, `wg`
// (wireguard-tools) and `tun_device` are there; NetworkSetupError in one line saying what is
// missing and how to install it otherwise.
std::string wireguard_version(const std::filesystem::path& tun_device = "/dev/net/tun");

class NetworkLink {
 public:
  // Makes the namespaces robotperf-<pid>-a and -b and the path between them with the shaping on
  // both hosts' ends, so that each direction is shaped once. Same subnet: one veth pair
  // (10.200.0.1/24 and .2/24, default routes through it so that DDS's multicast discovery
  // crosses it too). Routed: 10.200.1.1/24 and 10.200.2.2/24, each a veth pair to the namespace
  // robotperf-<pid>-r that forwards between them (.254 on both). WireGuard: the tunnel
  // (10.201.0.1/24 and .2/24, MTU 1420) over that path, a wireguard-go per host with keys made
  // for the run, and default routes into it. Where multicast does not cross (a router, a tunnel),
  // the hosts' addresses are DDS's static peers. Removes the namespaces of robotperf processes
  // that no longer exist first, with what still runs in them. Throws NetworkSetupError, having
  // removed what it made.
  explicit NetworkLink(const LinkShaping& shaping, const NetworkLayout& layout = {});
  ~NetworkLink();  // removes the tunnel, the namespaces (and with them the links)
  NetworkLink(const NetworkLink&) = delete;
  NetworkLink& operator=(const NetworkLink&) = delete;

  // Moves the calling thread into the runner's namespace: the sockets, threads and processes it
  // makes afterwards are there. Call it before any participant or thread that uses the network.
  // Where multicast does not cross, it also sets ROS_STATIC_PEERS to both hosts' addresses, which
  // this process's participants and the processes it starts discover each other through.
  void enter_runner_side();
  // The launcher of the other side's processes: {"ip", "netns", "exec", <namespace>}.
  std::vector<std::string> launcher() const;

  // The runner's end of the path the hosts' traffic takes (the tunnel's device when there is
  // one), since it was made: out is toward the other hosts.
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

  // The WireGuard tunnel, as results record it: a VPN run is never pooled with a plain one.
  struct Tunnel {
    std::string implementation;  // "wireguard-go"
    std::string version;         // e.g. "0.0.20220316"
    // The addresses the tunnel's packets travel between, and that path's MTU.
    std::string runner_endpoint, remote_endpoint;
    int underlay_mtu = 0;
  };
  struct Description {
    std::string runner_namespace, remote_namespace;
    std::string router_namespace;  // routed only
    // The addresses the hosts reach each other at (in the tunnel when there is one), and the MTU
    // of that path.
    std::string runner_address, remote_address;
    int mtu = 0;
    NetworkLayout layout;
    std::optional<Tunnel> tunnel;
    // ROS_STATIC_PEERS's addresses; empty where multicast discovery crosses.
    std::vector<std::string> static_peers;
    LinkShaping shaping;
  };
  const Description& description() const { return description_; }

 private:
  void make_path();
  void make_tunnel();
  void remove();  // what was made, so far as it was

  Description description_;
  // The hosts' ends of the veth pairs (shaped), and the devices their traffic leaves by.
  std::string runner_device_, remote_device_;
  std::string runner_traffic_device_;
  std::vector<std::pair<std::string, std::string>> tunnel_devices_;  // {namespace, device}
  std::filesystem::path key_folder_;  // while the tunnel is being made
};

}  // namespace robotperf::harness
