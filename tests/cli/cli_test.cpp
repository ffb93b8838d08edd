// robotperf end to end, as a user runs it.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace {

namespace fs = std::filesystem;

struct Outcome {
  int exit_code = -1;
  std::string out;  // stdout and stderr together
};

Outcome robotperf(const std::string& args) {
  const std::string cmd = std::string(ROBOTPERF_EXECUTABLE) + " " + args + " 2>&1";
  Outcome o;
  FILE* p = popen(cmd.c_str(), "r");
  if (p == nullptr) return o;
  std::array<char, 4096> buf;
  while (std::size_t n = fread(buf.data(), 1, buf.size(), p)) o.out.append(buf.data(), n);
  const int status = pclose(p);
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return o;
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    out_ = fs::temp_directory_path() /
           ("robotperf-cli-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(out_);
  }
  void TearDown() override { fs::remove_all(out_); }

  // The single results JSON the run wrote.
  nlohmann::json result_json() {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(out_)) {
      if (e.path().extension() == ".json") files.push_back(e.path());
    }
    EXPECT_EQ(files.size(), 1u);
    if (files.empty()) return {};
    std::ifstream in(files[0]);
    return nlohmann::json::parse(in);
  }
  std::string domain() const { return std::to_string(150 + getpid() % 80); }

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
  const Outcome list = robotperf("list");
  EXPECT_EQ(list.exit_code, 0);
  for (const char* id : {"a1_perception_2nodes", "a2_rectify", "a5_resize"}) {
    EXPECT_NE(list.out.find(id), std::string::npos) << list.out;
  }
  const Outcome d = robotperf("describe a1");
  EXPECT_EQ(d.exit_code, 0);
  EXPECT_NE(d.out.find("image_proc/rectify"), std::string::npos);
  EXPECT_NE(d.out.find("/resize/image"), std::string::npos);
}

TEST_F(Cli, RunA1OnIntra) {
  const Outcome o = robotperf("run a1 --count 60 --rmw intra --csv --output " + out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("result: VALID"), std::string::npos) << o.out;
  expect_clean_a1_result(result_json(), "intra");
  bool csv = false;
  for (const auto& e : fs::directory_iterator(out_))
    csv |= e.path().string().ends_with(".latencies.csv");
  EXPECT_TRUE(csv);
}

TEST_F(Cli, RunA1OnFastDds) {
  const Outcome o = robotperf("run a1 --count 60 --rmw fastdds --domain " + domain() +
                              " --output " + out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  expect_clean_a1_result(result_json(), "fastdds");
}

TEST_F(Cli, RunA1OneProcessPerNode) {
  // At 5 Hz even a loaded 2-core machine moves 1.2 MB frames between processes in time.
  const Outcome o =
      robotperf("run a1 --count 60 --rate 10 --rmw fastdds --processes per-node --domain " +
                domain() + " --output " + out_.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const auto j = result_json();
  expect_clean_a1_result(j, "fastdds");
  EXPECT_EQ(j["configuration"]["processes"], "per-node");
  ASSERT_EQ(j["nodes"].size(), 2u);
  for (const auto& n : j["nodes"]) {
    EXPECT_EQ(n["exit_status"], "ok") << n.dump();
    EXPECT_GT(n["pid"].get<int>(), 0);
  }
}

TEST_F(Cli, UnknownBenchmarkIsOneClearLine) {
  const Outcome o = robotperf("run z9 --output " + out_.string());
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_EQ(std::count(o.out.begin(), o.out.end(), '\n'), 1) << o.out;
  EXPECT_NE(o.out.find("unknown benchmark 'z9'"), std::string::npos) << o.out;
  EXPECT_FALSE(fs::exists(out_) && !fs::is_empty(out_));
}

TEST_F(Cli, BadOptionIsOneClearLine) {
  for (const char* args :
       {"run a1 --rate fast", "run a1 --rmw zenoh", "run a1 --count 5 --duration 2", "fly a1"}) {
    const Outcome o = robotperf(args);
    EXPECT_EQ(o.exit_code, 2) << args << "\n" << o.out;
    EXPECT_EQ(std::count(o.out.begin(), o.out.end(), '\n'), 1) << args << "\n" << o.out;
  }
}

TEST_F(Cli, WarmupNotBelowCountIsRefused) {
  const Outcome o = robotperf("run a2 --count 5 --warmup 5 --output " + out_.string());
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.out.find("warm-up"), std::string::npos) << o.out;
}

}  // namespace

