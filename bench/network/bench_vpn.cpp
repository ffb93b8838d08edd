// The WireGuard VPN's cost: n5 (the ping-pong through a wireguard-go tunnel) against n3 (the same
// over the plain veth link), both through --netns at 1 Gbit/s, at 64 B to 1 MiB. Needs root,
// wireguard-go and /dev/net/tun (says so in one line and ends otherwise). Run on demand:
//   sudo ./build/bench/network/bench_vpn [COUNT]   (default 300 messages per run, at 50 Hz)
// It prints each payload's round-trip p50 for n3 (the reference) and n5, and their ratio; 1 MiB
// is sent at 10 Hz (at 50 Hz a 2-core machine's wireguard-go falls behind and the run loses it
// all).
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "bench_start.hpp"
#include "robotperf/harness/network_link.hpp"
#include "robotperf/rmw/transport.hpp"

namespace fs = std::filesystem;

namespace {

// The round trip's p50 in ms of one run of `id` at `payload` bytes; NaN when it failed.
double round_trip_p50(const std::string& id, int payload, int count, const fs::path& out) {
  fs::remove_all(out);
  fs::create_directories(out.parent_path());  // where the run's log goes
  const std::string command =
      std::string(ROBOTPERF_EXECUTABLE) + " run " + id +
      " --netns --quiet --workload payload_bytes=" + std::to_string(payload) +
      (payload >= (1 << 20) ? " --rate 10" : "") + " --count " + std::to_string(count) +
      " --domain " + std::to_string(robotperf::rmw::reserved_domain()) + " --output " +
      out.string() + " >" + (out.string() + ".log") + " 2>&1";
  // An INVALID run (loss) ends non-zero but still has its figures: said, and its p50 kept.
  if (std::system(command.c_str()) != 0)
    std::printf("  %s at %d B: not a valid run, see %s.log\n", id.c_str(), payload, out.c_str());
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(out, ec)) {
    if (e.path().extension() != ".json") continue;
    const auto j = nlohmann::json::parse(std::ifstream(e.path()), nullptr, false);
    if (j.is_object() && j["latency_ms"]["from_sent"]["p50"].is_number())
      return j["latency_ms"]["from_sent"]["p50"].get<double>();
  }
  return std::nan("");
}

}  // namespace

int main(int argc, char** argv) {
  robotperf::bench::start_with_builtin_categories();
  const int count = argc > 1 ? std::atoi(argv[1]) : 300;
  if (count < 100) {
    std::fprintf(stderr, "bench_vpn: COUNT must be at least 100 (n3's and n5's min_samples)\n");
    return 2;
  }
  if (geteuid() != 0) {
    std::printf("bench_vpn: needs root (--netns makes network namespaces); nothing measured\n");
    return 0;
  }
  std::string version;
  try {
    version = robotperf::harness::wireguard_version();
  } catch (const robotperf::harness::NetworkSetupError& e) {
    std::printf("bench_vpn: %s; nothing measured\n", e.what());
    return 0;
  }
  const fs::path out =
      fs::temp_directory_path() / ("robotperf-bench-vpn-" + std::to_string(getpid()));
  std::printf(
      "round trip p50 (ms), fastdds, --netns 1gbit, %d messages at 50 Hz; wireguard-go %s, "
      "MTU 1420\n",
      count, version.c_str());
  std::printf("%10s %12s %12s %8s\n", "payload", "n3 (ref)", "n5 (VPN)", "n5/n3");
  bool all_ran = true;
  for (const int payload : {64, 1024, 65536, 1048576}) {
    const double plain = round_trip_p50("n3", payload, count, out / "n3");
    const double vpn = round_trip_p50("n5", payload, count, out / "n5");
    all_ran = all_ran && std::isfinite(plain) && std::isfinite(vpn);
    std::printf("%10d %12.4f %12.4f %8.2f\n", payload, plain, vpn, vpn / plain);
  }
  // A failed run's log stays for reading.
  if (all_ran) fs::remove_all(out);
  return all_ran ? 0 : 1;
}
