// The WireGuard tunnel --netns makes for graph.yaml `network: {vpn: wireguard}` (n5 to n8):
// traffic crosses it, and nothing of it (namespaces, wireguard-go, keys) outlives the link.
#include "robotperf/harness/network_link.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

namespace robotperf::harness {
namespace {

namespace fs = std::filesystem;
using Layout = NetworkLayout;

std::string output_of(const std::string& command) {
  std::string out;
  if (FILE* p = popen(command.c_str(), "r")) {
    char buf[4096];
    for (std::size_t n; (n = fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
    pclose(p);
  }
  return out;
}

// Awaits `done` for up to 10 s: wireguard-go's handshake and exit happen in its own time.
bool within_deadline(const std::function<bool()>& done) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

uint64_t received_bytes(const std::string& ns, const std::string& device) {
  const auto j = nlohmann::json::parse(
      output_of("ip -n " + ns + " -s -j link show dev " + device + " 2>/dev/null"), nullptr, false);
  if (!j.is_array() || j.empty()) return 0;
  return j[0]["stats64"]["rx"]["bytes"].get<uint64_t>();
}

bool key_folder_left() {
  const std::string prefix = "robotperf-wg-" + std::to_string(getpid()) + "-";
  for (const auto& e : fs::directory_iterator(fs::temp_directory_path()))
    if (e.path().filename().string().starts_with(prefix)) return true;
  return false;
}

// Why this process cannot make a WireGuard link, or empty when it can.
std::string wireguard_missing() {
  if (geteuid() != 0) return "--netns needs root to make network namespaces";
  try {
    wireguard_version();
  } catch (const NetworkSetupError& e) {
    return e.what();
  }
  return {};
}

TEST(NetworkLink, MissingWireguardOrTunIsOneLine) {
  try {
    wireguard_version("/nonexistent/tun");
    FAIL() << "a missing TUN device was accepted";
  } catch (const NetworkSetupError& e) {
    const std::string what = e.what();
    // wireguard-go and wg may be missing here too: then they are named first.
    EXPECT_NE(what.find(what.find("TUN") != std::string::npos ? "/nonexistent/tun" : "install"),
              std::string::npos)
        << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  const std::string path = std::getenv("PATH") ? std::getenv("PATH") : "";
  setenv("PATH", "/nonexistent", 1);
  std::string what;
  try {
    wireguard_version();
  } catch (const NetworkSetupError& e) {
    what = e.what();
  }
  setenv("PATH", path.c_str(), 1);
  EXPECT_NE(what.find("needs wireguard-go"), std::string::npos) << what;
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
}

TEST(NetworkLink, NamesOfTheLayout) {
  EXPECT_EQ(topology_from_name("routed"), Layout::Topology::kRouted);
  EXPECT_EQ(topology_from_name("same-subnet"), Layout::Topology::kSameSubnet);
  EXPECT_FALSE(topology_from_name("mesh"));
  EXPECT_EQ(vpn_from_name("wireguard"), Layout::Vpn::kWireguard);
  EXPECT_FALSE(vpn_from_name("openvpn"));
  EXPECT_EQ(to_string(Layout::Topology::kRouted), "routed");
  EXPECT_EQ(to_string(Layout::Vpn::kWireguard), "wireguard");
}

TEST(NetworkLink, TunnelCarriesTrafficAndLeavesNothing) {
  if (const auto why = wireguard_missing(); !why.empty()) GTEST_SKIP() << why;
  const std::string id = std::to_string(getpid());
  for (const auto topology : {Layout::Topology::kSameSubnet, Layout::Topology::kRouted}) {
    NetworkLink::Description d;
    {
      NetworkLink link(LinkShaping{}, Layout{topology, Layout::Vpn::kWireguard});
      d = link.description();
      ASSERT_TRUE(d.tunnel);
      EXPECT_EQ(d.tunnel->implementation, "wireguard-go");
      EXPECT_FALSE(d.tunnel->version.empty());
      EXPECT_EQ(d.mtu, 1420);
      EXPECT_EQ(d.runner_address, "10.201.0.1");
      EXPECT_EQ(d.remote_address, "10.201.0.2");
      EXPECT_EQ(d.tunnel->remote_endpoint,
                topology == Layout::Topology::kRouted ? "10.200.2.2" : "10.200.0.2");
      EXPECT_EQ(d.router_namespace.empty(), topology == Layout::Topology::kSameSubnet);
      EXPECT_EQ(d.static_peers, (std::vector<std::string>{"10.201.0.1", "10.201.0.2"}));
      // The keys went into the daemons; their files are gone already.
      EXPECT_FALSE(key_folder_left());
      // A datagram from the runner's host to the other's tunnel address arrives through the
      // other's WireGuard device (after the handshake it starts).
      const std::string send = "ip netns exec " + d.runner_namespace +
                               " bash -c 'echo ping > /dev/udp/10.201.0.2/9' 2>/dev/null";
      EXPECT_TRUE(within_deadline([&] {
        if (std::system(send.c_str()) != 0) return false;
        return received_bytes(d.remote_namespace, "wg" + id + "b") > 0;
      })) << to_string(topology);
      EXPECT_GT(link.counters().bytes_out, 0u);
    }
    for (const auto& ns : {d.runner_namespace, d.remote_namespace, d.router_namespace}) {
      if (!ns.empty()) {
        EXPECT_FALSE(fs::exists("/run/netns/" + ns)) << ns;
      }
    }
    // Each wireguard-go ends with its device, and removes its control socket as it goes.
    for (const char* side : {"a", "b"}) {
      const fs::path socket = "/var/run/wireguard/wg" + id + side + ".sock";
      EXPECT_TRUE(within_deadline([&] { return !fs::exists(socket); })) << socket;
    }
    EXPECT_FALSE(key_folder_left());
  }
}

}  // namespace
}  // namespace robotperf::harness
