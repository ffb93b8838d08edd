// A shared library that is not a robotperf plug-in: it has no plug-in entry points.
extern "C" __attribute__((visibility("default"))) int add_one(int x) {
  return x + 1;
}
