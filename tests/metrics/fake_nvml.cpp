// A stand-in for libnvidia-ml.so: the NVML entry points robotperf uses, with values the tests set
// through fake_nvml_set() and fake_nvml_set_load(). Built as a shared library and loaded through
// robotperf's own dlopen path. GPU 0 has an energy counter (Volta and later) and reports its
// utilisation; GPU 1 only reports power (older boards).
#include <cstring>

namespace {

constexpr int kSuccess = 0;
constexpr int kUninitialized = 1;
constexpr int kInvalidArgument = 2;
constexpr int kNotSupported = 3;

struct FakeGpu {
  const char* name;
  bool has_energy_counter;
  unsigned long long energy_mj;
  unsigned power_mw;
  unsigned utilisation_percent = 0;
  unsigned long long memory_used = 0;
  unsigned long long memory_total = 0;
};

FakeGpu gpus[2] = {{"NVIDIA Fake A100", true, 0, 0}, {"NVIDIA Fake K80", false, 0, 0}};

// nvmlUtilization_t and nvmlMemory_t.
struct Utilisation {
  unsigned gpu;
  unsigned memory;
};
struct Memory {
  unsigned long long total;
  unsigned long long free;
  unsigned long long used;
};
int init_count = 0;

FakeGpu* gpu(void* handle) {
  for (auto& g : gpus) {
    if (handle == &g) return &g;
  }
  return nullptr;
}

}  // namespace

extern "C" {

int nvmlInit_v2() {
  ++init_count;
  return kSuccess;
}
int nvmlShutdown() {
  if (init_count == 0) return kUninitialized;
  --init_count;
  return kSuccess;
}
const char* nvmlErrorString(int result) {
  switch (result) {
    case kSuccess:
      return "Success";
    case kUninitialized:
      return "Uninitialized";
    case kInvalidArgument:
      return "Invalid Argument";
    case kNotSupported:
      return "Not Supported";
    default:
      return "Unknown Error";
  }
}
int nvmlDeviceGetCount_v2(unsigned* count) {
  if (init_count == 0) return kUninitialized;
  *count = 2;
  return kSuccess;
}
int nvmlDeviceGetHandleByIndex_v2(unsigned index, void** device) {
  if (init_count == 0) return kUninitialized;
  if (index >= 2) return kInvalidArgument;
  *device = &gpus[index];
  return kSuccess;
}
int nvmlDeviceGetName(void* device, char* name, unsigned length) {
  FakeGpu* g = gpu(device);
  if (g == nullptr || length == 0) return kInvalidArgument;
  std::strncpy(name, g->name, length - 1);
  name[length - 1] = '\0';
  return kSuccess;
}
int nvmlDeviceGetTotalEnergyConsumption(void* device, unsigned long long* energy_mj) {
  FakeGpu* g = gpu(device);
  if (g == nullptr) return kInvalidArgument;
  if (!g->has_energy_counter) return kNotSupported;
  *energy_mj = g->energy_mj;
  return kSuccess;
}
int nvmlDeviceGetPowerUsage(void* device, unsigned* power_mw) {
  FakeGpu* g = gpu(device);
  if (g == nullptr) return kInvalidArgument;
  *power_mw = g->power_mw;
  return kSuccess;
}

int nvmlDeviceGetUtilizationRates(void* device, Utilisation* u) {
  FakeGpu* g = gpu(device);
  if (g == nullptr) return kInvalidArgument;
  // The K80 stands for a board that does not report it.
  if (!g->has_energy_counter) return kNotSupported;
  u->gpu = g->utilisation_percent;
  u->memory = 0;
  return kSuccess;
}
int nvmlDeviceGetMemoryInfo(void* device, Memory* m) {
  FakeGpu* g = gpu(device);
  if (g == nullptr) return kInvalidArgument;
  m->total = g->memory_total;
  m->used = g->memory_used;
  m->free = g->memory_total - g->memory_used;
  return kSuccess;
}

// Test controls.
void fake_nvml_set_load(unsigned index, unsigned utilisation_percent,
                        unsigned long long memory_used, unsigned long long memory_total) {
  gpus[index].utilisation_percent = utilisation_percent;
  gpus[index].memory_used = memory_used;
  gpus[index].memory_total = memory_total;
}
void fake_nvml_set(unsigned index, unsigned long long energy_mj, unsigned power_mw) {
  gpus[index].energy_mj = energy_mj;
  gpus[index].power_mw = power_mw;
}
int fake_nvml_init_count() {
  return init_count;
}

}  // extern "C"
