// The host emulation of the CUDA runtime that the cuda backend's tests run on where there is no
// GPU: it must catch what a GPU would punish, or those tests would pass code a GPU fails.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "cuda_runtime.h"

namespace {

__global__ void add_one(const int32_t* in, int32_t* out, int n) {
  const int i = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i < n) out[i] = in[i] + 1;
}

class CudaEmulation : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_EQ(cudaStreamCreateWithFlags(&stream_, 0), cudaSuccess); }
  void TearDown() override { EXPECT_EQ(cudaStreamDestroy(stream_), cudaSuccess); }
  cudaStream_t stream_ = nullptr;
};

TEST_F(CudaEmulation, RunsAKernelOverEveryThreadOfItsGrid) {
  constexpr int n = 1000;
  int32_t *pinned = nullptr, *in = nullptr, *out = nullptr;
  ASSERT_EQ(cudaHostAlloc(reinterpret_cast<void**>(&pinned), n * 4, cudaHostAllocDefault),
            cudaSuccess);
  ASSERT_EQ(cudaMalloc(reinterpret_cast<void**>(&in), n * 4), cudaSuccess);
  ASSERT_EQ(cudaMalloc(reinterpret_cast<void**>(&out), n * 4), cudaSuccess);
  for (int i = 0; i < n; ++i) pinned[i] = i;
  ASSERT_EQ(cudaMemcpyAsync(in, pinned, n * 4, cudaMemcpyHostToDevice, stream_), cudaSuccess);
  robotperf::cuda_emulation::launch(add_one, dim3((n + 127) / 128), dim3(128), stream_,
                                    static_cast<const int32_t*>(in), out, n);
  ASSERT_EQ(cudaGetLastError(), cudaSuccess);
  ASSERT_EQ(cudaMemcpyAsync(pinned, out, n * 4, cudaMemcpyDeviceToHost, stream_), cudaSuccess);
  // Nothing has run yet: the host has not waited.
  EXPECT_EQ(pinned[7], 7) << "a stream's work ran before the host waited for it";
  ASSERT_EQ(cudaStreamSynchronize(stream_), cudaSuccess);
  for (int i = 0; i < n; ++i) ASSERT_EQ(pinned[i], i + 1) << i;
  EXPECT_EQ(cudaFree(in), cudaSuccess);
  EXPECT_EQ(cudaFree(out), cudaSuccess);
  EXPECT_EQ(cudaFreeHost(pinned), cudaSuccess);
}

TEST_F(CudaEmulation, CopiesFromPageableMemoryAsCudaDoes) {
  int32_t* device = nullptr;
  ASSERT_EQ(cudaMalloc(reinterpret_cast<void**>(&device), 4), cudaSuccess);
  std::vector<int32_t> host{5};
  // The source is read before the call returns: rewriting it afterwards changes nothing.
  ASSERT_EQ(cudaMemcpyAsync(device, host.data(), 4, cudaMemcpyHostToDevice, stream_), cudaSuccess);
  host[0] = 6;
  // A download into pageable memory is done when the call returns.
  ASSERT_EQ(cudaMemcpyAsync(host.data(), device, 4, cudaMemcpyDeviceToHost, stream_), cudaSuccess);
  EXPECT_EQ(host[0], 5);
  EXPECT_EQ(cudaFree(device), cudaSuccess);
}

TEST_F(CudaEmulation, RefusesCopiesTheWrongWayOrPastAnAllocation) {
  int32_t* device = nullptr;
  ASSERT_EQ(cudaMalloc(reinterpret_cast<void**>(&device), 16), cudaSuccess);
  std::vector<int32_t> host(8);
  EXPECT_EQ(cudaMemcpyAsync(host.data(), device, 16, cudaMemcpyHostToDevice, stream_),
            cudaErrorInvalidValue);
  EXPECT_EQ(cudaMemcpyAsync(device, host.data(), 32, cudaMemcpyHostToDevice, stream_),
            cudaErrorInvalidValue);
  EXPECT_EQ(cudaMemcpyAsync(host.data(), host.data() + 4, 16, cudaMemcpyDeviceToHost, stream_),
            cudaErrorInvalidValue);
  EXPECT_EQ(cudaFree(host.data()), cudaErrorInvalidDevicePointer);
  EXPECT_EQ(cudaFree(device), cudaSuccess);
}

TEST_F(CudaEmulation, RefusesAKernelAHostPointer) {
  std::vector<int32_t> host(4);
  robotperf::cuda_emulation::launch(add_one, dim3(1), dim3(4), stream_,
                                    static_cast<const int32_t*>(host.data()), host.data(), 4);
  EXPECT_EQ(cudaGetLastError(), cudaErrorIllegalAddress);
  EXPECT_EQ(cudaGetLastError(), cudaSuccess) << "the error is reported once";
}

using CudaEmulationDeathTest = CudaEmulation;

TEST_F(CudaEmulationDeathTest, HostCodeCannotTouchDeviceMemory) {
  int32_t* device = nullptr;
  ASSERT_EQ(cudaMalloc(reinterpret_cast<void**>(&device), 4), cudaSuccess);
  volatile int32_t* p = device;
  EXPECT_DEATH(static_cast<void>(*p), "");
  EXPECT_EQ(cudaFree(device), cudaSuccess);
}

TEST_F(CudaEmulationDeathTest, AKernelCannotReadPastItsAllocation) {
  int32_t *in = nullptr, *out = nullptr;
  ASSERT_EQ(cudaMalloc(reinterpret_cast<void**>(&in), 256), cudaSuccess);
  ASSERT_EQ(cudaMalloc(reinterpret_cast<void**>(&out), 4096), cudaSuccess);
  // 64 ints fill `in` to its guard page; the 65th thread reads past it. The launch is in the
  // dying child alone, so that the stream's teardown here has nothing to run.
  EXPECT_DEATH(
      {
        robotperf::cuda_emulation::launch(add_one, dim3(1), dim3(65), stream_,
                                          static_cast<const int32_t*>(in), out, 65);
        static_cast<void>(cudaStreamSynchronize(stream_));
      },
      "");
  EXPECT_EQ(cudaFree(in), cudaSuccess);
  EXPECT_EQ(cudaFree(out), cudaSuccess);
}

TEST(CudaEmulationDevice, NamesItselfAnEmulationAndHonoursCudaVisibleDevices) {
  cudaDeviceProp properties{};
  ASSERT_EQ(cudaGetDeviceProperties(&properties, 0), cudaSuccess);
  EXPECT_NE(std::string(properties.name).find("emulation"), std::string::npos);
  int count = -1;
  setenv("CUDA_VISIBLE_DEVICES", "-1", 1);
  EXPECT_EQ(cudaGetDeviceCount(&count), cudaErrorNoDevice);
  EXPECT_EQ(count, 0);
  unsetenv("CUDA_VISIBLE_DEVICES");
  EXPECT_EQ(cudaGetDeviceCount(&count), cudaSuccess);
  EXPECT_EQ(count, 1);
}

}  // namespace
