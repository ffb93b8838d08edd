#include <lz4frame.h>
// For ZSTD_decompressBound (zstd 1.4 and later).
#define ZSTD_STATIC_LINKING_ONLY
#include <zstd.h>

#include <algorithm>
#include <memory>

#include "mcap_format.hpp"

namespace robotperf::bag::mcap {
namespace {

// Output produced in pieces of this size: small enough to stay in the L2
// cache between being written and being checksummed.
constexpr std::size_t kPiece = 256 * 1024;

LZ4F_dctx* new_lz4_context() {
  LZ4F_dctx* ctx = nullptr;
  return LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)) ? nullptr : ctx;
}

// Output allocated up front for a zstd chunk, per compressed byte: far above what recorded data
// reaches (the synthetic images: 20), while a frame header's claim of more is only believed as
// the bytes come.
constexpr uint64_t kPlausibleRatio = 64;
// And never more than this before a byte is decoded, whatever the compressed size: a forged claim
// in a large bag must not make the reader touch gigabytes up front (recorded chunks are a few MiB).
constexpr uint64_t kMostUpFront = uint64_t{256} << 20;

// The compressed bytes given to zstd at a time when it decodes straight into the output: at the
// synthetic images' 20:1, about a piece of output.
constexpr std::size_t kInputSlice = kPiece / 16;

// Decodes zstd frames straight into `out`, sized to the claim already (zstd's streaming otherwise
// decodes into a window of its own and copies from there), feeding the input a slice at a time so
// that each piece of output is checksummed while in cache. False when the frames do not come to
// exactly `out`; the caller then decodes again the other way, for its precise error.
bool zstd_into_sized_output(ZSTD_DCtx* ctx, std::span<const uint8_t> in, std::vector<uint8_t>& out,
                            uint32_t* crc) {
  if (ZSTD_isError(ZSTD_DCtx_setParameter(ctx, ZSTD_d_stableOutBuffer, 1))) return false;
  ZSTD_outBuffer output{out.data(), out.size(), 0};
  ZSTD_inBuffer input{in.data(), 0, 0};
  uint32_t running_crc = 0;
  std::size_t left = 0;
  do {
    const std::size_t produced = output.pos;
    const std::size_t consumed = input.pos;
    input.size = std::min(in.size(), input.size + kInputSlice);
    left = ZSTD_decompressStream(ctx, &output, &input);
    if (ZSTD_isError(left)) return false;
    if (crc != nullptr && output.pos > produced) {
      running_crc = crc32(std::span<const uint8_t>(out.data() + produced, output.pos - produced),
                          running_crc);
    }
    if (output.pos == produced && input.pos == consumed && input.size == in.size()) return false;
  } while (left != 0 || input.pos < in.size());
  if (output.pos != out.size()) return false;
  if (crc != nullptr) *crc = running_crc;
  return true;
}

// The most `in` can decompress to. zstd frames say it in their headers: no fixed ratio bounds
// them (a run of zero bytes compresses about 32000:1), and a header can lie, which only decoding
// finds out. lz4 expands at most about 255x per input byte; an unknown codec, refused later, gets
// the same allowance.
uint64_t most_decompressed(const std::string& compression, std::span<const uint8_t> in) {
  if (compression != "zstd") return (in.size() + 64) * 256;
  const unsigned long long bound = ZSTD_decompressBound(in.data(), in.size());
  if (bound == ZSTD_CONTENTSIZE_ERROR)
    throw FormatError("zstd: not whole zstd frames (cut short?)");
  return bound;
}

}  // namespace

