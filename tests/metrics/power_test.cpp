// Power sources against fixture sysfs trees that reproduce each layout, a fake NVML library
// loaded through the real dlopen path, an external meter command, and this machine.
#include "robotperf/metrics/power.hpp"

#include <dlfcn.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "../fixture_root.hpp"

namespace robotperf::metrics {
namespace {

namespace fs = std::filesystem;

constexpr int64_t kSecond = 1'000'000'000;

using robotperf::testing::FixtureRoot;

PowerOptions options_for(const FixtureRoot& root, std::set<std::string> types) {
  PowerOptions o;
  o.sysfs_root = root.path();
  o.types = std::move(types);
  return o;
}

const SourceEnergy& source(const PowerReport& report, const std::string& name) {
  for (const auto& s : report.sources) {
    if (s.info.name == name) return s;
  }
  throw std::runtime_error("no source " + name);
}

// Two packages, core and DRAM subzones, and an MMIO duplicate of package 0 that must be ignored.
// Package 1's counter wraps between the first and the second reading.
constexpr uint64_t kRange = 262143328850;  // max_energy_range_uj of many Intel packages
void write_rapl(const FixtureRoot& root, uint64_t package0, uint64_t core0, uint64_t dram0,
                uint64_t package1) {
  const std::string pc = "sys/class/powercap/";
  root.write(pc + "intel-rapl/enabled", "1\n");  // the control type: no energy_uj
  root.write(pc + "intel-rapl:0/name", "package-0\n");
  root.write(pc + "intel-rapl:0/energy_uj", std::to_string(package0) + "\n");
  root.write(pc + "intel-rapl:0/max_energy_range_uj", std::to_string(kRange) + "\n");
  root.write(pc + "intel-rapl:0:0/name", "core\n");
  root.write(pc + "intel-rapl:0:0/energy_uj", std::to_string(core0) + "\n");
  root.write(pc + "intel-rapl:0:0/max_energy_range_uj", std::to_string(kRange) + "\n");
  root.write(pc + "intel-rapl:0:2/name", "dram\n");
  root.write(pc + "intel-rapl:0:2/energy_uj", std::to_string(dram0) + "\n");
  root.write(pc + "intel-rapl:0:2/max_energy_range_uj", "65532610987\n");
  root.write(pc + "intel-rapl:1/name", "package-1\n");
  root.write(pc + "intel-rapl:1/energy_uj", std::to_string(package1) + "\n");
  root.write(pc + "intel-rapl:1/max_energy_range_uj", std::to_string(kRange) + "\n");
  root.write(pc + "intel-rapl-mmio:0/name", "package-0\n");
  root.write(pc + "intel-rapl-mmio:0/energy_uj", "999\n");
}

TEST(Rapl, TwoPackagesOneWrappingGiveExactEnergyAndPower) {
  FixtureRoot root;
  write_rapl(root, 1'000'000, 500'000, 100, kRange - 2'000'000);
  auto found = discover_power_sources(options_for(root, {"rapl"}));
  ASSERT_EQ(found.sources.size(), 4u);
  PowerMeter meter(std::move(found.sources), found.notes);
  const auto& infos = meter.sources();
  EXPECT_EQ(infos[0]->info().name, "rapl:package-0");
  EXPECT_EQ(infos[1]->info().name, "rapl:package-0/core");
  EXPECT_EQ(infos[2]->info().name, "rapl:package-0/dram");
  EXPECT_EQ(infos[3]->info().name, "rapl:package-1");
  EXPECT_TRUE(infos[0]->info().in_total);
  EXPECT_FALSE(infos[1]->info().in_total);  // inside package-0
  EXPECT_TRUE(infos[2]->info().in_total);
  EXPECT_DOUBLE_EQ(infos[3]->info().wrap_j, kRange * 1e-6);

  meter.sample_round(10 * kSecond);
  write_rapl(root, 3'000'000, 1'500'000, 500'100, 1'000'000);  // package-1 wrapped: +3 J
  meter.sample_round(11 * kSecond);
  write_rapl(root, 5'000'000, 2'500'000, 1'000'100, 4'000'000);
  meter.sample_round(12 * kSecond);

  const PowerReport r = meter.report();
  ASSERT_TRUE(r.available) << r.unavailable_reason;
  EXPECT_NEAR(source(r, "rapl:package-0").energy_j, 4.0, 1e-9);
  EXPECT_NEAR(source(r, "rapl:package-0").average_w, 2.0, 1e-9);
  EXPECT_NEAR(source(r, "rapl:package-0/core").energy_j, 2.0, 1e-9);
  EXPECT_NEAR(source(r, "rapl:package-0/dram").average_w, 0.5, 1e-9);
  EXPECT_NEAR(source(r, "rapl:package-1").energy_j, 6.0, 1e-6);
  EXPECT_NEAR(source(r, "rapl:package-1").average_w, 3.0, 1e-6);
  EXPECT_EQ(source(r, "rapl:package-1").wraps, 1u);
  EXPECT_EQ(source(r, "rapl:package-0").wraps, 0u);
  // Total: packages and DRAM, not the core (already inside package 0).
  EXPECT_NEAR(r.total_energy_j, 4.0 + 1.0 + 6.0, 1e-6);
  EXPECT_NEAR(r.total_average_w, 5.5, 1e-6);
  EXPECT_NEAR(r.window_s, 2.0, 1e-12);

  const auto j = to_json(r, 110, 55.0);
  EXPECT_EQ(j["available"], true);
  EXPECT_TRUE(j["unavailable_reason"].is_null());
  EXPECT_NEAR(j["total"]["energy_per_message_mj"].get<double>(), 11.0 * 1e3 / 110, 1e-6);
  EXPECT_NEAR(j["total"]["throughput_per_watt"].get<double>(), 55.0 / 5.5, 1e-6);
  EXPECT_EQ(j["total"]["sources"].size(), 3u);
}

TEST(Rapl, RootOnlyCounterIsUnavailableWithTheReason) {
  if (::geteuid() == 0) GTEST_SKIP() << "root reads files whatever their mode";
  FixtureRoot root;
  write_rapl(root, 1, 1, 1, 1);
  for (const char* zone : {"intel-rapl:0", "intel-rapl:0:0", "intel-rapl:0:2", "intel-rapl:1"}) {
    fs::permissions(root.path() / "sys/class/powercap" / zone / "energy_uj", fs::perms::none);
  }
  const auto found = discover_power_sources(options_for(root, {"rapl"}));
  EXPECT_TRUE(found.sources.empty());
  ASSERT_EQ(found.notes.size(), 1u);
  EXPECT_NE(found.notes[0].find("readable by root only"), std::string::npos) << found.notes[0];
}

TEST(Rapl, CounterGoingBackWithoutWrapRangeIsUnavailable) {
  PowerSourceInfo info;
  info.name = "x";
  info.kind = PowerSourceKind::kEnergyCounter;
  EnergyIntegrator integrator(info);
  integrator.add(0, 10.0);
  integrator.add(kSecond, 5.0);
  const auto r = integrator.result();
  EXPECT_FALSE(r.available);
  EXPECT_NE(r.unavailable_reason.find("went backwards"), std::string::npos);
}

TEST(EnergyIntegrator, ReadingsThatAreNotPhysicalAreFailedReadings) {
  PowerSourceInfo gauge;
  gauge.name = "g";
  EnergyIntegrator g(gauge);
  g.add(0, 10.0);
  g.add(kSecond / 2, std::nan(""));
  g.add(kSecond, 1e9);  // a gigawatt
  g.add(2 * kSecond, 10.0);
  auto r = g.result();
  EXPECT_EQ(r.readings, 2u);
  EXPECT_EQ(r.failed_readings, 2u);
  EXPECT_NE(r.first_error.find("not physical"), std::string::npos) << r.first_error;
  EXPECT_NEAR(r.energy_j, 20.0, 1e-9);  // 10 W over the 2 s between the good readings

  PowerSourceInfo counter;
  counter.name = "c";
  counter.kind = PowerSourceKind::kEnergyCounter;
  EnergyIntegrator c(counter);
  c.add(0, 100.0);
  c.add(kSecond, 1e12);  // a terajoule in a second
  c.add(2 * kSecond, 140.0);
  r = c.result();
  EXPECT_EQ(r.failed_readings, 1u);
  EXPECT_NE(r.first_error.find("more than 100000 W"), std::string::npos) << r.first_error;
  EXPECT_NEAR(r.energy_j, 40.0, 1e-9);
}

// A gauge that fails its first `failing` readings, then reads `watts`.
class LateGauge : public PowerSource {
 public:
  LateGauge(std::string name, int failing, double watts)
      : PowerSource({std::move(name), "hwmon", "fixture", "", PowerSourceKind::kPowerGauge}),
        failing_(failing),
        watts_(watts) {}
  std::optional<double> read(std::string& error) override {
    if (failing_-- > 0) {
      error = "EIO";
      return std::nullopt;
    }
    return watts_;
  }

 private:
  int failing_;
  double watts_;
};

// A source read for part of the window stands for the whole window at its average, and the total
// says which source that is: energy per message is over the window the messages were counted in.
TEST(PowerMeter, ASourceReadForPartOfTheWindowIsScaledToItAndNamed) {
  std::vector<std::unique_ptr<PowerSource>> sources;
  sources.push_back(std::make_unique<LateGauge>("cpu", 0, 50.0));
  sources.push_back(std::make_unique<LateGauge>("gpu", 6, 100.0));
  PowerMeter meter(std::move(sources), {});
  for (int i = 0; i <= 10; ++i) meter.sample_round(i * kSecond / 10);
  const PowerReport r = meter.report();
  ASSERT_TRUE(r.available);
  EXPECT_NEAR(r.window_s, 1.0, 1e-12);
  EXPECT_NEAR(source(r, "gpu").span_s, 0.4, 1e-12);
  EXPECT_NEAR(r.total_average_w, 150.0, 1e-9);
  EXPECT_NEAR(r.total_energy_j, 150.0, 1e-9);  // not 50 J + 40 J
  ASSERT_EQ(r.estimated.size(), 1u);
  EXPECT_EQ(r.estimated[0],
            "gpu read for 0.400 s of the 1.000 s window (its average taken for the rest)");
  const auto j = to_json(r, 100, 30.0);
  EXPECT_NEAR(j["total"]["energy_per_message_mj"].get<double>(), 1500.0, 1e-6);
  EXPECT_EQ(j["total"]["estimated"].size(), 1u);
}

// A discrete GPU gauge (power1_average), an ACPI meter (power1_input with a label), an energy
// counter, and a temperature-only sensor that is not a power source.
void write_hwmon(const FixtureRoot& root, int gpu_w, int acpi_w, uint64_t energy_uj) {
  root.write("sys/class/hwmon/hwmon0/name", "amdgpu\n");
  root.write("sys/class/hwmon/hwmon0/power1_average", std::to_string(gpu_w * 1'000'000) + "\n");
  root.write("sys/class/hwmon/hwmon1/name", "coretemp\n");
  root.write("sys/class/hwmon/hwmon1/temp1_input", "45000\n");
  // An older driver that keeps its attributes in device/.
  root.write("sys/class/hwmon/hwmon2/device/name", "power_meter\n");
  root.write("sys/class/hwmon/hwmon2/device/power1_input",
             std::to_string(acpi_w * 1'000'000) + "\n");
  root.write("sys/class/hwmon/hwmon2/device/power1_label", "system\n");
  root.write("sys/class/hwmon/hwmon10/name", "amd_energy\n");
  root.write("sys/class/hwmon/hwmon10/energy1_input", std::to_string(energy_uj) + "\n");
  root.write("sys/class/hwmon/hwmon10/energy1_label", "Esocket0\n");
}

// Two devices of one driver (two GPUs here) keep names of their own, with their hwmon folder.
TEST(Hwmon, TwoDevicesOfOneDriverAreToldApart) {
  FixtureRoot root;
  write_hwmon(root, 10, 50, 7'000'000);
  root.write("sys/class/hwmon/hwmon3/name", "amdgpu\n");
  root.write("sys/class/hwmon/hwmon3/power1_average", "20000000\n");
  const auto found = discover_power_sources(options_for(root, {"hwmon"}));
  std::vector<std::string> names;
  for (const auto& s : found.sources) names.push_back(s->info().name);
  EXPECT_EQ(names,
            (std::vector<std::string>{"hwmon:amdgpu[hwmon0]/power1", "hwmon:power_meter/system",
                                      "hwmon:amdgpu[hwmon3]/power1", "hwmon:amd_energy/Esocket0"}));
}

TEST(Hwmon, GaugesAreIntegratedAndCountersDifferenced) {
  FixtureRoot root;
  write_hwmon(root, 10, 50, 7'000'000);
  auto found = discover_power_sources(options_for(root, {"hwmon"}));
  ASSERT_EQ(found.sources.size(), 3u);
  PowerMeter meter(std::move(found.sources), found.notes);
  EXPECT_EQ(meter.sources()[0]->info().name, "hwmon:amdgpu/power1");
  EXPECT_EQ(meter.sources()[1]->info().name, "hwmon:power_meter/system");
  EXPECT_EQ(meter.sources()[2]->info().name, "hwmon:amd_energy/Esocket0");
  EXPECT_EQ(meter.sources()[2]->info().kind, PowerSourceKind::kEnergyCounter);

  meter.sample_round(0);
  write_hwmon(root, 20, 50, 9'000'000);
  meter.sample_round(kSecond);
  write_hwmon(root, 30, 50, 16'000'000);
  meter.sample_round(3 * kSecond);  // uneven spacing: trapezoids weigh each interval

  const PowerReport r = meter.report();
  ASSERT_TRUE(r.available);
  // GPU: (10+20)/2 * 1 s + (20+30)/2 * 2 s = 65 J over 3 s.
  EXPECT_NEAR(source(r, "hwmon:amdgpu/power1").energy_j, 65.0, 1e-9);
  EXPECT_NEAR(source(r, "hwmon:amdgpu/power1").average_w, 65.0 / 3, 1e-9);
  EXPECT_NEAR(source(r, "hwmon:power_meter/system").average_w, 50.0, 1e-9);
  EXPECT_NEAR(source(r, "hwmon:amd_energy/Esocket0").energy_j, 9.0, 1e-9);
  // The ACPI meter reads the whole machine: the GPU and the CPU are inside it.
  EXPECT_NEAR(r.total_energy_j, 150.0, 1e-9);
}

// A meter of the whole machine (ACPI power_meter, or --power-meter) beside RAPL would count the
// package twice: the total is the meter alone, the others listed with their own readings.
TEST(Hwmon, AWholeMachineMeterIsTheTotalAloneBesideRapl) {
  FixtureRoot root;
  write_rapl(root, 1'000'000, 500'000, 100, 1'000'000);
  write_hwmon(root, 10, 50, 7'000'000);
  auto found = discover_power_sources(options_for(root, {"rapl", "hwmon"}));
  std::vector<std::string> counted;
  for (const auto& s : found.sources) {
    if (s->info().in_total) counted.push_back(s->info().name);
  }
  EXPECT_EQ(counted, std::vector<std::string>{"hwmon:power_meter/system"});
  ASSERT_FALSE(found.notes.empty());
  EXPECT_NE(found.notes.back().find("total: hwmon:power_meter/system measures the whole machine, "
                                    "so the total is it alone; rapl:package-0, "
                                    "rapl:package-0/dram, rapl:package-1, hwmon:amdgpu/power1 are "
                                    "part of it"),
            std::string::npos)
      << found.notes.back();
  PowerMeter meter(std::move(found.sources), found.notes);
  meter.sample_round(0);
  write_rapl(root, 3'000'000, 1'500'000, 500'100, 4'000'000);
  meter.sample_round(kSecond);
  const PowerReport r = meter.report();
  ASSERT_TRUE(r.available);
  EXPECT_NEAR(r.total_average_w, 50.0, 1e-9);
  EXPECT_NEAR(source(r, "rapl:package-0").average_w, 2.0, 1e-9);  // still listed
  EXPECT_EQ(to_json(r, 0, 0)["total"]["sources"],
            nlohmann::json::array({"hwmon:power_meter/system"}));
}

TEST(Hwmon, CpuEnergyDriverIsLeftOutOfTheTotalWhenRaplCountsIt) {
  FixtureRoot root;
  write_rapl(root, 1, 1, 1, 1);
  write_hwmon(root, 10, 50, 7);
  fs::remove_all(root.path() / "sys/class/hwmon/hwmon2");  // no whole-machine meter
  const auto found = discover_power_sources(options_for(root, {}));
  for (const auto& s : found.sources) {
    if (s->info().name == "hwmon:amd_energy/Esocket0") {
      EXPECT_FALSE(s->info().in_total);
    }
    if (s->info().name == "hwmon:amdgpu/power1") {
      EXPECT_TRUE(s->info().in_total);
    }
  }
}

// Jetson Xavier NX / Nano style (L4T 32): the ina3221x IIO driver, power in mW.
void write_jetson_iio(const FixtureRoot& root, int in_mw, int cpu_mw, int soc_mw) {
  const std::string dev = "sys/bus/i2c/drivers/ina3221x/7-0040/iio:device0/";
  root.write(dev + "rail_name_0", "VDD_IN\n");
  root.write(dev + "in_power0_input", std::to_string(in_mw) + "\n");
  root.write(dev + "rail_name_1", "VDD_CPU_GPU_CV\n");
  root.write(dev + "in_power1_input", std::to_string(cpu_mw) + "\n");
  root.write(dev + "rail_name_2", "VDD_SOC\n");
  root.write(dev + "in_power2_input", std::to_string(soc_mw) + "\n");
}

TEST(Jetson, IioRailsWithModuleInputCountOnlyTheInput) {
  FixtureRoot root;
  write_jetson_iio(root, 6000, 2000, 1500);
  auto found = discover_power_sources(options_for(root, {"jetson"}));
  ASSERT_EQ(found.sources.size(), 3u);
  PowerMeter meter(std::move(found.sources), found.notes);
  meter.sample_round(0);
  write_jetson_iio(root, 8000, 3000, 1500);
  meter.sample_round(2 * kSecond);
  const PowerReport r = meter.report();
  ASSERT_TRUE(r.available);
  EXPECT_NEAR(source(r, "jetson:VDD_IN").average_w, 7.0, 1e-12);
  EXPECT_NEAR(source(r, "jetson:VDD_IN").energy_j, 14.0, 1e-12);
  EXPECT_NEAR(source(r, "jetson:VDD_CPU_GPU_CV").average_w, 2.5, 1e-12);
  EXPECT_FALSE(source(r, "jetson:VDD_SOC").info.in_total);
  EXPECT_NEAR(r.total_average_w, 7.0, 1e-12);
  EXPECT_NEAR(r.total_energy_j, 14.0, 1e-12);
}

// Jetson AGX Orin style (L4T 35): the ina3221 hwmon driver, mV and mA per channel, an
// unconnected channel labelled NC; no module input rail, so the rails add up.
TEST(Jetson, HwmonRailsMultiplyVoltageAndCurrent) {
  FixtureRoot root;
  const std::string hw = "sys/bus/i2c/drivers/ina3221/1-0040/hwmon/hwmon3/";
  const std::string labels[] = {"VDD_GPU_SOC", "VDD_CPU_CV", "VIN_SYS_5V0"};
  const int mv[] = {5000, 5000, 4800}, ma[] = {1200, 400, 500};
  for (int k = 1; k <= 3; ++k) {
    root.write(hw + "in" + std::to_string(k) + "_label", labels[k - 1] + "\n");
    root.write(hw + "in" + std::to_string(k) + "_input", std::to_string(mv[k - 1]) + "\n");
    root.write(hw + "curr" + std::to_string(k) + "_input", std::to_string(ma[k - 1]) + "\n");
  }
  const std::string hw2 = "sys/bus/i2c/drivers/ina3221/1-0041/hwmon/hwmon4/";
  root.write(hw2 + "in1_label", "NC\n");
  root.write(hw2 + "in1_input", "0\n");
  root.write(hw2 + "curr1_input", "0\n");
  auto found = discover_power_sources(options_for(root, {"jetson"}));
  ASSERT_EQ(found.sources.size(), 3u);
  PowerMeter meter(std::move(found.sources), found.notes);
  for (int t = 0; t <= 4; ++t) meter.sample_round(t * kSecond / 2);
  const PowerReport r = meter.report();
  ASSERT_TRUE(r.available);
  EXPECT_NEAR(source(r, "jetson:VDD_GPU_SOC").average_w, 6.0, 1e-12);
  EXPECT_NEAR(source(r, "jetson:VDD_CPU_CV").average_w, 2.0, 1e-12);
  EXPECT_NEAR(source(r, "jetson:VIN_SYS_5V0").average_w, 2.4, 1e-12);
  EXPECT_NEAR(r.total_average_w, 10.4, 1e-12);
  EXPECT_NEAR(r.total_energy_j, 20.8, 1e-12);
}

using FakeSet = void (*)(unsigned, unsigned long long, unsigned);

TEST(Nvml, FakeLibraryThroughTheDlopenPath) {
  // The same path gives the same loaded library: its controls act on what robotperf reads.
  void* fake = dlopen(FAKE_NVML_LIBRARY, RTLD_NOW | RTLD_LOCAL);
  ASSERT_NE(fake, nullptr) << dlerror();
  const auto set = reinterpret_cast<FakeSet>(dlsym(fake, "fake_nvml_set"));
  const auto init_count = reinterpret_cast<int (*)()>(dlsym(fake, "fake_nvml_init_count"));
  ASSERT_NE(set, nullptr);
  set(0, 1'000'000, 0);  // GPU 0: energy counter in mJ
  set(1, 0, 40'000);     // GPU 1: power only, 40 W
  {
    PowerOptions o;
    o.types = {"nvml"};
    o.nvml_library = FAKE_NVML_LIBRARY;
    auto found = discover_power_sources(o);
    ASSERT_EQ(found.sources.size(), 2u) << (found.notes.empty() ? "" : found.notes[0]);
    EXPECT_EQ(init_count(), 1);
    PowerMeter meter(std::move(found.sources), found.notes);
    EXPECT_EQ(meter.sources()[0]->info().name, "nvml:gpu0");
    EXPECT_EQ(meter.sources()[0]->info().description, "NVIDIA Fake A100");
    EXPECT_EQ(meter.sources()[0]->info().kind, PowerSourceKind::kEnergyCounter);
    EXPECT_EQ(meter.sources()[1]->info().kind, PowerSourceKind::kPowerGauge);

    // GPU 0 reports its load as well: busy 20 %, 90 %, 40 % of the time, memory growing.
    const auto set_load =
        reinterpret_cast<void (*)(unsigned, unsigned, unsigned long long, unsigned long long)>(
            dlsym(fake, "fake_nvml_set_load"));
    ASSERT_NE(set_load, nullptr);
    constexpr unsigned long long kGiB = 1ULL << 30;
    set_load(0, 20, 2 * kGiB, 80 * kGiB);
    meter.sample_round(0);
    set(0, 1'150'000, 0);
    set(1, 0, 60'000);
    set_load(0, 90, 6 * kGiB, 80 * kGiB);
    meter.sample_round(kSecond);
    set(0, 1'450'000, 0);
    set(1, 0, 60'000);
    set_load(0, 40, 5 * kGiB, 80 * kGiB);
    meter.sample_round(3 * kSecond);
    const PowerReport r = meter.report();
    const auto& load = source(r, "nvml:gpu0").load;
    ASSERT_TRUE(load.has_value());
    EXPECT_EQ(load->readings, 3u);
    EXPECT_NEAR(load->utilisation_mean_percent, 50.0, 1e-9);
    EXPECT_EQ(load->utilisation_max_percent, 90.0);
    EXPECT_EQ(load->memory_used_max_bytes, 6 * kGiB);
    EXPECT_EQ(load->memory_total_bytes, 80 * kGiB);
    EXPECT_FALSE(source(r, "nvml:gpu1").load.has_value()) << "a board without utilisation";
    const auto json = to_json(r, 10, 1.0);
    EXPECT_EQ(json["sources"][0]["load"]["utilisation_max_percent"], 90.0);
    EXPECT_TRUE(json["sources"][1]["load"].is_null());
    ASSERT_TRUE(r.available);
    EXPECT_NEAR(source(r, "nvml:gpu0").energy_j, 450.0, 1e-9);
    EXPECT_NEAR(source(r, "nvml:gpu0").average_w, 150.0, 1e-9);
    // 40 -> 60 W over 1 s, then 60 W for 2 s.
    EXPECT_NEAR(source(r, "nvml:gpu1").energy_j, 50.0 + 120.0, 1e-9);
    EXPECT_NEAR(r.total_energy_j, 620.0, 1e-9);
    EXPECT_NEAR(r.total_average_w, 150.0 + 170.0 / 3, 1e-9);
  }
  EXPECT_EQ(init_count(), 0) << "nvmlShutdown must balance nvmlInit";
  dlclose(fake);
}

TEST(Nvml, MissingLibraryOrSymbolsIsANoteNotAnError) {
  PowerOptions o;
  o.types = {"nvml"};
  o.nvml_library = "libnvidia-ml-does-not-exist.so.1";
  auto found = discover_power_sources(o);
  EXPECT_TRUE(found.sources.empty());
  ASSERT_EQ(found.notes.size(), 1u);
  EXPECT_NE(found.notes[0].find("not loadable"), std::string::npos) << found.notes[0];

  o.nvml_library = "libm.so.6";  // loads, but is no NVML
  found = discover_power_sources(o);
  ASSERT_EQ(found.notes.size(), 1u);
  EXPECT_NE(found.notes[0].find("NVML has no nvmlInit"), std::string::npos) << found.notes[0];
}

class ExternalMeter : public ::testing::Test {
 protected:
  void SetUp() override { fs::create_directories(root_.path()); }
  PowerOptions meter(const std::string& command) {
    PowerOptions o;
    o.types = {"external"};
    o.meter_command = command;
    // Long enough for a shell to start on a loaded 2-core machine, short of "sleep 5".
    o.meter_timeout_s = 2.0;
    return o;
  }
  FixtureRoot root_;
};

TEST_F(ExternalMeter, SampledOnTheBackgroundThreadDuringTheWindow) {
  root_.write("watts", "7.25 W\n");
  auto found = discover_power_sources(meter("cat '" + (root_.path() / "watts").string() + "'"));
  ASSERT_EQ(found.sources.size(), 1u);
  EXPECT_EQ(found.sources[0]->info().name, "external:meter");
  PowerMeter power(std::move(found.sources), found.notes);
  PowerSampler sampler(power, std::chrono::milliseconds(20));
  sampler.begin();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const PowerReport r = sampler.end();
  ASSERT_TRUE(r.available) << r.unavailable_reason;
  EXPECT_NEAR(r.total_average_w, 7.25, 1e-9);
  EXPECT_NEAR(r.total_energy_j, 7.25 * r.window_s, 1e-9);
  EXPECT_GT(r.window_s, 0.25);
  EXPECT_GE(r.rounds, 3u);  // a loaded 2-core machine may skip rounds, never take none
  EXPECT_EQ(source(r, "external:meter").failed_readings, 0u);
  EXPECT_GT(r.sampler_cpu_s, 0.0);
}

TEST_F(ExternalMeter, BrokenCommandsAreClearErrors) {
  auto message = [&](const std::string& command) {
    try {
      discover_power_sources(meter(command));
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("echo hello").find("expected watts"), std::string::npos);
  EXPECT_NE(message("echo -3").find("expected watts"), std::string::npos);
  // Finite but not physical: it would make throughput per watt 0.
  EXPECT_NE(message("echo 1e308").find("expected watts (a number from 0 to 100000)"),
            std::string::npos);
  EXPECT_NE(message("exit 3").find("exit status 3"), std::string::npos);
  EXPECT_NE(message("sleep 5").find("did not finish within"), std::string::npos);
  // What the meter said on its standard error ends the one line (its last line), instead of going
  // to the terminal as a second one.
  EXPECT_EQ(message("echo first >&2; echo 'no such sensor' >&2; exit 1"),
            "power meter 'echo first >&2; echo 'no such sensor' >&2; exit 1' failed (exit status "
            "1): no such sensor");
  // Output over several lines, or a command that spans them, stays in the one line.
  EXPECT_EQ(message("printf 'abc\\ndef'"),
            "power meter 'printf 'abc\\ndef'' printed 'abc\\ndef', expected watts (a number from "
            "0 to 100000) as its first word");
  EXPECT_EQ(message("exit 4\n"), "power meter 'exit 4\\n' failed (exit status 4)");
  // A child left running with the standard error open does not hold the reading up.
  EXPECT_EQ(message("(sleep 3 >/dev/null &); echo 5"), "no error");
}

TEST(PowerSampler, EndWithoutBeginSaysTheWindowNeverStarted) {
  PowerMeter meter({}, {"rapl: none"});
  PowerSampler sampler(meter, std::chrono::milliseconds(100));
  const PowerReport r = sampler.end();
  EXPECT_FALSE(r.available);
  EXPECT_NE(r.unavailable_reason.find("never started"), std::string::npos);
}

TEST(PowerDiscovery, UnknownTypeIsRejected) {
  PowerOptions o;
  o.types = {"watts"};
  EXPECT_THROW(discover_power_sources(o), std::invalid_argument);
}

TEST(ThisMachine, PowerIsUnavailableWithTheReasonNeverZero) {
  auto found = discover_power_sources(PowerOptions{});
  if (!found.sources.empty()) GTEST_SKIP() << "this machine has power sensors";
  PowerMeter meter(std::move(found.sources), found.notes);
  PowerSampler sampler(meter, std::chrono::milliseconds(10));
  sampler.begin();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const PowerReport r = sampler.end();
  EXPECT_FALSE(r.available);
  EXPECT_NE(r.unavailable_reason.find("no power source found"), std::string::npos);
  EXPECT_NE(r.unavailable_reason.find("rapl:"), std::string::npos) << r.unavailable_reason;
  EXPECT_NE(r.unavailable_reason.find("nvml:"), std::string::npos) << r.unavailable_reason;
  const auto j = to_json(r, 100, 30.0);
  EXPECT_EQ(j["available"], false);
  EXPECT_TRUE(j["total"].is_null());
  EXPECT_EQ(j["unavailable_reason"], r.unavailable_reason);
}

}  // namespace
}  // namespace robotperf::metrics
