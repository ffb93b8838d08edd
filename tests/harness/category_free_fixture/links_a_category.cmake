# Not used by the build: what category_free_test.cmake must find.
target_link_libraries(robotperf PRIVATE robotperf_harness robotperf_categories)