void decompress(const std::string& compression, std::span<const uint8_t> in,
                uint64_t uncompressed_size, std::vector<uint8_t>& out, uint32_t* crc) {
  // A forged uncompressed_size must not make us allocate without bound. What zstd frame headers
  // claim is not allocated either: zstd output grows as it comes.
  if (!compression.empty() && uncompressed_size > most_decompressed(compression, in)) {
    throw FormatError("chunk claims " + std::to_string(uncompressed_size) +
                      " uncompressed bytes from " + std::to_string(in.size()) +
                      " compressed ones, more than they can hold; corrupt");
  }
  if (compression.empty()) {
    if (in.size() != uncompressed_size) {
      throw FormatError("uncompressed chunk holds " + std::to_string(in.size()) +
                        " bytes but declares " + std::to_string(uncompressed_size));
    }
    out.assign(in.begin(), in.end());
    if (crc != nullptr) *crc = crc32(out);
    return;
  }
  uint32_t running_crc = 0;
  auto produced = [&](std::size_t from, std::size_t to) {
    if (crc != nullptr && to > from)
      running_crc = crc32(std::span<const uint8_t>(out.data() + from, to - from), running_crc);
  };
  if (compression == "zstd") {
    // One context per thread, reused: a fresh one per chunk costs an allocation and its setup.
    thread_local const std::unique_ptr<ZSTD_DCtx, decltype(&ZSTD_freeDCtx)> context(
        ZSTD_createDCtx(), &ZSTD_freeDCtx);
    if (!context) throw FormatError("cannot create a zstd decompression context");
    ZSTD_DCtx* ctx = context.get();
    // A chunk that failed may have left it mid-frame.
    ZSTD_DCtx_reset(ctx, ZSTD_reset_session_only);
    // Sized to the claim at once when that needs no allocation (an output reused from an earlier
    // chunk) or a plausible one: growing it piece by piece costs a copy and fresh pages each time.
    if (out.capacity() >= uncompressed_size ||
        (uncompressed_size <= kPlausibleRatio * in.size() && uncompressed_size <= kMostUpFront)) {
      out.resize(static_cast<std::size_t>(uncompressed_size));
      if (zstd_into_sized_output(ctx, in, out, crc)) return;
      ZSTD_DCtx_reset(ctx, ZSTD_reset_session_only);
    }
    ZSTD_DCtx_setParameter(ctx, ZSTD_d_stableOutBuffer, 0);
    // Streamed into an output that grows as the bytes come: a frame header may claim gigabytes
    // that its blocks never hold, and zstd finds that out only at the frame's end. A piece at a
    // time, so that each is checksummed while still in cache. The output is reused from the last
    // chunk as far as it goes.
    out.resize(static_cast<std::size_t>(
        std::min<uint64_t>(uncompressed_size, std::max(out.size(), kPiece))));
    ZSTD_inBuffer input{in.data(), in.size(), 0};
    std::size_t out_pos = 0;
    std::size_t left = 0;  // 0 when the frames read so far are whole
    do {
      if (out_pos == out.size() && out_pos < uncompressed_size)
        out.resize(static_cast<std::size_t>(std::min<uint64_t>(uncompressed_size, 2 * out_pos)));
      ZSTD_outBuffer output{out.data(), std::min(out.size(), out_pos + kPiece), out_pos};
      const std::size_t in_pos = input.pos;
      left = ZSTD_decompressStream(ctx, &output, &input);
      if (ZSTD_isError(left)) throw FormatError(std::string("zstd: ") + ZSTD_getErrorName(left));
      produced(out_pos, output.pos);
      const bool progress = output.pos != out_pos || input.pos != in_pos;
      out_pos = output.pos;
      // No progress: the input ends inside a frame, or the output is as large as the chunk
      // claims and the frames hold more.
      if (!progress) break;
    } while (left != 0 || input.pos < input.size);
    if (left != 0 || out_pos != uncompressed_size) {
      const std::string claimed = " the " + std::to_string(uncompressed_size) + " bytes claimed";
      throw FormatError(
          left == 0 ? "zstd frames hold " + std::to_string(out_pos) + " bytes, not" + claimed
          : out_pos == uncompressed_size ? "zstd frames hold more than" + claimed
                                         : "zstd frames end after " + std::to_string(out_pos) +
                                               " of" + claimed + " (cut short?)");
    }
    if (crc != nullptr) *crc = running_crc;
    return;
  }
  if (compression == "lz4") {
    // One context per thread, reused like zstd's: a fresh one allocates its block buffers anew
    // for every chunk.
    thread_local const std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> context(
        new_lz4_context(), &LZ4F_freeDecompressionContext);
    if (!context) throw FormatError("cannot create an lz4 decompression context");
    LZ4F_dctx* ctx = context.get();
    LZ4F_resetDecompressionContext(ctx);  // a chunk that failed may have left it mid-frame
    out.resize(static_cast<std::size_t>(uncompressed_size));
    // The output stays where it is between calls: lz4 then decodes linked blocks against it
    // instead of first saving the last 64 KB of every piece in its own buffer.
    LZ4F_decompressOptions_t options{};
    options.stableDst = 1;
    std::size_t in_pos = 0;
    std::size_t out_pos = 0;
    std::size_t hint = 1;
    while (hint != 0 && in_pos < in.size()) {
      std::size_t src = in.size() - in_pos;
      std::size_t dst = std::min(out.size() - out_pos, kPiece);
      hint = LZ4F_decompress(ctx, out.data() + out_pos, &dst, in.data() + in_pos, &src, &options);
      if (LZ4F_isError(hint))
        throw FormatError(std::string("lz4 chunk does not decompress: ") + LZ4F_getErrorName(hint));
      produced(out_pos, out_pos + dst);
      in_pos += src;
      out_pos += dst;
      if (src == 0 && dst == 0) break;  // no progress: output full or input exhausted
    }
    if (hint != 0 || out_pos != uncompressed_size) {
      throw FormatError("lz4 chunk decompresses to " + std::to_string(out_pos) + " bytes, not " +
                        std::to_string(uncompressed_size) + (hint ? " (frame incomplete)" : ""));
    }
    if (crc != nullptr) *crc = running_crc;
    return;
  }
  throw FormatError("unknown compression '" + compression + "' (supported: zstd, lz4, none)");
}

void compress(const std::string& compression, std::span<const uint8_t> in,
              std::vector<uint8_t>& out) {
  if (compression == "zstd") {
    out.resize(ZSTD_compressBound(in.size()));
    // Level 1: rosbag2's own default favours recording speed too.
    const std::size_t n = ZSTD_compress(out.data(), out.size(), in.data(), in.size(), 1);
    if (ZSTD_isError(n)) throw FormatError(std::string("zstd: ") + ZSTD_getErrorName(n));
    out.resize(n);
    return;
  }
  if (compression == "lz4") {
    LZ4F_preferences_t prefs{};
    prefs.frameInfo.contentSize = in.size();
    out.resize(LZ4F_compressFrameBound(in.size(), &prefs));
    const std::size_t n = LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), &prefs);
    if (LZ4F_isError(n)) throw FormatError(std::string("lz4: ") + LZ4F_getErrorName(n));
    out.resize(n);
    return;
  }
  throw FormatError("unknown compression '" + compression + "' (supported: zstd, lz4, none)");
}

}  // namespace robotperf::bag::mcap
