// The point cloud on the CUDA device: the cuda backend of depth_image_proc_computations.hpp, on
// the point cloud maker of cuda_backend.hpp (which, in a build without the toolkit, says so in
// one line when it is made). Compiled by the host compiler in every build.
#include "../depth_image_proc_computations.hpp"
#include "cuda_backend.hpp"

namespace robotperf::perception {
namespace {

class CudaPointCloud final : public PointCloudComputation {
 public:
  void xyzrgb(const cv::Mat& depth, const cv::Mat& colour, const XyzrgbModel& model,
              msgs::PointCloud2& cloud) override {
    cv::Mat points(depth.rows, static_cast<int>(cloud.row_step), CV_8UC1, cloud.data.data());
    maker_->xyzrgb(depth, colour, model, points);
  }

 private:
  std::unique_ptr<cuda::PointCloudMaker> maker_ = cuda::make_point_cloud_maker();
};

}  // namespace

std::unique_ptr<PointCloudComputation> make_cuda_point_cloud() {
  return std::make_unique<CudaPointCloud>();
}

}  // namespace robotperf::perception
