// Not compiled: what category_free_test.cmake must find (CategoryFree.FindsWhatItLooksFor).
#include "robotperf/harness/run.hpp"
#include "robotperf/perception/opencl_device.hpp"
