#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include "mcap_format.hpp"

namespace robotperf::bag::mcap {

uint32_t crc32(std::span<const uint8_t> bytes, uint32_t crc) {
  // zlib's crc32 is the CRC-32 (ISO-HDLC) that MCAP specifies; feed it in
  // pieces below its 32-bit length limit.
  const uint8_t* p = bytes.data();
  std::size_t n = bytes.size();
  uLong c = crc;
  while (n > 0) {
    const auto piece = static_cast<uInt>(std::min<std::size_t>(n, 1u << 30));
    c = ::crc32(c, p, piece);
    p += piece;
    n -= piece;
  }
  return static_cast<uint32_t>(c);
}

void decompress(const std::string& compression, std::span<const uint8_t> in,
                uint64_t uncompressed_size, std::vector<uint8_t>& out) {
  // A forged uncompressed_size must not make us allocate without bound: no
  // supported codec expands more than about 255x (lz4) per input byte.
  if (compression != "" && uncompressed_size > (in.size() + 64) * 256) {
    throw FormatError("chunk claims " + std::to_string(uncompressed_size) +
                      " uncompressed bytes from " + std::to_string(in.size()) +
                      " compressed ones; corrupt");
  }
  if (compression.empty()) {
    if (in.size() != uncompressed_size) {
      throw FormatError("uncompressed chunk holds " + std::to_string(in.size()) +
                        " bytes but declares " + std::to_string(uncompressed_size));
    }
    out.assign(in.begin(), in.end());
    return;
  }
  out.resize(static_cast<std::size_t>(uncompressed_size));
  if (compression == "zstd") {
    const std::size_t n = ZSTD_decompress(out.data(), out.size(), in.data(), in.size());
    if (ZSTD_isError(n))
      throw FormatError(std::string("zstd chunk does not decompress: ") + ZSTD_getErrorName(n));
    if (n != uncompressed_size) {
      throw FormatError("zstd chunk decompresses to " + std::to_string(n) + " bytes, not " +
                        std::to_string(uncompressed_size));
    }
    return;
  }
  if (compression == "lz4") {
    LZ4F_dctx* ctx = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)))
      throw FormatError("cannot create an lz4 decompression context");
    std::size_t in_pos = 0;
    std::size_t out_pos = 0;
    std::size_t hint = 1;
    while (hint != 0 && in_pos < in.size()) {
      std::size_t src = in.size() - in_pos;
      std::size_t dst = out.size() - out_pos;
      hint = LZ4F_decompress(ctx, out.data() + out_pos, &dst, in.data() + in_pos, &src, nullptr);
      if (LZ4F_isError(hint)) {
        const std::string why = LZ4F_getErrorName(hint);
        LZ4F_freeDecompressionContext(ctx);
        throw FormatError("lz4 chunk does not decompress: " + why);
      }
      in_pos += src;
      out_pos += dst;
      if (src == 0 && dst == 0) break;  // no progress: output full or input exhausted
    }
    LZ4F_freeDecompressionContext(ctx);
    if (hint != 0 || out_pos != uncompressed_size) {
      throw FormatError("lz4 chunk decompresses to " + std::to_string(out_pos) + " bytes, not " +
                        std::to_string(uncompressed_size) + (hint ? " (frame incomplete)" : ""));
    }
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
