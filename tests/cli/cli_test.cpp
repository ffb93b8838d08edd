// robotperf end to end, as a user runs it.
#include <gtest/gtest.h>
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <tuple>

#include "../command_line.hpp"
#include "../sanitized_build.hpp"
#include "../shared_data.hpp"
#include "../test_file_name.hpp"
#include "robotperf/rmw/transport.hpp"

namespace {

namespace fs = std::filesystem;

using robotperf::test_support::Outcome;
using robotperf::test_support::robotperf_cli;

// The results file of a folder that holds one run (beside it: the folder's results database).
fs::path only_result_in(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().extension() == ".json") return e.path();
  }
  return {};
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    out_ = fs::temp_directory_path() / ("robotperf-cli-" + std::to_string(getpid()) + "-" +
                                        robotperf::testing::current_test_file_name());
    fs::remove_all(out_);
  }
  void TearDown() override { fs::remove_all(out_); }

  // The single results JSON the run wrote.
  std::string result_json_path() {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(out_)) {
      if (e.path().extension() == ".json") files.push_back(e.path());
    }
    EXPECT_EQ(files.size(), 1u);
    return files.empty() ? std::string() : files[0].string();
  }
  nlohmann::json result_json() {
    const std::string path = result_json_path();
    if (path.empty()) return {};
    std::ifstream in(path);
    return nlohmann::json::parse(in);
  }
  std::string domain() const { return std::to_string(robotperf::rmw::reserved_domain()); }

  fs::path out_;
};

void expect_clean_a1_result(const nlohmann::json& j, const std::string& rmw) {
  EXPECT_EQ(j["schema"], "robotperf.result/1");
  EXPECT_EQ(j["benchmark"]["id"], "a1");
  EXPECT_EQ(j["configuration"]["rmw"], rmw);
  EXPECT_EQ(j["counts"]["sent"], 60);
  EXPECT_EQ(j["counts"]["measured"], 55);  // warm-up 5
  EXPECT_EQ(j["counts"]["matched"], 55);
  EXPECT_EQ(j["counts"]["lost"], 0);
  EXPECT_EQ(j["validity"]["valid"], true) << j["validity"].dump();
  EXPECT_GT(j["latency_ms"]["from_scheduled"]["min"].get<double>(), 0.0);
  EXPECT_GE(j["latency_ms"]["from_scheduled"]["max"].get<double>(),
            j["latency_ms"]["from_scheduled"]["p50"].get<double>());
  EXPECT_EQ(j["headline"]["latency_ms"], j["latency_ms"]["from_scheduled"]["max"]);
  EXPECT_TRUE(j["dataset"]["hash"].get<std::string>().starts_with("fnv1a64:"));
  EXPECT_FALSE(j["software"]["git_revision"].get<std::string>().empty());
  EXPECT_TRUE(j["machine"].is_object());
}

TEST_F(Cli, ListAndDescribe) {
  const Outcome list = robotperf_cli("list");
  EXPECT_EQ(list.exit_code, 0);
  for (const char* id : {"a1_perception_2nodes", "a2_rectify", "a3_stereo_image_proc",
                         "a4_depth_image_proc", "a5_resize"}) {
    EXPECT_NE(list.out.find(id), std::string::npos) << list.out;
  }
  const Outcome d = robotperf_cli("describe a1");
  EXPECT_EQ(d.exit_code, 0);
  EXPECT_NE(d.out.find("image_proc/rectify"), std::string::npos);
  EXPECT_NE(d.out.find("/resize/image"), std::string::npos);
}

