// The perception kernels without the CUDA toolkit: no cuda backend, and every way to ask for it
// says so in one line.
#include <stdexcept>

#include "cuda_backend.hpp"
#include "robotperf/perception/cuda_device.hpp"

namespace robotperf::perception {
namespace {

[[noreturn]] void not_built() {
  throw std::invalid_argument(kCudaNotBuilt);
}

}  // namespace

bool cuda_backend_built() {
  return false;
}

std::vector<plugin::DeviceInfo> cuda_devices() {
  return {};
}

const plugin::DeviceInfo& cuda_device() {
  not_built();
}

CudaTransferFloor cuda_transfer_floor(std::size_t, int) {
  not_built();
}

namespace cuda {

std::unique_ptr<Remapper> make_remapper() {
  not_built();
}

std::unique_ptr<ImageResizer> make_resizer() {
  not_built();
}

std::unique_ptr<PointCloudMaker> make_point_cloud_maker() {
  not_built();
}

std::unique_ptr<BlockMatcher> make_block_matcher(const StereoParams& /*params*/) {
  not_built();
}

}  // namespace cuda
}  // namespace robotperf::perception
