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

// Each block reverses its part of `in` through shared memory; with `barrier` false a thread reads
// its partner's slot without waiting for the partner to write it.
__global__ void reverse_blocks(const int32_t* in, int32_t* out, bool barrier) {
  int32_t* slots = static_cast<int32_t*>(robotperf::cuda_emulation::dynamic_shared_memory());
  const unsigned i = blockIdx.x * blockDim.x + threadIdx.x;
  slots[threadIdx.x] = in[i];
  if (barrier) __syncthreads();
  out[i] = slots[blockDim.x - 1 - threadIdx.x];
}

// Per thread of a block of two warps: the lanes of its warp whose value is odd, and those whose
// value is its own.
__global__ void warp_votes(const int32_t* in, int32_t* odd, int32_t* same) {
  const unsigned i = blockIdx.x * blockDim.x + threadIdx.x;
  odd[i] = static_cast<int32_t>(__ballot_sync(0xffffffffu, in[i] % 2));
  same[i] = static_cast<int32_t>(__match_any_sync(0xffffffffu, in[i]));
}

__global__ void barrier_in_a_plain_launch(int32_t* out) {
  __syncthreads();
  out[threadIdx.x] = 1;
}

// Lane 0 ends before the vote that names it.
__global__ void vote_without_lane_zero(int32_t* out) {
  if (threadIdx.x == 0) return;
  out[threadIdx.x] = static_cast<int32_t>(__ballot_sync(0xffffffffu, 1));
}

class CudaEmulation : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_EQ(cudaStreamCreateWithFlags(&stream_, 0), cudaSuccess); }
  void TearDown() override { EXPECT_EQ(cudaStreamDestroy(stream_), cudaSuccess); }
  // `in` up, `kernel` run by `launch` on the device copies (in, then `outs` outputs of in's size),
  // and the outputs down.
  template <class Launch>
  std::vector<std::vector<int32_t>> run(const std::vector<int32_t>& in, int outs, Launch launch) {
    const std::size_t bytes = in.size() * sizeof(int32_t);
    std::vector<int32_t*> device(static_cast<std::size_t>(outs) + 1);
    for (int32_t*& d : device)
      EXPECT_EQ(cudaMalloc(reinterpret_cast<void**>(&d), bytes), cudaSuccess);
    EXPECT_EQ(cudaMemcpyAsync(device[0], in.data(), bytes, cudaMemcpyHostToDevice, stream_),
              cudaSuccess);
    launch(device);
    EXPECT_EQ(cudaGetLastError(), cudaSuccess);
    std::vector<std::vector<int32_t>> out(static_cast<std::size_t>(outs), in);
    for (int i = 0; i < outs; ++i) {
      EXPECT_EQ(
          cudaMemcpyAsync(out[i].data(), device[i + 1], bytes, cudaMemcpyDeviceToHost, stream_),
          cudaSuccess);
    }
    for (int32_t* d : device) EXPECT_EQ(cudaFree(d), cudaSuccess);
    return out;
  }

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

TEST_F(CudaEmulation, ThreadsOfABlockWaitForEachOtherAtABarrier) {
  std::vector<int32_t> in(256);
  for (std::size_t i = 0; i < in.size(); ++i) in[i] = static_cast<int32_t>(i);
  const auto reversed = [&](bool barrier) {
    return run(in, 1, [&](const std::vector<int32_t*>& d) {
      robotperf::cuda_emulation::launch_synchronising(
          reverse_blocks, dim3(2), dim3(128), 128 * sizeof(int32_t), stream_,
          static_cast<const int32_t*>(d[0]), d[1], barrier);
    })[0];
  };
  const std::vector<int32_t> with_barrier = reversed(true);
  for (int i = 0; i < 256; ++i) ASSERT_EQ(with_barrier[i], i / 128 * 128 + 127 - i % 128) << i;
  // Without the barrier the first threads read slots not yet written, as they may on a GPU: the
  // emulation's order makes that a wrong answer rather than a lucky one.
  EXPECT_NE(reversed(false), with_barrier);
}

TEST_F(CudaEmulation, AnswersWarpVotesOverTheLanesOfEachWarp) {
  std::vector<int32_t> in(128);
  for (std::size_t i = 0; i < in.size(); ++i) in[i] = static_cast<int32_t>(i % 3 + (i / 32) * 10);
  const auto out = run(in, 2, [&](const std::vector<int32_t*>& d) {
    robotperf::cuda_emulation::launch_synchronising(warp_votes, dim3(2), dim3(64), 0, stream_,
                                                    static_cast<const int32_t*>(d[0]), d[1], d[2]);
  });
  for (std::size_t i = 0; i < in.size(); ++i) {
    const std::size_t warp = i / 32 * 32;
    unsigned odd = 0, same = 0;
    for (unsigned lane = 0; lane < 32; ++lane) {
      odd |= in[warp + lane] % 2 != 0 ? 1u << lane : 0u;
      same |= in[warp + lane] == in[i] ? 1u << lane : 0u;
    }
    ASSERT_EQ(static_cast<unsigned>(out[0][i]), odd) << i;
    ASSERT_EQ(static_cast<unsigned>(out[1][i]), same) << i;
  }
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

TEST_F(CudaEmulationDeathTest, ABarrierNeedsTheSynchronisingLaunch) {
  int32_t* out = nullptr;
  ASSERT_EQ(cudaMalloc(reinterpret_cast<void**>(&out), 4 * 32), cudaSuccess);
  EXPECT_DEATH(
      {
        robotperf::cuda_emulation::launch(barrier_in_a_plain_launch, dim3(1), dim3(32), stream_,
                                          out);
        static_cast<void>(cudaStreamSynchronize(stream_));
      },
      "__syncthreads in a kernel launched with launch\\(\\)");
  EXPECT_EQ(cudaFree(out), cudaSuccess);
}

TEST_F(CudaEmulationDeathTest, AWarpVoteALaneNeverReachesEndsTheTest) {
  int32_t* out = nullptr;
  ASSERT_EQ(cudaMalloc(reinterpret_cast<void**>(&out), 4 * 32), cudaSuccess);
  EXPECT_DEATH(
      {
        robotperf::cuda_emulation::launch_synchronising(vote_without_lane_zero, dim3(1), dim3(32),
                                                        0, stream_, out);
        static_cast<void>(cudaStreamSynchronize(stream_));
      },
      "a lane a warp collective names has ended");
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
