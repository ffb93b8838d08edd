#include "robotperf/sysinfo/machine.hpp"

#include <gtest/gtest.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "../fixture_root.hpp"

namespace robotperf::sysinfo {
namespace {

namespace fs = std::filesystem;

using robotperf::testing::FixtureRoot;

std::string x86_cpuinfo(int sockets, int cores_per_socket, int threads_per_core) {
  std::string text;
  int processor = 0;
  for (int thread = 0; thread < threads_per_core; ++thread) {
    for (int socket = 0; socket < sockets; ++socket) {
      for (int core = 0; core < cores_per_socket; ++core) {
        text += "processor\t: " + std::to_string(processor++) + "\n";
        text += "vendor_id\t: GenuineIntel\n";
        text += "model name\t: Intel(R) Xeon(R) Silver 4210 CPU @ 2.20GHz\n";
        text += "physical id\t: " + std::to_string(socket) + "\n";
        text += "core id\t\t: " + std::to_string(core) + "\n";
        text += "flags\t\t: fpu vme de pse tsc msr pae mce ht syscall nx lm avx2\n\n";
      }
    }
  }
  return text;
}

// Dual-socket Xeon workstation: 2 x 2 cores x 2 threads, cpufreq with powersave on all CPUs but
// one, a PREEMPT_RT Debian kernel, an NVIDIA GPU (also visible through DRM) and an Intel iGPU.
void write_x86_workstation(const FixtureRoot& root) {
  root.write("proc/cpuinfo", x86_cpuinfo(2, 2, 2));
  root.write("sys/devices/system/cpu/online", "0-7\n");
  for (int cpu = 0; cpu < 8; ++cpu) {
    const std::string cpufreq = "sys/devices/system/cpu/cpu" + std::to_string(cpu) + "/cpufreq/";
    root.write(cpufreq + "scaling_cur_freq", std::to_string(1'000'000 + cpu * 100'000) + "\n");
    root.write(cpufreq + "cpuinfo_min_freq", cpu == 3 ? "1000000\n" : "800000\n");
    root.write(cpufreq + "cpuinfo_max_freq", cpu < 4 ? "3200000\n" : "3500000\n");
    root.write(cpufreq + "scaling_governor", cpu == 7 ? "performance\n" : "powersave\n");
  }
  root.write("proc/meminfo",
             "MemTotal:       33554432 kB\nMemFree:        1000000 kB\nMemAvailable:   9 kB\n");
  root.write("proc/sys/kernel/osrelease", "6.1.0-18-rt-amd64\n");
  root.write("proc/sys/kernel/version", "#1 SMP PREEMPT_RT Debian 6.1.76-1 (2024-02-01)\n");
  root.write("proc/version",
             "Linux version 6.1.0-18-rt-amd64 (debian-kernel@lists.debian.org) (gcc-12) #1 SMP "
             "PREEMPT_RT Debian 6.1.76-1 (2024-02-01)\n");
  root.write("proc/sys/kernel/hostname", "lab-ws-01\n");
  root.write("proc/sys/kernel/arch", "x86_64\n");
  root.write("etc/os-release",
             "NAME=\"Debian GNU/Linux\"\nPRETTY_NAME=\"Debian GNU/Linux 12 "
             "(bookworm)\"\nID=debian\n");
  root.write("proc/1/cgroup", "0::/init.scope\n");
  root.write("sys/class/dmi/id/sys_vendor", "Dell Inc.\n");
  root.write("sys/class/dmi/id/product_name", "Precision 7920 Tower\n");
  root.write("proc/driver/nvidia/version",
             "NVRM version: NVIDIA UNIX x86_64 Kernel Module  535.104.05  Sat Aug 19 01:15:15 UTC "
             "2023\nGCC version:  gcc version 12.2.0 (Debian 12.2.0-14)\n");
  root.write("proc/driver/nvidia/gpus/0000:65:00.0/information",
             "Model: \t\t NVIDIA RTX A4000\nIRQ:   \t\t 180\nGPU UUID: \t GPU-1234\n"
             "Bus Location: \t 0000:65:00.0\n");
  root.write("sys/class/drm/card0/device/vendor", "0x10de\n");
  root.write("sys/class/drm/card0/device/device", "0x24b0\n");
  root.write("sys/class/drm/card0/device/uevent", "DRIVER=nvidia\nPCI_SLOT_NAME=0000:65:00.0\n");
  root.write("sys/class/drm/card1/device/vendor", "0x8086\n");
  root.write("sys/class/drm/card1/device/device", "0x3e92\n");
  root.write("sys/class/drm/card1/device/uevent", "DRIVER=i915\nPCI_SLOT_NAME=0000:00:02.0\n");
  // Connector and render nodes must not be listed as further GPUs.
  root.write("sys/class/drm/card1-HDMI-A-1/device/vendor", "0x8086\n");
  root.write("sys/class/drm/renderD128/device/vendor", "0x10de\n");
}

std::string arm_cpuinfo(const std::string& part, int first, int count) {
  std::string text;
  for (int cpu = first; cpu < first + count; ++cpu) {
    text += "processor\t: " + std::to_string(cpu) + "\n";
    text += "BogoMIPS\t: 62.50\nFeatures\t: fp asimd evtstrm aes pmull sha1 sha2 crc32 atomics\n";
    text += "CPU implementer\t: 0x41\nCPU architecture: 8\nCPU variant\t: 0x1\n";
    text += "CPU part\t: " + part + "\nCPU revision\t: 1\n\n";
  }
  return text;
}

// Jetson AGX Orin-like: 8 Cortex-A78AE cores of which 6 are online, no SMT, schedutil, an L4T
// kernel without PREEMPT_RT, running in a Docker container (cgroup v1 hint only), no PCI GPU.
void write_jetson(const FixtureRoot& root) {
  root.write("proc/cpuinfo", arm_cpuinfo("0xd42", 0, 6));
  root.write("sys/devices/system/cpu/online", "0-5\n");
  root.write("sys/devices/system/cpu/smt/control", "notsupported\n");
  for (int cpu = 0; cpu < 8; ++cpu) {
    const std::string base = "sys/devices/system/cpu/cpu" + std::to_string(cpu) + "/";
    root.write(base + "topology/core_cpus_list", std::to_string(cpu) + "\n");
    root.write(base + "topology/physical_package_id", "0\n");
    root.write(base + "cpufreq/scaling_cur_freq", cpu < 4 ? "729600\n" : "2201600\n");
    root.write(base + "cpufreq/cpuinfo_min_freq", "115200\n");
    root.write(base + "cpufreq/cpuinfo_max_freq", "2201600\n");
    root.write(base + "cpufreq/scaling_governor", "schedutil\n");
  }
  root.write("proc/meminfo", "MemTotal:       31457280 kB\n");
  root.write("proc/sys/kernel/osrelease", "5.10.120-tegra\n");
  root.write("proc/version",
             "Linux version 5.10.120-tegra (buildbrain@mobile-u64-5273-d7000) (aarch64-buildroot-"
             "linux-gnu-gcc.br_real) #1 SMP PREEMPT Tue Aug 1 12:32:50 PDT 2023\n");
  root.write("proc/device-tree/model", std::string("NVIDIA Jetson AGX Orin Developer Kit\0", 37));
  root.write("proc/1/cgroup", "12:cpuset:/docker/0123456789abcdef\n11:memory:/docker/0123\n");
}

TEST(CollectMachineInfo, X86Workstation) {
  FixtureRoot root;
  write_x86_workstation(root);
  const MachineInfo info = collect_machine_info(root.path());

  EXPECT_EQ(info.cpu_model, "Intel(R) Xeon(R) Silver 4210 CPU @ 2.20GHz");
  EXPECT_EQ(info.logical_cpus, 8u);
  EXPECT_EQ(info.physical_cores, 4u);
  EXPECT_EQ(info.sockets, 2u);
  EXPECT_EQ(info.smt_enabled, true);

  ASSERT_EQ(info.cpu_frequencies.size(), 8u);
  EXPECT_EQ(info.cpu_frequencies[5].cpu, 5u);
  EXPECT_EQ(info.cpu_frequencies[5].current_khz, 1'500'000u);
  EXPECT_EQ(info.cpu_frequencies[5].governor, "powersave");
  EXPECT_EQ(info.current_frequency_min_khz, 1'000'000u);
  EXPECT_EQ(info.current_frequency_max_khz, 1'700'000u);
  EXPECT_EQ(info.frequency_min_khz, 800'000u);
  EXPECT_EQ(info.frequency_max_khz, 3'500'000u);
  EXPECT_EQ(info.governors, (std::vector<std::string>{"performance", "powersave"}));

  EXPECT_EQ(info.memory_total_bytes, 33554432ull * 1024);
  EXPECT_EQ(info.kernel_release, "6.1.0-18-rt-amd64");
  EXPECT_EQ(info.kernel_version, "#1 SMP PREEMPT_RT Debian 6.1.76-1 (2024-02-01)");
  EXPECT_EQ(info.preempt_rt, true);
  EXPECT_EQ(info.hostname, "lab-ws-01");
  EXPECT_EQ(info.architecture, "x86_64");
  EXPECT_EQ(info.os_name, "Debian GNU/Linux 12 (bookworm)");
  EXPECT_EQ(info.system_vendor, "Dell Inc.");
  EXPECT_EQ(info.system_product, "Precision 7920 Tower");
  EXPECT_FALSE(info.board_model.has_value());
  EXPECT_FALSE(info.in_container);
  EXPECT_FALSE(info.container_runtime.has_value());
  EXPECT_EQ(info.virtual_machine, false);

  ASSERT_EQ(info.gpus.size(), 2u);
  EXPECT_EQ(info.gpus[0].source, "nvidia");
  EXPECT_EQ(info.gpus[0].model, "NVIDIA RTX A4000");
  EXPECT_EQ(info.gpus[0].pci_address, "0000:65:00.0");
  EXPECT_EQ(info.gpus[0].driver_version, "535.104.05");
  EXPECT_EQ(info.gpus[1].source, "drm");
  EXPECT_FALSE(info.gpus[1].model.has_value());
  EXPECT_EQ(info.gpus[1].vendor_id, "0x8086");
  EXPECT_EQ(info.gpus[1].vendor_name, "Intel");
  EXPECT_EQ(info.gpus[1].device_id, "0x3e92");
  EXPECT_EQ(info.gpus[1].driver, "i915");
  EXPECT_EQ(info.gpus[1].pci_address, "0000:00:02.0");

  EXPECT_EQ(summary_line(info),
            "Intel(R) Xeon(R) Silver 4210 CPU @ 2.20GHz · 8 CPUs (4 cores, 2 sockets) · 32.0 GiB · "
            "Linux 6.1.0-18-rt-amd64 PREEMPT_RT · NVIDIA RTX A4000 · Intel GPU 0x3e92");
}

TEST(CollectMachineInfo, X86WorkstationJson) {
  FixtureRoot root;
  write_x86_workstation(root);
  const nlohmann::json json = to_json(collect_machine_info(root.path()));

  EXPECT_EQ(json.at("cpu").at("model"), "Intel(R) Xeon(R) Silver 4210 CPU @ 2.20GHz");
  EXPECT_EQ(json.at("cpu").at("physical_cores"), 4);
  EXPECT_EQ(json.at("cpu").at("smt_enabled"), true);
  const auto& frequency = json.at("cpu").at("frequency");
  EXPECT_EQ(frequency.at("max_khz"), 3'500'000);
  EXPECT_EQ(frequency.at("governors"), nlohmann::json({"performance", "powersave"}));
  EXPECT_EQ(frequency.at("per_cpu").size(), 8u);
  EXPECT_EQ(frequency.at("per_cpu")[7].at("governor"), "performance");
  EXPECT_EQ(json.at("kernel").at("preempt_rt"), true);
  EXPECT_EQ(json.at("memory_total_bytes"), 34359738368ull);
  EXPECT_TRUE(json.at("board_model").is_null());
  EXPECT_EQ(json.at("container").at("detected"), false);
  EXPECT_TRUE(json.at("container").at("runtime").is_null());
  EXPECT_EQ(json.at("gpus").size(), 2u);
  EXPECT_EQ(json.at("gpus")[0].at("model"), "NVIDIA RTX A4000");
  EXPECT_TRUE(json.at("gpus")[1].at("model").is_null());
}

TEST(CollectMachineInfo, JetsonLikeArmBoard) {
  FixtureRoot root;
  write_jetson(root);
  const MachineInfo info = collect_machine_info(root.path());

  EXPECT_EQ(info.cpu_model, "ARM Cortex-A78AE");
  EXPECT_EQ(info.board_model, "NVIDIA Jetson AGX Orin Developer Kit");
  EXPECT_EQ(info.logical_cpus, 6u);
  EXPECT_EQ(info.physical_cores, 6u);
  EXPECT_EQ(info.sockets, 1u);
  EXPECT_EQ(info.smt_enabled, false);
  // Offline CPUs 6 and 7 have cpufreq directories but are not part of the machine as it runs.
  EXPECT_EQ(info.cpu_frequencies.size(), 6u);
  EXPECT_EQ(info.current_frequency_min_khz, 729'600u);
  EXPECT_EQ(info.current_frequency_max_khz, 2'201'600u);
  EXPECT_EQ(info.frequency_min_khz, 115'200u);
  EXPECT_EQ(info.governors, std::vector<std::string>{"schedutil"});
  EXPECT_EQ(info.preempt_rt, false);
  EXPECT_EQ(info.kernel_release, "5.10.120-tegra");
  EXPECT_TRUE(info.in_container);
  EXPECT_EQ(info.container_runtime, "docker");
  // No x86 flags and no DMI: whether this is a VM cannot be told.
  EXPECT_FALSE(info.virtual_machine.has_value());
  EXPECT_FALSE(info.hostname.has_value());
  EXPECT_FALSE(info.system_vendor.has_value());
  EXPECT_TRUE(info.gpus.empty());
  EXPECT_EQ(summary_line(info),
            "ARM Cortex-A78AE · 6 CPUs (6 cores) · 30.0 GiB · Linux 5.10.120-tegra");
}

TEST(CollectMachineInfo, MissingTreeReportsEverythingUnknown) {
  const MachineInfo info = collect_machine_info("/nonexistent/robotperf/root");
  EXPECT_FALSE(info.cpu_model.has_value());
  EXPECT_FALSE(info.logical_cpus.has_value());
  EXPECT_FALSE(info.physical_cores.has_value());
  EXPECT_FALSE(info.sockets.has_value());
  EXPECT_FALSE(info.smt_enabled.has_value());
  EXPECT_TRUE(info.cpu_frequencies.empty());
  EXPECT_FALSE(info.frequency_max_khz.has_value());
  EXPECT_TRUE(info.governors.empty());
  EXPECT_FALSE(info.memory_total_bytes.has_value());
  EXPECT_FALSE(info.kernel_release.has_value());
  EXPECT_FALSE(info.preempt_rt.has_value());
  EXPECT_FALSE(info.hostname.has_value());
  EXPECT_FALSE(info.in_container);
  EXPECT_FALSE(info.virtual_machine.has_value());
  EXPECT_TRUE(info.gpus.empty());
  EXPECT_EQ(summary_line(info), "unknown CPU");

  const nlohmann::json json = to_json(info);
  EXPECT_TRUE(json.at("cpu").at("model").is_null());
  EXPECT_TRUE(json.at("cpu").at("logical_cpus").is_null());
  EXPECT_TRUE(json.at("cpu").at("frequency").at("max_khz").is_null());
  EXPECT_TRUE(json.at("memory_total_bytes").is_null());
  EXPECT_TRUE(json.at("kernel").at("preempt_rt").is_null());
  EXPECT_TRUE(json.at("virtual_machine").is_null());
}

TEST(CollectMachineInfo, BigLittleCoresAreJoinedInOrder) {
  FixtureRoot root;
  root.write("proc/cpuinfo", arm_cpuinfo("0xd05", 0, 4) + arm_cpuinfo("0xd0b", 4, 4));
  EXPECT_EQ(collect_machine_info(root.path()).cpu_model, "ARM Cortex-A55 + ARM Cortex-A76");
}

TEST(CollectMachineInfo, UnknownArmPartLeavesModelUnknown) {
  FixtureRoot root;
  root.write("proc/cpuinfo", arm_cpuinfo("0xd05", 0, 2) + arm_cpuinfo("0xfff", 2, 2));
  const MachineInfo info = collect_machine_info(root.path());
  EXPECT_FALSE(info.cpu_model.has_value());
  EXPECT_EQ(info.logical_cpus, 4u);
}

// Raspberry Pi kernels say "Hardware: BCM2835" on every Pi: the cores say what the CPU is, and the
// SoC line names only a CPU whose cores are not known.
TEST(CollectMachineInfo, ArmCoresComeBeforeTheHardwareLine) {
  const std::string pi =
      "Hardware\t: BCM2835\nRevision\t: c03114\nModel\t\t: Raspberry Pi 4 Model B\n";
  FixtureRoot root;
  root.write("proc/cpuinfo", arm_cpuinfo("0xd08", 0, 4) + pi);
  EXPECT_EQ(collect_machine_info(root.path()).cpu_model, "ARM Cortex-A72");
  FixtureRoot unknown_cores;
  unknown_cores.write("proc/cpuinfo", arm_cpuinfo("0xfff", 0, 4) + pi);
  EXPECT_EQ(collect_machine_info(unknown_cores.path()).cpu_model, "BCM2835");
}

// kernel.arch is from Linux 6.1 on; before, the architecture is uname's.
TEST(CollectMachineInfo, ArchitectureIsTheRunningKernelsMachine) {
  utsname name{};
  ASSERT_EQ(uname(&name), 0);
  EXPECT_EQ(collect_machine_info("/").architecture, std::string(name.machine));
}

TEST(CollectMachineInfo, SysfsTopologyWinsAndSmtActiveIsRead) {
  FixtureRoot root;
  // cpuinfo claims one core per CPU; sysfs says CPUs 0 and 1 are siblings of one core.
  root.write("proc/cpuinfo", x86_cpuinfo(1, 2, 1));
  root.write("sys/devices/system/cpu/online", "0-1");
  root.write("sys/devices/system/cpu/smt/active", "1\n");
  for (int cpu = 0; cpu < 2; ++cpu) {
    const std::string topology = "sys/devices/system/cpu/cpu" + std::to_string(cpu) + "/topology/";
    root.write(topology + "thread_siblings_list", "0-1\n");
    root.write(topology + "physical_package_id", "0\n");
  }
  const MachineInfo info = collect_machine_info(root.path());
  EXPECT_EQ(info.logical_cpus, 2u);
  EXPECT_EQ(info.physical_cores, 1u);
  EXPECT_EQ(info.sockets, 1u);
  EXPECT_EQ(info.smt_enabled, true);
}

TEST(CollectMachineInfo, RealtimeFileAndOldStyleVersionMeanPreemptRt) {
  FixtureRoot realtime_file;
  realtime_file.write("sys/kernel/realtime", "1\n");
  realtime_file.write("proc/version", "Linux version 6.12.0 #1 SMP PREEMPT_DYNAMIC\n");
  EXPECT_EQ(collect_machine_info(realtime_file.path()).preempt_rt, true);

  FixtureRoot old_style;
  old_style.write("proc/version", "Linux version 4.19.59-rt24 #1 SMP PREEMPT RT Mon Jul 1\n");
  EXPECT_EQ(collect_machine_info(old_style.path()).preempt_rt, true);

  FixtureRoot dynamic;
  dynamic.write("proc/version", "Linux version 6.1.0 #1 SMP PREEMPT_DYNAMIC Debian\n");
  EXPECT_EQ(collect_machine_info(dynamic.path()).preempt_rt, false);
}

TEST(CollectMachineInfo, ContainerHints) {
  FixtureRoot docker;
  docker.write(".dockerenv", "");
  EXPECT_EQ(collect_machine_info(docker.path()).container_runtime, "docker");

  FixtureRoot podman;
  podman.write("run/.containerenv", "engine=\"podman-4.3.1\"\n");
  EXPECT_EQ(collect_machine_info(podman.path()).container_runtime, "podman");

  FixtureRoot kubernetes;
  kubernetes.write(".dockerenv", "");
  kubernetes.write("proc/1/cgroup", "0::/kubepods/besteffort/pod1234/abcd\n");
  EXPECT_EQ(collect_machine_info(kubernetes.path()).container_runtime, "kubernetes");

  FixtureRoot nspawn;
  nspawn.write("run/systemd/container", "systemd-nspawn\n");
  const MachineInfo info = collect_machine_info(nspawn.path());
  EXPECT_TRUE(info.in_container);
  EXPECT_EQ(info.container_runtime, "systemd-nspawn");
}

TEST(CollectMachineInfo, VirtualMachineHints) {
  FixtureRoot x86_guest;
  x86_guest.write("proc/cpuinfo", "processor\t: 0\nflags\t\t: fpu vme hypervisor lahf_lm\n");
  EXPECT_EQ(collect_machine_info(x86_guest.path()).virtual_machine, true);

  FixtureRoot arm_guest;
  arm_guest.write("proc/cpuinfo", arm_cpuinfo("0xd0c", 0, 2));
  arm_guest.write("sys/class/dmi/id/sys_vendor", "QEMU\n");
  EXPECT_EQ(collect_machine_info(arm_guest.path()).virtual_machine, true);

  FixtureRoot hyper_v;
  hyper_v.write("sys/class/dmi/id/sys_vendor", "Microsoft Corporation\n");
  hyper_v.write("sys/class/dmi/id/product_name", "Virtual Machine\n");
  EXPECT_EQ(collect_machine_info(hyper_v.path()).virtual_machine, true);

  FixtureRoot surface;
  surface.write("sys/class/dmi/id/sys_vendor", "Microsoft Corporation\n");
  surface.write("sys/class/dmi/id/product_name", "Surface Laptop 5\n");
  EXPECT_FALSE(collect_machine_info(surface.path()).virtual_machine.has_value());
}

TEST(CollectMachineInfo, RealMachineSmoke) {
  const MachineInfo info = collect_machine_info();
  ASSERT_TRUE(info.logical_cpus.has_value());
  EXPECT_GE(*info.logical_cpus, 1u);
  EXPECT_EQ(*info.logical_cpus, static_cast<unsigned>(::sysconf(_SC_NPROCESSORS_ONLN)));
  EXPECT_EQ(*info.logical_cpus, std::thread::hardware_concurrency());
  if (info.physical_cores) {
    EXPECT_LE(*info.physical_cores, *info.logical_cpus);
  }

  utsname names{};
  ASSERT_EQ(::uname(&names), 0);
  EXPECT_EQ(info.kernel_release, std::string(names.release));
  EXPECT_EQ(info.hostname, std::string(names.nodename));
  ASSERT_TRUE(info.memory_total_bytes.has_value());
  EXPECT_GT(*info.memory_total_bytes, 0u);

  const std::string line = summary_line(info);
  EXPECT_NE(line.find(std::to_string(*info.logical_cpus) + " CPUs"), std::string::npos) << line;
  EXPECT_NO_THROW(to_json(info).dump());
}

}  // namespace
}  // namespace robotperf::sysinfo
