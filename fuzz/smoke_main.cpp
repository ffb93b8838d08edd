// A libFuzzer-compatible driver for builds without libFuzzer (GCC, CI): runs a fuzz target on
// every seed file and on deterministic mutations of them, for a bounded time.
//
//   <target>_smoke [--seconds S] [--mutations N] file-or-folder...
//
// --mutations bounds the rounds over the seeds (default: as many as fit in the time).
//
// Exits 0 when every input ran; an input that throws out of the target ends the run with the seed
// and mutation named, and a crash ends it as crashes do.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);
extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) __attribute__((weak));

namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<uint8_t>;

struct Seed {
  std::string name;
  Bytes bytes;
};

Bytes read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void collect(const fs::path& path, std::vector<Seed>& seeds) {
  if (fs::is_directory(path)) {
    std::vector<fs::path> files;
    for (const auto& entry : fs::recursive_directory_iterator(path)) {
      if (entry.is_regular_file()) files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    for (const auto& file : files) seeds.push_back({file.string(), read_file(file)});
  } else if (fs::is_regular_file(path)) {
    seeds.push_back({path.string(), read_file(path)});
  } else {
    std::fprintf(stderr, "smoke: %s: no such file or folder\n", path.c_str());
    std::exit(2);
  }
}

// One to four of libFuzzer's simpler mutations: bit flips, boundary bytes, truncation, erasure,
// repetition, random insertion, and a splice with another seed.
Bytes mutate(const Bytes& input, const std::vector<Seed>& seeds, std::mt19937_64& rng) {
  Bytes out = input;
  const auto pick = [&rng](std::size_t n) {
    return static_cast<std::size_t>(rng() % (n == 0 ? 1 : n));
  };
  const int steps = 1 + static_cast<int>(rng() % 4);
  for (int s = 0; s < steps; ++s) {
    switch (rng() % 7) {
      case 0:
        if (!out.empty()) out[pick(out.size())] ^= static_cast<uint8_t>(1u << (rng() % 8));
        break;
      case 1: {
        static constexpr uint8_t kBoundary[] = {0x00, 0x01, 0x7f, 0x80, 0xfe, 0xff};
        if (!out.empty()) out[pick(out.size())] = kBoundary[rng() % std::size(kBoundary)];
        break;
      }
      case 2:
        out.resize(pick(out.size() + 1));
        break;
      case 3: {
        const std::size_t at = pick(out.size() + 1);
        const std::size_t n = std::min(out.size() - std::min(at, out.size()), pick(64) + 1);
        out.erase(out.begin() + static_cast<std::ptrdiff_t>(at),
                  out.begin() + static_cast<std::ptrdiff_t>(at + n));
        break;
      }
      case 4: {
        if (out.empty()) break;
        const std::size_t at = pick(out.size());
        const std::size_t n = std::min(out.size() - at, pick(256) + 1);
        const Bytes chunk(out.begin() + static_cast<std::ptrdiff_t>(at),
                          out.begin() + static_cast<std::ptrdiff_t>(at + n));
        out.insert(out.begin() + static_cast<std::ptrdiff_t>(pick(out.size() + 1)), chunk.begin(),
                   chunk.end());
        break;
      }
      case 5: {
        const std::size_t n = pick(16) + 1;
        Bytes random(n);
        for (auto& b : random) b = static_cast<uint8_t>(rng());
        out.insert(out.begin() + static_cast<std::ptrdiff_t>(pick(out.size() + 1)), random.begin(),
                   random.end());
        break;
      }
      default: {
        const Bytes& other = seeds[pick(seeds.size())].bytes;
        const std::size_t keep = pick(out.size() + 1);
        const std::size_t from = pick(other.size() + 1);
        out.resize(keep);
        out.insert(out.end(), other.begin() + static_cast<std::ptrdiff_t>(from), other.end());
        break;
      }
    }
  }
  return out;
}

void run_one(const Bytes& input, const std::string& seed, long mutation) {
  try {
    LLVMFuzzerTestOneInput(input.data(), input.size());
  } catch (const std::exception& e) {
    std::ofstream("smoke-failure", std::ios::binary)
        .write(reinterpret_cast<const char*>(input.data()),
               static_cast<std::streamsize>(input.size()));
    std::fprintf(stderr,
                 "smoke: seed %s, mutation %ld: the target threw: %s (input kept in "
                 "./smoke-failure)\n",
                 seed.c_str(), mutation, e.what());
    std::exit(1);
  }
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 10;
  long mutations = std::numeric_limits<long>::max();
  std::vector<Seed> seeds;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--seconds" && i + 1 < argc) {
      seconds = std::stod(argv[++i]);
    } else if (arg == "--mutations" && i + 1 < argc) {
      mutations = std::stol(argv[++i]);
    } else {
      collect(arg, seeds);
    }
  }
  if (LLVMFuzzerInitialize != nullptr) LLVMFuzzerInitialize(&argc, &argv);
  if (seeds.empty()) seeds.push_back({"(empty input)", {}});

  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  std::mt19937_64 rng(0x5eed);
  long runs = 0;
  for (const auto& seed : seeds) {
    run_one(seed.bytes, seed.name, -1);
    ++runs;
  }
  // Round-robin over the seeds, so a short time still reaches every one.
  for (long m = 0; m < mutations && std::chrono::steady_clock::now() < deadline; ++m) {
    for (const auto& seed : seeds) {
      run_one(mutate(seed.bytes, seeds, rng), seed.name, m);
      ++runs;
    }
  }
  std::printf("smoke: %ld inputs from %zu seeds, no failure\n", runs, seeds.size());
  return 0;
}