TEST_F(Cli, RunA1OnIntra) {
  // At the benchmark's own rate, 30 Hz, where the build keeps up with it.
  const Outcome o = robotperf_cli("run a1 --count 60 --rmw intra --csv" +
                                  sanitized_rate_option(10) + " --output " + out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("result: VALID"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find(std::string("· ") + (kSanitizedBuild ? "10.0" : "30.0") +
                       " Hz · dataset perception/image"),
            std::string::npos)
      << o.out;
  const auto j = result_json();
  expect_clean_a1_result(j, "intra");
  EXPECT_EQ(j["configuration"]["timeline"], "fixed");
  EXPECT_TRUE(j["configuration"]["rate_scale"].is_null());
  bool csv = false;
  for (const auto& e : fs::directory_iterator(out_))
    csv |= e.path().string().ends_with(".latencies.csv");
  EXPECT_TRUE(csv);
}

TEST_F(Cli, RunA1OnFastDds) {
  const Outcome o = robotperf_cli("run a1 --count 60 --rmw fastdds" + sanitized_rate_option(5) +
                                  " --domain " + domain() + " --output " + out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  expect_clean_a1_result(result_json(), "fastdds");
}

class CliPerNode : public Cli, public ::testing::WithParamInterface<std::string> {};

TEST_P(CliPerNode, RunA1OneProcessPerNode) {
  const std::string rmw = GetParam();
  // At 10 Hz even a loaded 2-core machine moves 1.2 MB frames between processes in time.
  const Outcome o = robotperf_cli("run a1 --count 60" + rate_option(10, 2) + " --rmw " + rmw +
                                  " --processes per-node --cpus 0 --domain " + domain() +
                                  " --output " + out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const auto j = result_json();
  expect_clean_a1_result(j, rmw);
  EXPECT_EQ(j["configuration"]["processes"], "per-node");
  ASSERT_EQ(j["nodes"].size(), 2u);
  for (const auto& n : j["nodes"]) {
    EXPECT_EQ(n["exit_status"], "ok") << n.dump();
    EXPECT_EQ(n["backend"], "cpu") << n.dump();
    EXPECT_GT(n["pid"].get<int>(), 0);
  }
  // Resources are those of the node processes, by node name.
  // ... and of robotperf's own, with the Playback and Monitor (not counted as interference).
  ASSERT_EQ(j["resources"]["processes"].size(), 3u);
  EXPECT_EQ(j["resources"]["processes"][0]["label"], "rectify");
  EXPECT_EQ(j["resources"]["processes"][2]["label"], "robotperf (Playback, Monitor)");
  EXPECT_EQ(j["resources"]["processes"][0]["pid"], j["nodes"][0]["pid"]);
  EXPECT_EQ(j["resources"]["processes"][1]["measured"], true);
  EXPECT_GT(j["resources"]["processes"][1]["cpu_percent"].get<double>(), 0.0);
  EXPECT_EQ(j["configuration"]["scheduling"]["cpus"], "0");
  const auto& transport = j["software"]["transport"];
  EXPECT_EQ(transport["rmw"], rmw);
  EXPECT_NE(
      transport["settings"].get<std::string>().find(rmw == "fastdds" ? "Fast DDS" : "Cyclone DDS"),
      std::string::npos)
      << transport.dump();
  // What robotperf sets beyond the vendor's defaults is said.
  EXPECT_NE(transport["settings"].get<std::string>().find("8 MiB"), std::string::npos)
      << transport.dump();
  EXPECT_FALSE(j["software"]["libraries"][rmw].get<std::string>().empty());
  // The QoS of every endpoint robotperf made.
  bool monitor_qos = false, node_qos = false;
  for (const auto& e : transport["qos"]) {
    monitor_qos |= e["owner"] == "monitor" && e["topic"] == "/resize/image" &&
                   e["reliability"] == "reliable" && e["history"] == "keep_all";
    node_qos |= e["owner"] == "rectify";
  }
  EXPECT_TRUE(monitor_qos && node_qos) << transport["qos"].dump();
}

INSTANTIATE_TEST_SUITE_P(Dds, CliPerNode, ::testing::Values("fastdds", "cyclonedds"),
                         [](const auto& info) { return info.param; });

// n1 over two payload sizes in one command: a run each, both valid with every sampled echo
// identical, and the sweep summary beside them.
TEST_F(Cli, N1SweepsPayloadSizes) {
  const Outcome o = robotperf_cli(
      "run n1 --count 130 --rate 100 --quiet --sweep payload_bytes=64,1048576 --output " +
      out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("sweep n1 over payload_bytes: 2 runs"), std::string::npos) << o.out;
  std::vector<fs::path> runs, sweeps;
  for (const auto& e : fs::directory_iterator(out_)) {
    const std::string name = e.path().filename().string();
    if (name.ends_with(".sweep.json"))
      sweeps.push_back(e.path());
    else if (name.ends_with(".json"))
      runs.push_back(e.path());
  }
  ASSERT_EQ(runs.size(), 2u);
  ASSERT_EQ(sweeps.size(), 1u);
  const auto sweep = nlohmann::json::parse(std::ifstream(sweeps[0]));
  EXPECT_EQ(sweep["parameter"], "payload_bytes");
  ASSERT_EQ(sweep["runs"].size(), 2u);
  EXPECT_EQ(sweep["runs"][1]["value"], "1048576");
  EXPECT_EQ(sweep["runs"][1]["valid"], true);
  EXPECT_GT(sweep["runs"][1]["latency_ms"]["p50"].get<double>(), 0.0);
  for (const auto& run : runs) {
    const auto j = nlohmann::json::parse(std::ifstream(run));
    EXPECT_EQ(j["validity"]["valid"], true) << j["validity"].dump();
    EXPECT_EQ(j["functional"]["metrics"]["identical_fraction"]["value"], 1.0);
  }
  // The results folder lists the two runs, not the sweep summary.
  const Outcome list = robotperf_cli("results list " + out_.string());
  EXPECT_EQ(list.exit_code, 0) << list.out;
  EXPECT_EQ(list.out.find(".sweep"), std::string::npos) << list.out;
}

// A sweep value beyond the dataset's bounds, alone or with another parameter, is refused before
// the first run: nothing is run or written.
TEST_F(Cli, ASweepValueOutOfBoundsIsRefusedBeforeTheFirstRun) {
  for (const std::string sweep :
       {"payload_bytes=64,300000000", "payload_bytes=64,67108864 --workload frames=100"}) {
    const Outcome o =
        robotperf_cli("run n1 --count 130 --quiet --sweep " + sweep + " --output " + out_.string());
    EXPECT_EQ(o.exit_code, 2) << o.out;
    EXPECT_NE(o.out.find("payload_bytes"), std::string::npos) << o.out;
    EXPECT_EQ(o.out.find("latency"), std::string::npos) << "a run was made: " << o.out;
    EXPECT_FALSE(fs::exists(out_) && !fs::is_empty(out_)) << sweep;
  }
}

// n2 is per-node by definition: the pong runs in its own process, over Cyclone DDS here.
TEST_F(Cli, N2PongRunsInAProcessOfItsOwn) {
  const Outcome o =
      robotperf_cli("run n2 --rmw cyclonedds --count 130 --rate 50 --quiet --domain " + domain() +
                    " --output " + out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const auto j = result_json();
  EXPECT_EQ(j["configuration"]["processes"], "per-node");
  EXPECT_EQ(j["configuration"]["rmw"], "cyclonedds");
  ASSERT_EQ(j["resources"]["processes"].size(), 2u);
  EXPECT_EQ(j["resources"]["processes"][0]["label"], "pong");
  EXPECT_EQ(j["functional"]["metrics"]["identical_fraction"]["value"], 1.0);
  const Outcome intra =
      robotperf_cli("run n2 --rmw intra --count 130 --quiet --output " + out_.string());
  EXPECT_EQ(intra.exit_code, 2) << intra.out;
  EXPECT_NE(intra.out.find("needs an inter-process transport"), std::string::npos) << intra.out;
}

// n3 with a launcher of the user's: `env` starts the pong here, as ssh would there.
TEST_F(Cli, N3StartsThePongWithTheHostsLauncher) {
  const Outcome o =
      robotperf_cli("run n3 --host remote=env --count 130 --rate 50 --quiet --domain " + domain() +
                    " --output " + out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("host remote: pong (started with 'env'"), std::string::npos) << o.out;
  const auto j = result_json();
  ASSERT_EQ(j["network"]["hosts"].size(), 1u) << j["network"].dump();
  EXPECT_EQ(j["network"]["hosts"][0]["launcher"], "env");
  EXPECT_EQ(j["network"]["hosts"][0]["nodes"][0], "pong");
  EXPECT_EQ(j["network"]["hosts"][0]["same_machine"], true);
  EXPECT_TRUE(j["network"]["link"].is_null());
  EXPECT_EQ(j["nodes"][0]["host"], "remote");
  // Behind a launcher, the node's own process is the one measured.
  ASSERT_EQ(j["resources"]["processes"].size(), 2u);
  EXPECT_EQ(j["resources"]["processes"][0]["pid"], j["nodes"][0]["pid"]);

  const Outcome described = robotperf_cli("describe n3");
  EXPECT_NE(described.out.find("pong: util/relay (cpu; from built-in util) on host remote"),
            std::string::npos)
      << described.out;

  const Outcome single =
      robotperf_cli("run n3 --processes single --rmw fastdds --quiet --output " + out_.string());
  EXPECT_EQ(single.exit_code, 2) << single.out;
  EXPECT_NE(single.out.find("run in processes of their own"), std::string::npos) << single.out;
  const Outcome unknown =
      robotperf_cli("run n3 --host robot7=env --quiet --output " + out_.string());
  EXPECT_EQ(unknown.exit_code, 2) << unknown.out;
  EXPECT_NE(unknown.out.find("places no node on that host"), std::string::npos) << unknown.out;
}

// Why this process cannot make network namespaces (--netns), or empty when it can.
std::string netns_missing() {
  if (geteuid() != 0) return "--netns needs root to make network namespaces";
  const pid_t child = fork();
  if (child == 0) _exit(unshare(CLONE_NEWNET) == 0 ? 0 : 1);
  int status = 0;
  waitpid(child, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    return "root without CAP_SYS_ADMIN here: unshare(CLONE_NEWNET) is refused";
  return {};
}

// n3 across two network namespaces robotperf makes: the messages cross the veth pair.
TEST_F(Cli, N3CrossesTheLinkBetweenNetworkNamespaces) {
  if (const auto why = netns_missing(); !why.empty()) GTEST_SKIP() << why;
  for (const std::string rmw : {"fastdds", "cyclonedds"}) {
    fs::remove_all(out_);
    const Outcome o = robotperf_cli("run n3 --netns --rmw " + rmw +
                                    " --workload payload_bytes=16384 --count 130 --rate 50 "
                                    "--quiet --domain " +
                                    domain() + " --output " + out_.string());
    ASSERT_EQ(o.exit_code, 0) << rmw << "\n" << o.out;
    const auto j = result_json();
    const auto& link = j["network"]["link"];
    ASSERT_TRUE(link.is_object()) << j["network"].dump();
    EXPECT_EQ(link["rate"], "1gbit");
    // Every ping went out over the link and every echo came back over it (not shared memory).
    const uint64_t payloads = 130ull * 16384;
    EXPECT_GE(link["traffic"]["bytes_out"].get<uint64_t>(), payloads) << link.dump();
    EXPECT_GE(link["traffic"]["bytes_in"].get<uint64_t>(), payloads) << link.dump();
    const std::string launcher = j["network"]["hosts"][0]["launcher"];
    EXPECT_EQ(launcher, "ip netns exec " + link["remote_namespace"].get<std::string>());
    EXPECT_EQ(j["functional"]["metrics"]["identical_fraction"]["value"], 1.0);
    // Both namespaces are gone with the run.
    EXPECT_FALSE(fs::exists("/run/netns/" + link["runner_namespace"].get<std::string>()));
    EXPECT_FALSE(fs::exists("/run/netns/" + link["remote_namespace"].get<std::string>()));
  }
  const Outcome no_hosts = robotperf_cli("run n2 --netns --quiet --output " + out_.string());
  EXPECT_EQ(no_hosts.exit_code, 2) << no_hosts.out;
  EXPECT_NE(no_hosts.out.find("places no node on a host"), std::string::npos) << no_hosts.out;
}

// netem's delay shows in the round trip, or, on a kernel without sch_netem, one line says so.
TEST_F(Cli, N3NetemDelaysTheLinkOrSaysItCannot) {
  if (const auto why = netns_missing(); !why.empty()) GTEST_SKIP() << why;
  const Outcome o = robotperf_cli(
      "run n3 --netns --netem \"delay 2ms\" --count 130 --rate 50 "
      "--quiet --domain " +
      domain() + " --output " + out_.string());
  if (o.exit_code == 2) {
    EXPECT_NE(o.out.find("this kernel has no netem qdisc"), std::string::npos) << o.out;
    EXPECT_EQ(std::count(o.out.begin(), o.out.end(), '\n'), 1) << o.out;
    return;
  }
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const auto j = result_json();
  // 2 ms each way.
  EXPECT_GE(j["latency_ms"]["from_sent"]["p50"].get<double>(), 4.0) << j["latency_ms"].dump();
  EXPECT_EQ(j["network"]["link"]["netem"], "delay 2ms");
}

// n4: a keystore made by `security init`, then the secured ping-pong between namespaces.
TEST_F(Cli, N4SecuredPingPongBetweenNetworkNamespaces) {
  const fs::path keystore = out_ / "keystore";
  const Outcome init = robotperf_cli("security init " + keystore.string());
  ASSERT_EQ(init.exit_code, 0) << init.out;
  EXPECT_NE(init.out.find("crypto AES-GCM-GMAC"), std::string::npos) << init.out;
  const Outcome again = robotperf_cli("security init " + keystore.string());
  EXPECT_EQ(again.exit_code, 2) << again.out;
  EXPECT_NE(again.out.find("nothing to add"), std::string::npos) << again.out;

  const Outcome unsecured =
      robotperf_cli("run n4 --host remote=env --quiet --output " + out_.string());
  EXPECT_EQ(unsecured.exit_code, 2) << unsecured.out;
  EXPECT_NE(unsecured.out.find("give --security DIR"), std::string::npos) << unsecured.out;
  const Outcome intra = robotperf_cli("run n1 --rmw intra --security " + keystore.string() +
                                      " --quiet --output " + out_.string());
  EXPECT_EQ(intra.exit_code, 2) << intra.out;
  EXPECT_NE(intra.out.find("--security secures DDS"), std::string::npos) << intra.out;

  if (const auto why = netns_missing(); !why.empty()) GTEST_SKIP() << why;
  for (const std::string rmw : {"fastdds", "cyclonedds"}) {
    fs::remove_all(out_ / "runs");
    const Outcome o =
        robotperf_cli("run n4 --netns --rmw " + rmw + " --security " + keystore.string() +
                      " --count 130 --rate 50 --quiet " + "--domain " + domain() + " --output " +
                      (out_ / "runs").string());
    ASSERT_EQ(o.exit_code, 0) << rmw << "\n" << o.out;
    EXPECT_NE(o.out.find("security: authentication PKI-DH"), std::string::npos) << o.out;
    nlohmann::json j;
    for (const auto& e : fs::directory_iterator(out_ / "runs")) {
      if (e.path().extension() == ".json") j = nlohmann::json::parse(std::ifstream(e.path()));
    }
    const auto& security = j["software"]["transport"]["security"];
    ASSERT_TRUE(security.is_object()) << j["software"].dump();
    EXPECT_EQ(security["enclave"], "/robotperf");
    EXPECT_EQ(security["keystore"], fs::absolute(keystore).string());
    EXPECT_EQ(j["functional"]["metrics"]["identical_fraction"]["value"], 1.0);
    EXPECT_GT(j["network"]["link"]["traffic"]["bytes_out"].get<uint64_t>(), 0u);
  }

  // A keystore missing a file: one line naming it, before anything starts.
  fs::remove(keystore / "enclaves" / "robotperf" / "permissions.p7s");
  const Outcome broken = robotperf_cli("run n4 --netns --security " + keystore.string() +
                                       " --quiet --output " + out_.string());
  EXPECT_EQ(broken.exit_code, 2) << broken.out;
  EXPECT_NE(broken.out.find("permissions.p7s"), std::string::npos) << broken.out;
  EXPECT_EQ(std::count(broken.out.begin(), broken.out.end(), '\n'), 1) << broken.out;
}

// Why this process cannot make the WireGuard tunnel of n5 to n8, or empty when it can.
std::string wireguard_missing() {
  if (auto why = netns_missing(); !why.empty()) return why;
  if (std::system("wireguard-go --version >/dev/null 2>&1") != 0) return "no wireguard-go here";
  if (!fs::exists("/dev/net/tun")) return "no /dev/net/tun here";
  return {};
}

// n5 to n8: the ping-pong through a WireGuard tunnel robotperf makes, on one subnet or across a
// router, with and without DDS Security; discovery crosses it by unicast (no multicast in a
// tunnel), and the run records the tunnel.
TEST_F(Cli, N5ToN8CrossTheWireguardTunnel) {
  if (const auto why = wireguard_missing(); !why.empty()) GTEST_SKIP() << why;
  const fs::path keystore = out_ / "keystore";
  ASSERT_EQ(robotperf_cli("security init " + keystore.string()).exit_code, 0);
  const Outcome cyclone =
      robotperf_cli("run n5 --netns --rmw cyclonedds --quiet --output " + out_.string());
  EXPECT_EQ(cyclone.exit_code, 2) << cyclone.out;
  EXPECT_NE(cyclone.out.find("around the tunnel"), std::string::npos) << cyclone.out;
  for (const std::string id : {"n5", "n6", "n7", "n8"}) {
    const std::string rmw = "fastdds";
    const fs::path runs = out_ / (id + rmw);
    const bool secured = id == "n6" || id == "n8";
    const Outcome o =
        robotperf_cli("run " + id + " --netns --rmw " + rmw +
                      (secured ? " --security " + keystore.string() : "") +
                      " --workload payload_bytes=16384 --count 130 --rate 50 --quiet --domain " +
                      domain() + " --output " + runs.string());
    ASSERT_EQ(o.exit_code, 0) << id << " " << rmw << "\n" << o.out;
    nlohmann::json j;
    for (const auto& e : fs::directory_iterator(runs)) {
      if (e.path().extension() == ".json") j = nlohmann::json::parse(std::ifstream(e.path()));
    }
    EXPECT_EQ(j["validity"]["valid"], true) << id << j["validity"].dump();
    EXPECT_EQ(j["functional"]["metrics"]["identical_fraction"]["value"], 1.0);
    const auto& link = j["network"]["link"];
    ASSERT_TRUE(link["tunnel"].is_object()) << link.dump();
    EXPECT_EQ(link["tunnel"]["implementation"], "wireguard-go");
    EXPECT_EQ(link["tunnel"]["mtu"], 1420);
    EXPECT_EQ(link["topology"], id == "n7" || id == "n8" ? "routed" : "same-subnet");
    // Every ping and echo crossed the tunnel's device.
    const uint64_t payloads = 130ull * 16384;
    EXPECT_GE(link["traffic"]["bytes_out"].get<uint64_t>(), payloads) << link.dump();
    EXPECT_GE(link["traffic"]["bytes_in"].get<uint64_t>(), payloads) << link.dump();
    EXPECT_FALSE(fs::exists("/run/netns/" + link["runner_namespace"].get<std::string>()));
    EXPECT_FALSE(fs::exists("/run/netns/" + link["remote_namespace"].get<std::string>()));
  }
}

// a3 and a4 on every transport: valid, with a functional section that passed.
void expect_functional_result(const nlohmann::json& j, const std::string& id,
                              const std::string& rmw, const std::string& evaluator) {
  EXPECT_EQ(j["benchmark"]["id"], id);
  EXPECT_EQ(j["configuration"]["rmw"], rmw);
  EXPECT_EQ(j["validity"]["valid"], true) << j["validity"].dump();
  const auto& f = j["functional"];
  ASSERT_TRUE(f.is_object()) << j.dump();
  EXPECT_EQ(f["evaluator"], evaluator);
  EXPECT_EQ(f["valid"], true) << f.dump();
  EXPECT_GT(f["samples"]["evaluated"].get<int>(), 0);
  for (const auto& [name, m] : f["metrics"].items()) {
    EXPECT_TRUE(m["value"].is_number()) << name;
    EXPECT_EQ(m["passed"], true) << name;
  }
}

TEST_F(Cli, RunA3AndA4OnEveryTransport) {
  const std::pair<const char*, const char*> benchmarks[] = {{"a3", "stereo_disparity"},
                                                            {"a4", "depth_point_cloud"}};
  for (const auto& [id, evaluator] : benchmarks) {
    for (const std::string rmw : {"intra", "fastdds", "cyclonedds"}) {
      fs::remove_all(out_);
      // 10 Hz leaves a loaded 2-core machine room for 10 MB point clouds through DDS.
      const Outcome o = robotperf_cli(std::string("run ") + id + " --count 40 --rate 10 --rmw " +
                                      rmw + " --domain " + domain() + " --output " + out_.string());
      ASSERT_EQ(o.exit_code, 0) << id << " " << rmw << "\n" << o.out;
      EXPECT_NE(o.out.find("functional result: VALID"), std::string::npos) << o.out;
      expect_functional_result(result_json(), id, rmw, evaluator);
    }
  }
  const Outcome d = robotperf_cli("describe a3");
  EXPECT_NE(d.out.find("evaluator stereo_disparity"), std::string::npos) << d.out;
  EXPECT_NE(d.out.find("threshold bad1 <= 0.05"), std::string::npos) << d.out;
}

// describe shows the dataset's workload and the parameters a kernel computes, which a run
// depends on as much as on those given.
TEST_F(Cli, DescribeShowsTheWorkloadAndComputedParameters) {
  const Outcome d = robotperf_cli("describe d1");
  ASSERT_EQ(d.exit_code, 0) << d.out;
  EXPECT_NE(d.out.find("\nworkload:  requests = 40, seed = 1\n"), std::string::npos) << d.out;
  EXPECT_NE(d.out.find("param seed computed: OMPL's seed"), std::string::npos) << d.out;
  EXPECT_EQ(robotperf_cli("describe a1").out.find("workload:"), std::string::npos);
}

// d1-d6 end to end on intra, short: valid, functional checks passed, the workload seed recorded.
TEST_F(Cli, RunManipulationBenchmarks) {
  // A plan takes 0.1 s here, several times that on a loaded machine: at 4 Hz the queue of queries
  // (10 deep) does not overflow.
  const std::string d1_rate = rate_option(4, 1);
  const std::tuple<const char*, const char*, std::string> benchmarks[] = {
      {"d6", "forward_kinematics", "--count 120"},
      {"d4", "inverse_kinematics", "--count 120"},
      {"d5", "inverse_kinematics", "--count 120"},
      {"d2", "collision", "--count 120"},
      {"d3", "collision", "--count 120"},
      {"d1", "plan_execution", "--count 34" + d1_rate}};
  for (const auto& [id, evaluator, options] : benchmarks) {
    fs::remove_all(out_);
    const Outcome o =
        robotperf_cli(std::string("run ") + id + " " + options + " --output " + out_.string());
    ASSERT_EQ(o.exit_code, 0) << id << "\n" << o.out;
    const nlohmann::json j = result_json();
    expect_functional_result(j, id, "intra", evaluator);
    EXPECT_EQ(j["dataset"]["parameters"]["seed"], "1") << j["dataset"].dump();
  }
  // OMPL is seeded from the workload seed: a second d1 process plans the same paths.
  const auto d1_path_length = [&] {
    return result_json()["functional"]["metrics"]["path_length_mean_rad"]["value"];
  };
  const nlohmann::json first = d1_path_length();
  fs::remove_all(out_);
  ASSERT_EQ(robotperf_cli("run d1 --count 34" + d1_rate + " --output " + out_.string()).exit_code,
            0);
  EXPECT_EQ(d1_path_length(), first);
}

// The localization benchmarks end to end on every transport, on a bag without ground truth, and
// with a kernel misconfigured the way a user can (a wrong tag size), which only the functional
// check catches.
TEST_F(Cli, RunLocalizationBenchmarks) {
  const std::pair<const char*, const char*> benchmarks[] = {
      {"b1", "visual_odometry"}, {"b2", "map_localization"}, {"b3", "apriltag_detection"}};
  for (const auto& [id, evaluator] : benchmarks) {
    for (const std::string rmw : {"intra", "fastdds", "cyclonedds"}) {
      fs::remove_all(out_);
      const Outcome o =
          robotperf_cli(std::string("run ") + id + " --count 110" + rate_option(20, 5) + " --rmw " +
                        rmw + " --domain " + domain() + " --output " + out_.string());
      ASSERT_EQ(o.exit_code, 0) << id << " " << rmw << "\n" << o.out;
      EXPECT_NE(o.out.find("functional result: VALID"), std::string::npos) << o.out;
      expect_functional_result(result_json(), id, rmw, evaluator);
    }
  }

  fs::remove_all(out_);
  const std::string bag = (out_ / "tags").string();
  Outcome o = robotperf_cli("dataset generate localization/apriltags --out " + bag);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  // At 20 Hz, as the runs above: at the bag's own rate, 1280x720 detection beside another test on
  // a 2-core machine fell behind and lost frames.
  o = robotperf_cli("run b3 --dataset " + bag + " --count 110" + rate_option(20, 5) + " --output " +
                    (out_ / "r").string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("outputs not checked for accuracy (apriltag_detection)"), std::string::npos)
      << o.out;

  // b3 with the tags declared 0.20 m instead of 0.22 m: every tag found, every distance 9 % short.
  const fs::path package = out_ / "bench" / "localization" / "x3_wrong_tag_size";
  fs::create_directories(package);
  for (const char* file : {"benchmark.yaml", "graph.yaml"}) {
    std::ifstream in(fs::path(ROBOTPERF_SOURCE_DIR) /
                     "benchmarks/localization/b3_apriltag_detection" / file);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (const auto& [from, to] : {std::pair<std::string, std::string>{"id: b3", "id: x3"},
                                   {"name: b3_apriltag_detection", "name: x3_wrong_tag_size"},
                                   {"size: 0.22", "size: 0.20"}}) {
      if (auto at = text.find(from); at != std::string::npos) text.replace(at, from.size(), to);
    }
    std::ofstream(package / file) << text;
  }
  o = robotperf_cli("--benchmarks " + (out_ / "bench").string() + " run x3 --count 110" +
                    sanitized_rate_option(5) + " --output " + (out_ / "x3").string());
  EXPECT_EQ(o.exit_code, 3) << o.out;
  EXPECT_NE(o.out.find("functional result: INVALID"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("translation_error_median_m"), std::string::npos) << o.out;
}

TEST_F(Cli, UnknownBenchmarkIsOneClearLine) {
  const Outcome o = robotperf_cli("run z9 --output " + out_.string());
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_EQ(std::count(o.out.begin(), o.out.end(), '\n'), 1) << o.out;
  EXPECT_NE(o.out.find("unknown benchmark 'z9'"), std::string::npos) << o.out;
  EXPECT_FALSE(fs::exists(out_) && !fs::is_empty(out_));
}

TEST_F(Cli, BadOptionIsOneClearLine) {
  for (const char* args :
       {"run a1 --rate fast", "run a1 --rmw zenoh", "run a1 --count 5 --duration 2", "fly a1"}) {
    const Outcome o = robotperf_cli(args);
    EXPECT_EQ(o.exit_code, 2) << args << "\n" << o.out;
    EXPECT_EQ(std::count(o.out.begin(), o.out.end(), '\n'), 1) << args << "\n" << o.out;
  }
}

// A number out of its bounds is named with the bound in words (CLI11's own check printed the
// range up to DBL_MAX, three hundred digits long).
TEST_F(Cli, NumberOutOfItsBoundsIsOneShortLine) {
  for (const auto& [args, says] : std::vector<std::pair<std::string, std::string>>{
           {"run a1 --count 0", "--count: must be a whole number, 1 or more (got 0)"},
           {"run a1 --count -3", "--count: must be a whole number, 1 or more (got -3)"},
           {"run a1 --callback-timeout 0", "must be a number greater than 0 (got 0)"},
           {"run a1 --rate-scale x", "must be a number greater than 0 (got x)"},
           {"run a1 --callback-timeout 0x10",
            "must be seconds, or a duration with its unit: 5s, 500ms, 2min (got 0x10)"},
           {"run a1 --rate 0x10",
            "--rate: must be a rate in Hz, or with its unit: 30Hz, 1.5kHz (got 0x10)"},
           {"run a1 --duration 5parsecs",
            "--duration: must be seconds, or a duration with its unit: 5s, 500ms, 2min (got "
            "5parsecs)"},
           {"run a1 --warmup -1", "--warmup: must be a whole number, 0 or more (got -1)"},
           {"run a1 --repeat 10001",
            "--repeat: must be a whole number from 1 to 10000 (got 10001)"},
           {"run a1 --domain 233",
            "--domain: must be a DDS domain id from 0 to 232, or auto (got 233)"}}) {
    const Outcome o = robotperf_cli(args);
    EXPECT_EQ(o.exit_code, 2) << args << "\n" << o.out;
    EXPECT_EQ(std::count(o.out.begin(), o.out.end(), '\n'), 1) << args << "\n" << o.out;
    EXPECT_NE(o.out.find(says), std::string::npos) << args << "\n" << o.out;
    EXPECT_LT(o.out.size(), 200u) << args << "\n" << o.out;
  }
}

// A mistyped verb, subcommand, option, choice or benchmark id is one line naming the nearest that
// exists; a word near none (or near two alike) gets no guess.
TEST_F(Cli, TyposAreOneLineWithTheirNearestName) {
  for (const auto& [args, says] : std::vector<std::pair<std::string, std::string>>{
           {"descrbe a1", "unknown command 'descrbe'; did you mean 'describe'?"},
           {"lst", "unknown command 'lst'; did you mean 'list'?"},
           {"results lsit",
            "unknown command 'lsit'; did you mean 'list'? (robotperf results --help"},
           {"run a1 --rat 60", "unknown option --rat for 'robotperf run'; did you mean '--rate'?"},
           {"--benchmark /tmp list",
            "unknown option --benchmark for 'robotperf'; did you mean "
            "'--benchmarks'?"},
           {"run a1 --rmw fastds",
            "fastds not in {intra,fastdds,cyclonedds}; did you mean "
            "'fastdds'?"},
           {"list kernel", "did you mean 'kernels'?"},
           {"describe a11", "unknown benchmark 'a11'; did you mean 'a1'?"},
           {"help resuls", "unknown command 'resuls'; did you mean 'results'?"},
           {"frobnicate", "unknown command 'frobnicate' (robotperf --help lists the commands)"},
           {"describe x9", "unknown benchmark 'x9' (available:"}}) {
    const Outcome o = robotperf_cli(args);
    EXPECT_EQ(o.exit_code, 2) << args << "\n" << o.out;
    EXPECT_EQ(std::count(o.out.begin(), o.out.end(), '\n'), 1) << args << "\n" << o.out;
    EXPECT_NE(o.out.find(says), std::string::npos) << args << "\n" << o.out;
  }
}

// Durations and rates take their unit: 500ms is half a second, 1.5kHz is 1500 Hz.
TEST_F(Cli, DurationsAndRatesTakeTheirUnit) {
  const Outcome o = robotperf_cli(
      "run a1 --rate 0.06kHz --duration 1500ms --warmup 2 --quiet "
      "--output " +
      out_.string());
  EXPECT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("sent 90 "), std::string::npos) << o.out;
}

// `help COMMAND...` prints what `COMMAND... --help` does, under the command's full name.
TEST_F(Cli, HelpOfACommand) {
  const Outcome run = robotperf_cli("help run");
  EXPECT_EQ(run.exit_code, 0) << run.out;
  EXPECT_NE(run.out.find("Usage: robotperf run [OPTIONS] id"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("--find-peak"), std::string::npos) << run.out;
  const Outcome list = robotperf_cli("help results list");
  EXPECT_EQ(list.exit_code, 0) << list.out;
  EXPECT_NE(list.out.find("Usage: robotperf results list"), std::string::npos) << list.out;
  const Outcome all = robotperf_cli("help");
  EXPECT_EQ(all.exit_code, 0) << all.out;
  EXPECT_NE(all.out.find("Usage: robotperf [OPTIONS] SUBCOMMAND"), std::string::npos) << all.out;
  // Every command's help ends with at least one example.
  for (const char* command : {"list", "describe", "run", "results", "results list", "readme",
                              "report", "compare", "trace", "trace analyze", "bag", "bag info",
                              "dataset", "sysinfo", "graph", "security", "completion"}) {
    const Outcome help = robotperf_cli(std::string("help ") + command);
    EXPECT_NE(help.out.find("Example"), std::string::npos) << command << "\n" << help.out;
  }
}

// --device-resident refuses, in one line, a run with nothing to keep on the device and a run whose
// nodes are not in one process.
TEST_F(Cli, DeviceResidentThatCannotApplyIsOneLine) {
  for (const auto& [args, says] : std::vector<std::pair<std::string, std::string>>{
           {"run a1 --device-resident", "no topic of a1 can stay on the device"},
           {"run a5 --backend opencl --device-resident", "no topic of a5 can stay on the device"},
           {"run a1 --device-resident --rmw fastdds",
            "inside one process: run it with --rmw intra"}}) {
    const Outcome o = robotperf_cli(args + " --output " + out_.string());
    EXPECT_EQ(o.exit_code, 2) << args << "\n" << o.out;
    EXPECT_EQ(std::count(o.out.begin(), o.out.end(), '\n'), 1) << args << "\n" << o.out;
    EXPECT_NE(o.out.find(says), std::string::npos) << args << "\n" << o.out;
  }
}

TEST_F(Cli, WarmupNotBelowCountIsRefused) {
  const Outcome o = robotperf_cli("run a2 --count 5 --warmup 5 --output " + out_.string());
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.out.find("warm-up"), std::string::npos) << o.out;
}

TEST_F(Cli, ResultHasMachineSoftwarePowerResourcesAndWarnings) {
  const Outcome o = robotperf_cli("run a2 --count 40 --output " + out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const auto j = result_json();
  const auto& m = j["machine"];
  EXPECT_FALSE(m["cpu"]["model"].is_null());
  EXPECT_GE(m["cpu"]["logical_cpus"].get<int>(), 1);
  EXPECT_FALSE(m["kernel"]["release"].is_null());
  EXPECT_TRUE(m["kernel"].contains("preempt_rt"));
  EXPECT_TRUE(m["container"].contains("detected"));
  EXPECT_GT(m["memory_total_bytes"].get<double>(), 0);
  const auto& sw = j["software"];
  EXPECT_FALSE(sw["compiler"].get<std::string>().empty());
  EXPECT_NE(sw["cxx_flags"].get<std::string>().find("-Wall"), std::string::npos);
  EXPECT_FALSE(sw["libraries"]["fastdds"].get<std::string>().empty());
  EXPECT_FALSE(sw["libraries"]["opencv"].get<std::string>().empty());
  EXPECT_EQ(sw["transport"]["rmw"], "intra");

  // 35 measured messages are too few for p99: that rule applies everywhere.
  bool samples_rule = false;
  for (const auto& w : j["warnings"]) samples_rule |= w["rule"] == "samples";
  EXPECT_TRUE(samples_rule) << j["warnings"].dump();
  const auto run_warnings = o.out.find("warnings (this run):\n");
  ASSERT_NE(run_warnings, std::string::npos) << o.out;
  EXPECT_NE(o.out.find("\n  samples: 35 measured messages", run_warnings), std::string::npos)
      << o.out;

  const auto& power = j["power"];
  if (!power["available"].get<bool>()) {
    // This machine has no power sensors: unavailable, with the reason, never 0.
    EXPECT_TRUE(power["total"].is_null());
    EXPECT_NE(power["unavailable_reason"].get<std::string>().find("rapl:"), std::string::npos);
    EXPECT_NE(o.out.find("power: not measured (no power source found; "), std::string::npos)
        << o.out;
  }
  EXPECT_GT(power["rounds"].get<int>(), 2);

  const auto& resources = j["resources"];
  ASSERT_EQ(resources["processes"].size(), 1u);
  EXPECT_EQ(resources["processes"][0]["measured"], true);
  EXPECT_GT(resources["processes"][0]["peak_rss_bytes"].get<double>(), 1 << 20);
  EXPECT_FALSE(resources["system"]["busy_percent"].is_null());
  EXPECT_NEAR(resources["window_s"].get<double>(), power["window_s"].get<double>(), 1e-9);
}

TEST_F(Cli, ExternalMeterGivesEnergyPerMessageAndThroughputPerWatt) {
  const Outcome o = robotperf_cli(
      "run a2 --count 40 --power-meter 'echo 12.5' --power-sources external --power-period 0.05 "
      "--output " +
      out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const auto j = result_json();
  const auto& power = j["power"];
  ASSERT_EQ(power["available"], true) << power.dump();
  EXPECT_NEAR(power["total"]["average_w"].get<double>(), 12.5, 1e-9);
  const double energy = power["total"]["energy_j"].get<double>();
  EXPECT_NEAR(energy, 12.5 * power["window_s"].get<double>(), 1e-9);
  const double matched = j["counts"]["matched"].get<double>();
  EXPECT_NEAR(power["total"]["energy_per_message_mj"].get<double>(), energy * 1e3 / matched, 1e-9);
  EXPECT_NEAR(power["total"]["throughput_per_watt"].get<double>(),
              j["throughput"]["output_hz"].get<double>() / 12.5, 1e-9);
  EXPECT_EQ(power["sources"][0]["name"], "external:meter");
  // One line: the total, energy, per message, per watt, then the sources in the total.
  EXPECT_TRUE(
      std::regex_search(o.out, std::regex(R"(\npower: 12\.50 W, [0-9.]+ J, [0-9.]+ mJ/msg, )"
                                          R"([0-9.]+ msg/s per W \(external:meter 12\.50 W\)\n)")))
      << o.out;
}

TEST_F(Cli, BrokenPowerMeterIsOneClearLine) {
  const Outcome o =
      robotperf_cli("run a2 --count 20 --power-meter 'echo nope' --output " + out_.string());
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_EQ(std::count(o.out.begin(), o.out.end(), '\n'), 1) << o.out;
  EXPECT_NE(o.out.find("expected watts"), std::string::npos) << o.out;
}

TEST_F(Cli, StrictRefusesWhenARunRuleIsBroken) {
  const Outcome o = robotperf_cli("run a2 --count 20 --strict --output " + out_.string());
  EXPECT_EQ(o.exit_code, 4) << o.out;
  EXPECT_NE(o.out.find("--strict: not running"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("samples: 15 measured messages"), std::string::npos) << o.out;
  EXPECT_FALSE(fs::exists(out_) && !fs::is_empty(out_));
}

TEST_F(Cli, PinnedRunIsRecorded) {
  const Outcome o = robotperf_cli("run a2 --count 40 --cpus 0 --output " + out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_EQ(result_json()["configuration"]["scheduling"]["cpus"], "0");
  const Outcome bad = robotperf_cli("run a2 --count 20 --cpus 1-x --output " + out_.string());
  EXPECT_EQ(bad.exit_code, 2) << bad.out;
  EXPECT_NE(bad.out.find("bad CPU list '1-x'"), std::string::npos) << bad.out;
  // An empty list (a shell variable that was not set) pins nothing: refused, not ignored.
  const Outcome empty = robotperf_cli("run a2 --count 20 --cpus '' --output " + out_.string());
  EXPECT_EQ(empty.exit_code, 2) << empty.out;
  EXPECT_NE(empty.out.find("bad CPU list ''"), std::string::npos) << empty.out;
}

// A meter that fails with output over several lines is still one line of robotperf's.
TEST_F(Cli, PowerMeterPrintingSeveralLinesIsOneLine) {
  const Outcome o =
      robotperf_cli("sysinfo --power-meter \"printf 'abc\\ndef'\" --power-sources external");
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_EQ(std::ranges::count(o.out, '\n'), 1) << o.out;
  EXPECT_NE(o.out.find("printed 'abc\\ndef'"), std::string::npos) << o.out;
}

// The flags recorded are those the compiler got: add_compile_options' generator expressions
// ($<$<COMPILE_LANGUAGE:C,CXX>:-Wall;-Wextra>) expanded.
TEST_F(Cli, SysinfoRecordsTheCompilerFlagsExpanded) {
  const Outcome o = robotperf_cli("sysinfo --power-sources rapl --sysfs-root " + out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const auto flags = nlohmann::json::parse(o.out)["software"]["cxx_flags"].get<std::string>();
  EXPECT_EQ(flags.find("$<"), std::string::npos) << flags;
  EXPECT_EQ(flags.find(';'), std::string::npos) << flags;
  EXPECT_NE(flags.find("-Wall -Wextra"), std::string::npos) << flags;
}

TEST_F(Cli, SysinfoShowsMachineSoftwareAndPowerSources) {
  const fs::path zone = out_ / "sys/class/powercap/intel-rapl:0";
  fs::create_directories(zone);
  std::ofstream(zone / "name") << "package-0\n";
  std::ofstream(zone / "energy_uj") << "123456\n";
  std::ofstream(zone / "max_energy_range_uj") << "262143328850\n";
  const Outcome o =
      robotperf_cli("sysinfo --sysfs-root " + out_.string() + " --power-sources rapl");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const auto j = nlohmann::json::parse(o.out);
  EXPECT_FALSE(j["machine"]["cpu"]["logical_cpus"].is_null());
  EXPECT_FALSE(j["software"]["git_revision"].get<std::string>().empty());
  ASSERT_EQ(j["power"]["sources"].size(), 1u);
  EXPECT_EQ(j["power"]["sources"][0]["name"], "rapl:package-0");
  EXPECT_EQ(j["power"]["sources"][0]["kind"], "energy_counter");

  const Outcome here = robotperf_cli("sysinfo");
  ASSERT_EQ(here.exit_code, 0) << here.out;
  const auto h = nlohmann::json::parse(here.out);
  if (h["power"]["sources"].empty()) {
    EXPECT_FALSE(h["power"]["notes"].empty());
  }
}

}  // namespace

namespace {

// A bag of ROS 2's own, in the shared data folder.
std::string shared_bag(const std::string& name) {
  return shared_data("rosbag2/" + name).string();
}

TEST_F(Cli, BagInfoLikeRos2BagInfo) {
  const Outcome o = robotperf_cli("bag info " + shared_bag("sqlite3_cdr_test"));
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("Storage id:        sqlite3"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("Messages:          7"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("/array_topic         4 msgs  test_msgs/msg/Arrays"), std::string::npos)
      << o.out;
  EXPECT_NE(o.out.find("QoS: reliable, transient_local"), std::string::npos) << o.out;
}

TEST_F(Cli, BagEchoAndConvert) {
  Outcome o = robotperf_cli("bag echo " + shared_bag("mcap_talker") + " --topic /topic --limit 4");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("--- /topic [std_msgs/msg/String] at 1585866236.613084249\n"
                       "data: 'Hello, world! 3'\n"),
            std::string::npos)
      << o.out;
  EXPECT_EQ(o.out.find("Hello, world! 4"), std::string::npos) << "--limit 4 printed more";

  o = robotperf_cli("bag convert " + shared_bag("mcap_talker") + " " + (out_ / "db").string() +
                    " --storage sqlite3");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  o = robotperf_cli("bag echo " + (out_ / "db").string() + " --topic /topic");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("data: 'Hello, world! 9'"), std::string::npos) << o.out;
}

TEST_F(Cli, DatasetGenerateWritesARealBag) {
  const std::string bag = (out_ / "image").string();
  Outcome o = robotperf_cli("dataset generate perception/image --out " + bag);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  o = robotperf_cli("bag info " + bag);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("Storage id:        mcap"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("/camera/image_raw          68 msgs  sensor_msgs/msg/Image"),
            std::string::npos)
      << o.out;
  EXPECT_NE(o.out.find("/camera/camera_info        68 msgs  sensor_msgs/msg/CameraInfo"),
            std::string::npos)
      << o.out;
  // The bag carries the definitions, so any reader can decode it.
  o = robotperf_cli("bag echo " + bag + " --topic /camera/image_raw --limit 1");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("encoding: 'rgb8'"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("data: '<921600 bytes>'"), std::string::npos) << o.out;
}

TEST_F(Cli, BadBagIsOneClearLine) {
  fs::create_directories(out_);
  for (const std::string& args : std::vector<std::string>{
           "bag info " + out_.string(), "bag echo " + (out_ / "missing").string(),
           "dataset generate no/such",
           "bag convert " + shared_bag("mcap_talker") + " " + (out_ / "x").string() +
               " --compression brotli"}) {
    const Outcome o = robotperf_cli(args);
    EXPECT_EQ(o.exit_code, 2) << args << ": " << o.out;
    EXPECT_EQ(std::count(o.out.begin(), o.out.end(), '\n'), 1) << args << ": " << o.out;
  }
}

// A split size the byte count cannot hold is refused before anything is written; 0 is one file.
TEST_F(Cli, BagConvertMaxFileSizeIsAFiniteNumberZeroOrMore) {
  for (const char* size : {"-1", "nan", "inf", "1e300"}) {
    const Outcome o = robotperf_cli("bag convert " + shared_bag("mcap_talker") + " " +
                                    (out_ / "x").string() + " --max-file-size " + size);
    EXPECT_EQ(o.exit_code, 2) << size << ": " << o.out;
    EXPECT_EQ(std::ranges::count(o.out, '\n'), 1) << size << ": " << o.out;
    EXPECT_NE(o.out.find("--max-file-size: must be a number of MiB"), std::string::npos)
        << size << ": " << o.out;
    EXPECT_FALSE(fs::exists(out_ / "x")) << size;
  }
  const Outcome o = robotperf_cli("bag convert " + shared_bag("mcap_talker") + " " +
                                  (out_ / "x").string() + " --max-file-size 0");
  EXPECT_EQ(o.exit_code, 0) << o.out;
}

// Whole numbers are decimal digits: CLI11 reads integers with strtoll/strtoull in base 0, so
// 0x10 was 16, 010 was 8, and -1 an unsigned 2^64-1 (every message, the largest chunk), while a
// run's --domain was range-checked in base 0 and then read in decimal (0x10 ran on domain 0).
// The runs end before any benchmark starts, should the option be taken: 5 messages, warm-up 5.
TEST_F(Cli, WholeNumberOptionsTakeDecimalDigitsOnly) {
  const std::string run = "run a2 --quiet --output " + out_.string() + " ";
  const std::string stops = " --count 5 --warmup 5";
  const std::string bag = shared_bag("mcap_talker");
  for (const auto& [args, option] : std::vector<std::pair<std::string, std::string>>{
           {run + "--count 0x10 --warmup 16", "--count"},
           {run + "--count 5 --warmup 0x10", "--warmup"},
           {run + "--count 1e1 --warmup 10", "--count"},
           {run + "--repeat 0x10 --find-peak", "--repeat"},
           {run + "--rt-priority 0x10" + stops, "--rt-priority"},
           {run + "--arrival-seed -1" + stops, "--arrival-seed"},
           {run + "--trace-subbuf-size -1" + stops, "--trace-subbuf-size"},
           {run + "--domain 0x10" + stops, "--domain"},
           {run + "--domain 0300" + stops, "--domain"},
           {run + "--domain +7" + stops, "--domain"},
           {"graph --listen 0.1 --domain 0x10", "--domain"},
           {"node no/such --node x --domain 0x10", "--domain"},
           {"node no/such --node x --rt-priority 0x10", "--rt-priority"},
           {"trace analyze " + out_.string() + " --pid -1", "--pid"},
           {"bag echo " + bag + " --limit -1", "--limit"},
           {"bag echo " + bag + " --max-array -1", "--max-array"},
           {"bag convert " + bag + " " + (out_ / "x").string() + " --chunk-size -1",
            "--chunk-size"}}) {
    const Outcome o = robotperf_cli(args);
    EXPECT_EQ(o.exit_code, 2) << args << "\n" << o.out;
    EXPECT_EQ(std::ranges::count(o.out, '\n'), 1) << args << "\n" << o.out;
    EXPECT_TRUE(o.out.starts_with("robotperf: " + option + ": must be ")) << args << "\n" << o.out;
  }
  EXPECT_FALSE(fs::exists(out_ / "x"));
  // Leading zeros are decimal, not octal: 010 is ten.
  const Outcome o = robotperf_cli(run + "--count 010 --warmup 010");
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_NE(o.out.find("warm-up (10) must be smaller than the message count (10)"),
            std::string::npos)
      << o.out;
}

// Options that would change nothing, or a series with a bad value anywhere in it, are refused
// before the first run: one line, exit 2, nothing written.
TEST_F(Cli, OptionsThatWouldChangeNothingOrFailLaterAreRefusedFirst) {
  const std::string out = " --quiet --count 20 --output " + (out_ / "r").string();
  const std::string bag = shared_bag("mcap_talker");
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {"run n1 --sweep payload_bytes=64,abc" + out, "payload_bytes"},
           {"run n1 --sweep no_such=1,2" + out, "no_such"},
           {"run a5 --dataset " + bag + " --workload seed=2" + out,
            "--workload sets the generated dataset's parameters: not with --dataset"},
           {"run n1 --dataset " + bag + " --sweep payload_bytes=64,128" + out,
            "--sweep sets the generated dataset's parameters: not with --dataset"},
           {"run a5 --arrival-seed 5" + out, "--arrival-seed only applies with --arrival poisson"},
           {"run a5 --repeat 2 --repeat-pause nan" + out, "--repeat-pause: must be a number"},
           {"graph --listen nan --domain " + domain(), "--listen: must be a number"}}) {
    const Outcome o = robotperf_cli(args);
    EXPECT_EQ(o.exit_code, 2) << args << ": " << o.out;
    EXPECT_EQ(std::ranges::count(o.out, '\n'), 1) << args << ": " << o.out;
    EXPECT_NE(o.out.find(message), std::string::npos) << args << ": " << o.out;
    EXPECT_FALSE(fs::exists(out_ / "r") && !fs::is_empty(out_ / "r")) << args;
  }
}

TEST_F(Cli, WithoutACommandItListsTheCommands) {
  const Outcome o = robotperf_cli("");
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.out.find("give a command"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("run"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("list"), std::string::npos) << o.out;
}

// Checks before timing: each is one line, exit 2, and nothing is run or written.
TEST_F(Cli, SettingsThatCannotWorkAreRefusedBeforeTheRun) {
  fs::create_directories(out_);
  const fs::path file = out_ / "a-file";
  std::ofstream(file) << "x";
  const std::pair<std::string, std::string> cases[] = {
      {"--output " + (file / "results").string(), "cannot write there"},
      {"--cpus 1000", "CPU 1000 is not available to this process"},
      {"--mode grey --trace-subbuf-size 1", "LTTng takes a power of two"},
      {"--power-meter 'echo 1e308'", "expected watts (a number from 0 to 100000)"},
  };
  for (const auto& [args, message] : cases) {
    const Outcome o =
        robotperf_cli("run a5 --count 20 --quiet " + args + " --domain " + domain() +
                      (args.starts_with("--output") ? "" : " --output " + (out_ / "r").string()));
    EXPECT_EQ(o.exit_code, 2) << args << ": " << o.out;
    EXPECT_EQ(std::ranges::count(o.out, '\n'), 1) << o.out;
    EXPECT_NE(o.out.find(message), std::string::npos) << args << ": " << o.out;
  }
  EXPECT_FALSE(fs::exists(out_ / "r") && !fs::is_empty(out_ / "r"));
  // A --duration too short for the rate says what the count was derived from.
  const Outcome o = robotperf_cli("run a5 --rate 1 --duration 0.4 --warmup 1 --quiet --output " +
                                  (out_ / "r").string());
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_NE(o.out.find("message count (0 = 0.4 s x 1 Hz; give a longer --duration or a --count)"),
            std::string::npos)
      << o.out;
}

}  // namespace

TEST_F(Cli, RunReplaysABagOnItsOwnTimeline) {
  const std::string bag = (out_ / "camera").string();
  Outcome o = robotperf_cli("dataset generate perception/image --out " + bag);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  // 30 Hz recorded, played twice as fast (a fifth as fast in a sanitized build); the result says
  // so.
  const std::string scale = kSanitizedBuild ? "0.2" : "2";
  const std::string rate = kSanitizedBuild ? "6.0" : "60.0";
  o = robotperf_cli("run a1 --dataset " + bag + " --rate bag --rate-scale " + scale +
                    " --count 60 --output " + out_.string() + " --quiet");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const auto j = result_json();
  expect_clean_a1_result(j, "intra");
  EXPECT_EQ(j["dataset"]["name"], bag);
  EXPECT_NEAR(j["configuration"]["rate_hz"].get<double>(), std::stod(rate), 0.1);
  EXPECT_EQ(j["configuration"]["timeline"], "bag");
  EXPECT_EQ(j["configuration"]["rate_scale"], std::stod(scale));
  EXPECT_NE(o.out.find(" · " + rate + " Hz (the bag's timeline x" + scale + ") · dataset " + bag),
            std::string::npos)
      << o.out;
}

// A bag replayed through Cyclone DDS in one process: Playback's participant sends the recorded
// bytes of the same message type the graph's nodes send typed, and each keeps its own.
TEST_F(Cli, RunReplaysABagThroughCycloneDdsInOneProcess) {
  const std::string bag = (out_ / "camera").string();
  Outcome o = robotperf_cli("dataset generate perception/image --out " + bag);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  o = robotperf_cli("run a1 --dataset " + bag + " --count 40 --rate 10 --rmw cyclonedds --domain " +
                    domain() + " --quiet --output " + out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const auto j = result_json();
  EXPECT_EQ(j["configuration"]["rmw"], "cyclonedds");
  EXPECT_EQ(j["counts"]["matched"], 35);
  EXPECT_EQ(j["validity"]["valid"], true) << j["validity"].dump();
}

// A bag replayed into nodes that each run in their own process: the Playback publishes the
// recorded CDR payloads as they are, with the IDs written into their header bytes.
TEST_F(Cli, RunReplaysABagIntoOneProcessPerNode) {
  const std::string bag = (out_ / "camera").string();
  Outcome o = robotperf_cli("dataset generate perception/image --out " + bag);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  o = robotperf_cli("run a1 --dataset " + bag +
                    " --count 40 --rate 10 --rmw fastdds --processes per-node --domain " +
                    domain() + " --quiet --output " + out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  auto j = result_json();
  EXPECT_EQ(j["dataset"]["name"], bag);
  EXPECT_EQ(j["configuration"]["processes"], "per-node");
  EXPECT_EQ(j["counts"]["measured"], 35);
  EXPECT_EQ(j["counts"]["matched"], 35);
  EXPECT_EQ(j["validity"]["valid"], true) << j["validity"].dump();
  ASSERT_EQ(j["nodes"].size(), 2u);
  for (const auto& n : j["nodes"]) {
    EXPECT_EQ(n["exit_status"], "ok") << n.dump();
    EXPECT_GT(n["pid"].get<int>(), 0);
  }

  // a4's generated dataset plays into a4 as it is, three inputs a frame; a bag has no ground
  // truth, so the outputs are not checked, and the result says so.
  const std::string depth_bag = (out_ / "depth").string();
  o = robotperf_cli("dataset generate perception/depth --out " + depth_bag);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  fs::remove(result_json_path());
  o = robotperf_cli("run a4 --dataset " + depth_bag + " --count 35" + rate_option(10, 3) +
                    " --rmw fastdds --processes per-node --domain " + domain() +
                    " --quiet --output " + out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("functional: outputs not checked"), std::string::npos) << o.out;
  j = result_json();
  EXPECT_EQ(j["counts"]["matched"], 30);
  EXPECT_EQ(j["validity"]["valid"], true) << j["validity"].dump();
  EXPECT_TRUE(j["functional"].is_null()) << j["functional"].dump();
  ASSERT_EQ(j["nodes"].size(), 1u);
  EXPECT_EQ(j["nodes"][0]["counters"]["sets_processed"], 35);
}

TEST_F(Cli, BadDatasetOptionsAreOneClearLine) {
  const std::string bag = (out_ / "camera").string();
  ASSERT_EQ(robotperf_cli("dataset generate perception/image --out " + bag).exit_code, 0);
  for (const std::string& args :
       std::vector<std::string>{"run a1 --dataset " + bag + " --remap /nope:=/camera/image_raw",
                                "run a1 --dataset " + bag + " --remap nonsense",
                                "run a1 --dataset " + bag + " --window 5:x",
                                "run a1 --dataset " + bag + " --window 100:200",
                                "run a1 --rate bag", "run a1 --dataset " + bag + " --rate-scale 2",
                                "run a1 --dataset " + (out_ / "missing").string()}) {
    const Outcome o = robotperf_cli(args);
    EXPECT_EQ(o.exit_code, 2) << args << ": " << o.out;
    EXPECT_EQ(std::count(o.out.begin(), o.out.end(), '\n'), 1) << args << ": " << o.out;
  }
}

// A starved Playback sends its late commands in a burst; those arriving within one loop period
// replace each other in the controller's one-slot command buffer before the loop takes one, as in
// ros2_control, and are never actuated: lost in a state stream. Only a burst excuses losses.
bool playback_burst(const nlohmann::json& result, const nlohmann::json& loop) {
  const double period_ms = 1e3 / loop["update_rate_hz"].get<double>();
  return result["latency_ms"]["send_lateness"]["max"].get<double>() > 0.5 * period_ms;
}

// c1-c5 end to end, kept short: state outputs matched by ID, loop metrics in the results and the
// functional checks of c1 and c2 passing. Short runs have fewer samples than the packages
// require, so the only reason for invalidity allowed is that.
TEST_F(Cli, RunControlBenchmarksC1ToC5) {
  const std::pair<const char*, const char*> runs[] = {{"c1", "--count 2 --warmup 0"},
                                                      {"c2", "--count 25 --warmup 2"},
                                                      {"c3", "--count 120 --warmup 10"},
                                                      {"c4", "--count 120 --warmup 10"},
                                                      {"c5", "--count 120 --warmup 10"}};
  for (const auto& [id, args] : runs) {
    fs::remove_all(out_);
    const Outcome o =
        robotperf_cli(std::string("run ") + id + " " + args + " --quiet --output " + out_.string());
    EXPECT_NE(o.out.find("control loop controller_manager"), std::string::npos) << o.out;
    const nlohmann::json j = result_json();
    ASSERT_TRUE(j.is_object()) << o.out;
    EXPECT_EQ(j["counts"]["duplicates"], 0) << id;
    EXPECT_EQ(j["counts"]["unknown"], 0) << id;
    EXPECT_GT(j["counts"]["repeats"].get<int>(), 0) << id;
    ASSERT_EQ(j["control_loops"].size(), 1u) << id;
    const auto& loop = j["control_loops"][0];
    if (!playback_burst(j, loop)) {
      EXPECT_EQ(j["counts"]["lost"], 0) << id << "\n" << o.out;
      for (const auto& reason : j["validity"]["reasons"])
        EXPECT_NE(reason.get<std::string>().find("fewer than"), std::string::npos) << reason;
    }
    EXPECT_GT(loop["cycles"].get<int>(), 0);
    EXPECT_TRUE(loop["deadline_misses"].is_number());
    EXPECT_GT(loop["update_duration_us"]["count"].get<int>(), 0);
    EXPECT_TRUE(loop["period_jitter_us"]["p99"].is_number());
    // Each command is written to the hardware before the state reflecting it is received, so
    // the earliest write precedes the earliest state and the latest write the latest state
    // (comparing one message's write with another's state would not hold under load).
    const auto& to_write = loop["command_to_write_ms"];
    const auto& to_state = j["latency_ms"]["from_scheduled"];
    EXPECT_LT(to_write["min"].get<double>(), to_state["min"].get<double>()) << id;
    EXPECT_LT(to_write["max"].get<double>(), to_state["max"].get<double>()) << id;
    if (std::string(id) == "c1" || std::string(id) == "c2") {
      ASSERT_TRUE(j["functional"].is_object()) << id;
      EXPECT_EQ(j["functional"]["valid"], true) << j["functional"].dump();
    }
  }
}

// Per-node: the loop runs in the controller's own process, which sends its metrics (and the raw
// command writes) back to the runner; the command -> write latency is computed there.
TEST_F(Cli, RunC3OneProcessPerNodeReportsItsLoop) {
  const Outcome o = robotperf_cli(
      "run c3 --count 120 --warmup 10 --rmw fastdds --processes per-node "
      "--quiet --domain " +
      domain() + " --output " + out_.string());
  EXPECT_NE(o.out.find("control loop controller_manager"), std::string::npos) << o.out;
  const auto j = result_json();
  ASSERT_TRUE(j.is_object()) << o.out;
  EXPECT_EQ(j["configuration"]["processes"], "per-node");
  ASSERT_EQ(j["nodes"].size(), 1u);
  EXPECT_EQ(j["nodes"][0]["exit_status"], "ok") << j["nodes"][0].dump();
  ASSERT_EQ(j["control_loops"].size(), 1u) << o.out;
  const auto& loop = j["control_loops"][0];
  if (!playback_burst(j, loop)) {
    EXPECT_EQ(j["counts"]["lost"], 0) << o.out;
  }
  EXPECT_EQ(loop["node"], "controller_manager");
  EXPECT_EQ(loop["update_rate_hz"].get<double>(), 100.0);
  // 120 commands at 100 Hz take more than a second: over a hundred cycles.
  EXPECT_GT(loop["cycles"].get<int>(), 100);
  EXPECT_EQ(loop["recorded_cycles"], loop["cycles"]);
  EXPECT_GT(loop["update_duration_us"]["count"].get<int>(), 100);
  EXPECT_GT(loop["wake_latency_us"]["min"].get<double>(), 0.0);
  // Every measured command observed in a state was written to the hardware before.
  const auto& to_write = loop["command_to_write_ms"];
  EXPECT_GE(to_write["count"].get<int>(), j["counts"]["matched"].get<int>()) << to_write.dump();
  EXPECT_LE(to_write["count"].get<int>(), 110) << to_write.dump();
  EXPECT_LT(to_write["min"].get<double>(), j["latency_ms"]["from_scheduled"]["min"].get<double>());
  EXPECT_LT(to_write["max"].get<double>(), j["latency_ms"]["from_scheduled"]["max"].get<double>());
}

// --update-rate runs the controller manager's loop faster than the graph says, and is recorded.
TEST_F(Cli, UpdateRateOverridesTheControlLoopRate) {
  const Outcome o = robotperf_cli(
      "run c3 --rate 100 --update-rate 1000 --count 100 --warmup 10 "
      "--quiet --output " +
      out_.string());
  const auto j = result_json();
  ASSERT_TRUE(j.is_object()) << o.out;
  EXPECT_EQ(j["configuration"]["update_rate_hz"].get<double>(), 1000.0);
  ASSERT_EQ(j["control_loops"].size(), 1u);
  const auto& loop = j["control_loops"][0];
  EXPECT_EQ(loop["update_rate_hz"].get<double>(), 1000.0);
  // About a second of commands: far more cycles than the 100 Hz loop of the graph would run.
  EXPECT_GT(loop["cycles"].get<int>(), 500) << loop.dump();

  for (const std::string args :
       {"run c3 --update-rate 0", "run c3 --update-rate -100", "run c3 --update-rate inf",
        "run c3 --update-rate fast", "run a1 --update-rate 1000"}) {
    const Outcome bad =
        robotperf_cli(args + " --count 20 --quiet --output " + (out_ / "bad").string());
    EXPECT_EQ(bad.exit_code, 2) << args << ": " << bad.out;
    EXPECT_EQ(std::count(bad.out.begin(), bad.out.end(), '\n'), 1) << args << ": " << bad.out;
    EXPECT_NE(bad.out.find("--update-rate"), std::string::npos) << args << ": " << bad.out;
  }
}

// --backend opencl runs a1's rectify and resize on the OpenCL device (pocl's CPU device where
// there is no GPU), records the backend and the device per node, and its answer passes a1's
// functional checks; a backend no kernel has, or one without its device, is one line and exit 2.
TEST_F(Cli, BackendRunsTheKernelsThatHaveItAndRecordsTheDevice) {
  for (const std::string args : {"run a1 --backend vulkan", "run b3 --backend opencl"}) {
    const Outcome bad =
        robotperf_cli(args + " --count 20 --quiet --output " + (out_ / "bad").string());
    EXPECT_EQ(bad.exit_code, 2) << args << ": " << bad.out;
    EXPECT_EQ(std::count(bad.out.begin(), bad.out.end(), '\n'), 1) << args << ": " << bad.out;
    EXPECT_NE(bad.out.find("--backend"), std::string::npos) << args << ": " << bad.out;
  }
  // An ICD loader that finds no driver: what to install, in one line.
  const fs::path no_drivers = out_ / "no-opencl-drivers";
  fs::create_directories(no_drivers);
  const Outcome missing = robotperf_cli(
      "run a5 --backend opencl --count 20 --quiet --output " + (out_ / "bad").string(),
      "OCL_ICD_VENDORS=" + no_drivers.string());
  EXPECT_EQ(missing.exit_code, 2) << missing.out;
  EXPECT_EQ(std::count(missing.out.begin(), missing.out.end(), '\n'), 1) << missing.out;
  EXPECT_NE(missing.out.find("pocl-opencl-icd"), std::string::npos) << missing.out;
  EXPECT_TRUE(!fs::exists(out_ / "bad") || fs::is_empty(out_ / "bad"))
      << "nothing written for a run that could not start";

  const Outcome probe = robotperf_cli("sysinfo");
  ASSERT_EQ(probe.exit_code, 0) << probe.out;
  if (nlohmann::json::parse(probe.out)["opencl_devices"].empty())
    GTEST_SKIP() << "no OpenCL device on this machine (Debian: pocl-opencl-icd)";
  // At 10 Hz: pocl's CPU device takes about 21 ms a frame for a1, too close to 30 Hz's period
  // with the other core busy (a test beside this one).
  const Outcome o =
      robotperf_cli("run a1 --backend opencl --rate 10 --count 40 --output " + out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("backends: rectify opencl ("), std::string::npos) << o.out;
  const auto j = result_json();
  ASSERT_TRUE(j.is_object()) << o.out;
  ASSERT_EQ(j["nodes"].size(), 2u);
  for (const auto& node : j["nodes"]) {
    EXPECT_EQ(node["backend"], "opencl") << node.dump();
    EXPECT_FALSE(node["device"]["name"].get<std::string>().empty()) << node.dump();
    EXPECT_GT(node["device"]["memory_bytes"].get<uint64_t>(), 0u) << node.dump();
  }
  EXPECT_EQ(j["validity"]["valid"], true) << o.out;
  // The sampled answers agree with the cpu nodes' answers to the same frames.
  EXPECT_EQ(j["backend_check"]["passed"], true) << j["backend_check"].dump();
  EXPECT_EQ(j["backend_check"]["compared"], 16) << j["backend_check"].dump();
  EXPECT_GE(j["backend_check"]["agreement"].get<double>(), 0.999) << j["backend_check"].dump();

  // Every perception benchmark with a kernel on the device gives the cpu's answers. a3 at 1 Hz:
  // its block matcher takes 150-600 ms a pair on a CPU device with the other core busy, so its
  // 12 messages are too few for a valid run (exit 3), and the answers are what is checked.
  for (const std::string run : {"a2 --rate 10 --count 35", "a3 --rate 1 --count 12 --warmup 2",
                                "a4 --rate 10 --count 35", "a5 --rate 10 --count 35"}) {
    const bool few = run.starts_with("a3");
    const fs::path dir = out_ / ("each-" + run.substr(0, 2));
    const Outcome each =
        robotperf_cli("run " + run + " --backend opencl --quiet --output " + dir.string());
    ASSERT_EQ(each.exit_code, few ? 3 : 0) << run << ": " << each.out;
    std::ifstream in(only_result_in(dir));
    const auto r = nlohmann::json::parse(in);
    EXPECT_EQ(r["backend_check"]["passed"], true) << run << ": " << r["backend_check"].dump();
    EXPECT_GT(r["backend_check"]["compared"].get<int>(), 0) << run;
    if (few) {
      EXPECT_EQ(r["functional"]["valid"], true) << run << ": " << r["functional"].dump();
      EXPECT_EQ(r["counts"]["lost"], 0) << run << ": " << each.out;
    }
  }

  // a3 with its own warm-up of 5 at 3 Hz: pocl builds the block matcher at the first pair, the
  // warm-up is repeated meanwhile, and the disparity node's exact-time pairing drops the
  // repeats (stamps older than its last set). Its falling silent is the device being ready, not
  // a device that never answers (exit 2 after --connect-timeout); measured, pocl cannot keep up
  // with 3 Hz (exit 3).
  const Outcome warm = robotperf_cli(
      "run a3 --backend opencl --rate 3 --count 10 --quiet "
      "--connect-timeout 60 --output " +
      (out_ / "warm-a3").string());
  EXPECT_EQ(warm.exit_code, 3) << warm.out;
  EXPECT_EQ(warm.out.find("answered none"), std::string::npos) << warm.out;

  // Per-node children build their node on the backend too, and report their device.
  const fs::path per_node = out_ / "per-node";
  const Outcome p = robotperf_cli(
      "run a1 --backend opencl --processes per-node --rate 10 --count 40 "
      "--quiet --domain " +
      domain() + " --output " + per_node.string());
  ASSERT_EQ(p.exit_code, 0) << p.out;
  std::ifstream in(only_result_in(per_node));
  const auto children = nlohmann::json::parse(in);
  for (const auto& node : children["nodes"]) {
    EXPECT_GT(node.value("pid", 0), 0) << node.dump();
    EXPECT_EQ(node["backend"], "opencl") << node.dump();
    EXPECT_FALSE(node["device"]["name"].get<std::string>().empty()) << node.dump();
  }
}

TEST_F(Cli, CudaBackendIsOneLineWithoutItsBuildOrDeviceAndRunsWithOne) {
  // The kernels name cuda only in a build with the CUDA toolkit.
  const Outcome kernels = robotperf_cli("list kernels");
  ASSERT_EQ(kernels.exit_code, 0) << kernels.out;
  const bool built = kernels.out.find("backends: cpu, opencl, cuda)") != std::string::npos;
  const Outcome probe = robotperf_cli("sysinfo");
  ASSERT_EQ(probe.exit_code, 0) << probe.out;
  const auto devices = nlohmann::json::parse(probe.out)["cuda_devices"];
  ASSERT_TRUE(devices.is_array()) << probe.out;
  if (!built) {
    EXPECT_TRUE(devices.empty()) << devices.dump();
  }

  // Without the build, or in it without a device (CUDA_VISIBLE_DEVICES=-1 hides any GPU from
  // CUDA): one line saying what is missing, exit 2, nothing written.
  for (const std::string args : {"run a5", "run a3"}) {
    const Outcome refused = robotperf_cli(
        args + " --backend cuda --count 20 --quiet --output " + (out_ / "bad").string(),
        built ? "CUDA_VISIBLE_DEVICES=-1" : "");
    EXPECT_EQ(refused.exit_code, 2) << args << ": " << refused.out;
    EXPECT_EQ(std::count(refused.out.begin(), refused.out.end(), '\n'), 1) << refused.out;
    EXPECT_NE(refused.out.find(built ? "no CUDA device" : "install-deps.sh --cuda"),
              std::string::npos)
        << refused.out;
  }
  EXPECT_TRUE(!fs::exists(out_ / "bad") || fs::is_empty(out_ / "bad"))
      << "nothing written for a run that could not start";

  if (devices.empty())
    GTEST_SKIP() << "no CUDA device on this machine (built with CUDA: " << built << ")";
  const Outcome o = robotperf_cli("run a1 --backend cuda --count 40 --output " + out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("backends: rectify cuda ("), std::string::npos) << o.out;
  const auto j = result_json();
  ASSERT_TRUE(j.is_object()) << o.out;
  for (const auto& node : j["nodes"]) {
    EXPECT_EQ(node["backend"], "cuda") << node.dump();
    EXPECT_EQ(node["device"]["vendor"], "NVIDIA") << node.dump();
    EXPECT_GT(node["device"]["memory_bytes"].get<uint64_t>(), 0u) << node.dump();
  }
  EXPECT_EQ(j["validity"]["valid"], true) << o.out;
  EXPECT_EQ(j["backend_check"]["passed"], true) << j["backend_check"].dump();

  // Every perception benchmark's kernels on the GPU give the cpu's answers, in one process and
  // in per-node children.
  for (const std::string run : {"a2", "a3", "a4", "a5", "a1 --processes per-node"}) {
    const fs::path dir = out_ / ("each-" + run.substr(0, 2) + std::to_string(run.size()));
    const Outcome each =
        robotperf_cli("run " + run + " --backend cuda --count 35 --quiet --domain " + domain() +
                      " --output " + dir.string());
    EXPECT_EQ(each.exit_code, 0) << run << ": " << each.out;
    std::ifstream in(only_result_in(dir));
    const auto r = nlohmann::json::parse(in);
    EXPECT_EQ(r["backend_check"]["passed"], true) << run << ": " << r["backend_check"].dump();
    EXPECT_GT(r["backend_check"]["compared"].get<int>(), 0) << run;
    for (const auto& node : r["nodes"]) {
      EXPECT_EQ(node["backend"], "cuda") << run << node.dump();
    }
  }
}

// A copy of control benchmark `package` under out_ as c9 (benchmark folders add to the built-in
// ones: the copy needs an id of its own), its graph.yaml's `from` replaced by `to`; returns the
// --benchmarks option that finds it.
std::string control_copy_as_c9(const fs::path& out, const std::string& package,
                               const std::string& from, const std::string& to) {
  const fs::path src = fs::path(ROBOTPERF_SOURCE_DIR) / "benchmarks" / "control" / package;
  const fs::path copy = out / "control" / "c9_copy";
  fs::create_directories(copy);
  std::ifstream meta_in(src / "benchmark.yaml");
  std::string meta((std::istreambuf_iterator<char>(meta_in)), std::istreambuf_iterator<char>());
  const auto id = meta.find("id: c");
  EXPECT_NE(id, std::string::npos);
  meta.replace(id, 6, "id: c9");
  std::ofstream(copy / "benchmark.yaml") << meta;
  std::ifstream in(src / "graph.yaml");
  std::string graph((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(graph.find(from), std::string::npos) << from;
  graph.replace(graph.find(from), from.size(), to);
  std::ofstream(copy / "graph.yaml") << graph;
  return "--benchmarks " + out.string();
}

TEST_F(Cli, ControlLoopCpuThatCannotBeHadIsOneClearLine) {
  // No machine here has CPU 1000: pinning the loop thread there fails before the run.
  const std::string benchmarks = control_copy_as_c9(
      out_, "c3_rrbot_forward_command_controller_position", "cpu: -1", "cpu: 1000");
  const Outcome o = robotperf_cli(benchmarks + " run c9 --count 20 --warmup 2 --quiet --output " +
                                  (out_ / "r").string());
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_NE(o.out.find("cannot pin the control loop to CPU 1000"), std::string::npos) << o.out;
}

// Closed-loop odometry (open_loop: false, ros2_controllers' default) is of the wheel positions
// read at the start of a cycle; checked against the true pose of that instant, c2 passes as with
// open-loop odometry (against the pose after the cycle's write it was off by one cycle's motion).
TEST_F(Cli, C2ClosedLoopOdometryMatchesTheTruePose) {
  const std::string benchmarks = control_copy_as_c9(out_, "c2_diffbot_diff_driver_controller",
                                                    "open_loop: true", "open_loop: false");
  const Outcome o = robotperf_cli(benchmarks + " run c9 --count 25 --warmup 2 --quiet --output " +
                                  (out_ / "r").string());
  std::vector<fs::path> results;
  for (const auto& e : fs::directory_iterator(out_ / "r"))
    if (e.path().extension() == ".json") results.push_back(e.path());
  ASSERT_EQ(results.size(), 1u) << o.out;
  std::ifstream in(results[0]);
  const auto j = nlohmann::json::parse(in);
  ASSERT_TRUE(j["functional"].is_object()) << o.out;
  EXPECT_EQ(j["functional"]["valid"], true) << j["functional"].dump();
}
