// The backends the perception kernels bring besides the host's cpu: opencl, through OpenCV's
// transparent API, and cuda, kernels of their own in a build with the CUDA toolkit.
#include <string>

#include "category.hpp"
#include "robotperf/perception/cuda_device.hpp"
#include "robotperf/perception/opencl_device.hpp"

namespace robotperf::perception {

void register_backends(plugin::Registrar& registrar) {
  registrar.add_backend(
      {.name = "opencl",
       .description = "OpenCL through OpenCV's transparent API: a GPU first, else a CPU or "
                      "accelerator device (OPENCV_OPENCL_DEVICE chooses)"},
      {.devices = opencl_devices, .unavailable_reason = {}});
  // Without the toolkit the kernels do not list cuda, so a run asking for it would only hear that
  // no kernel has it: the backend says what to install instead.
  registrar.add_backend(
      {.name = "cuda",
       .description = "CUDA kernels of the perception category on the runtime's device 0 "
                      "(CUDA_VISIBLE_DEVICES chooses)"},
      {.devices = cuda_devices, .unavailable_reason = [] {
         return cuda_backend_built() ? std::string() : std::string(kCudaNotBuilt);
       }});
}

}  // namespace robotperf::perception