namespace {

const std::string kSharedBags = std::string(ROBOTPERF_SHARED_DATA_DIR) + "/rosbag2/";

TEST_F(Cli, BagInfoLikeRos2BagInfo) {
  const Outcome o = robotperf("bag info " + kSharedBags + "sqlite3_cdr_test");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("Storage id:        sqlite3"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("Messages:          7"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("/array_topic         4 msgs  test_msgs/msg/Arrays"), std::string::npos)
      << o.out;
  EXPECT_NE(o.out.find("QoS: reliable, transient_local"), std::string::npos) << o.out;
}

TEST_F(Cli, BagEchoAndConvert) {
  Outcome o = robotperf("bag echo " + kSharedBags + "mcap_talker --topic /topic --limit 4");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("--- /topic [std_msgs/msg/String] at 1585866236.613084249\n"
                       "data: 'Hello, world! 3'\n"),
            std::string::npos)
      << o.out;
  EXPECT_EQ(o.out.find("Hello, world! 4"), std::string::npos) << "--limit 4 printed more";

  o = robotperf("bag convert " + kSharedBags + "mcap_talker " + (out_ / "db").string() +
                " --storage sqlite3");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  // sqlite3 schema 3 (Humble) has no place for definitions: they come from .msg files.
  o = robotperf("bag echo " + (out_ / "db").string() + " --topic /topic");
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_NE(o.out.find("no definition of std_msgs/msg/String"), std::string::npos) << o.out;
  o = robotperf("bag echo " + (out_ / "db").string() + " --topic /topic --msg-dir " +
                ROBOTPERF_SHARED_DATA_DIR + "/msg");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("data: 'Hello, world! 9'"), std::string::npos) << o.out;
}

TEST_F(Cli, DatasetGenerateWritesARealBag) {
  const std::string bag = (out_ / "image").string();
  Outcome o = robotperf("dataset generate perception/image --out " + bag);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  o = robotperf("bag info " + bag);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("Storage id:        mcap"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("/camera/image_raw          68 msgs  sensor_msgs/msg/Image"),
            std::string::npos)
      << o.out;
  EXPECT_NE(o.out.find("/camera/camera_info        68 msgs  sensor_msgs/msg/CameraInfo"),
            std::string::npos)
      << o.out;
  // The bag carries the definitions, so any reader can decode it.
  o = robotperf("bag echo " + bag + " --topic /camera/image_raw --limit 1");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("encoding: 'rgb8'"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("data: '<921600 bytes>'"), std::string::npos) << o.out;
}

TEST_F(Cli, BadBagIsOneClearLine) {
  fs::create_directories(out_);
  for (const std::string& args : std::vector<std::string>{
           "bag info " + out_.string(), "bag echo " + (out_ / "missing").string(),
           "dataset generate no/such",
           "bag convert " + kSharedBags + "mcap_talker " + (out_ / "x").string() +
               " --compression brotli"}) {
    const Outcome o = robotperf(args);
    EXPECT_EQ(o.exit_code, 2) << args << ": " << o.out;
    EXPECT_EQ(std::count(o.out.begin(), o.out.end(), '\n'), 1) << args << ": " << o.out;
  }
}

}  // namespace

TEST_F(Cli, RunReplaysABagOnItsOwnTimeline) {
  const std::string bag = (out_ / "camera").string();
  Outcome o = robotperf("dataset generate perception/image --out " + bag);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  o = robotperf("run a1 --dataset " + bag + " --rate bag --rate-scale 2 --count 60 --output " +
                out_.string() + " --quiet");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const auto j = result_json();
  expect_clean_a1_result(j, "intra");
  EXPECT_EQ(j["dataset"]["name"], bag);
  // 30 Hz recorded, played twice as fast.
  EXPECT_NEAR(j["configuration"]["rate_hz"].get<double>(), 60.0, 0.1);
}

TEST_F(Cli, BadDatasetOptionsAreOneClearLine) {
  const std::string bag = (out_ / "camera").string();
  ASSERT_EQ(robotperf("dataset generate perception/image --out " + bag).exit_code, 0);
  for (const std::string& args :
       std::vector<std::string>{"run a1 --dataset " + bag + " --remap /nope:=/camera/image_raw",
                                "run a1 --dataset " + bag + " --remap nonsense",
                                "run a1 --dataset " + bag + " --window 5:x",
                                "run a1 --dataset " + bag + " --window 100:200",
                                "run a1 --rate bag", "run a1 --dataset " + bag + " --rate-scale 2",
                                "run a1 --dataset " + (out_ / "missing").string()}) {
    const Outcome o = robotperf(args);
    EXPECT_EQ(o.exit_code, 2) << args << ": " << o.out;
    EXPECT_EQ(std::count(o.out.begin(), o.out.end(), '\n'), 1) << args << ": " << o.out;
  }
}
