// CTF 1.8 binary streams: packets (header, context, events), event headers
// with clock-value wrap-around, stream and event contexts, payloads.
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <map>
#include <optional>

#include "robotperf/tracing/ctf.hpp"

namespace robotperf::tracing::ctf {

namespace fs = std::filesystem;

struct Trace::Mapped {
  const uint8_t* data = nullptr;
  std::size_t size = 0;
  ~Mapped() {
    if (data != nullptr && size > 0) munmap(const_cast<uint8_t*>(data), size);
  }
};

namespace {

constexpr uint32_t kPacketMagic = 0xC1FC1FC1;

// Reads fields from a bit position in a mapped stream. Every read checks the
// packet's bounds, so a corrupt trace gives an error and never a wild read.
// A struct of byte-aligned scalars, strings and fixed arrays (every LTTng-UST
// payload and context), compiled once into a list of reads.
struct FlatOp {
  // kSkip steps over `count` bytes, kSkipString over a string: fields not selected, or integer
  // arrays (gids, uuids).
  enum Kind : uint8_t { kUnsigned, kSigned, kFloat, kString, kText, kSkip, kSkipString } kind;
  uint8_t bytes;        // scalars
  unsigned align_bits;  // >= 8
  uint64_t count;       // kText, kSkip: bytes
};
struct FlatLayout {
  std::vector<FlatOp> ops;
};

// Compiles `t` to a flat layout, or returns false when it needs the general
// decoder (bit fields, big-endian data, sequences, variants, nested structs). Fields for which
// `wanted` is false are stepped over.
bool compile_flat(const Type& t, bool trace_big_endian,
                  const std::function<bool(std::size_t)>& wanted, FlatLayout& out) {
  if (t.kind != Kind::kStruct || trace_big_endian || std::endian::native != std::endian::little)
    return false;
  auto little = [](const Type& x) { return x.byte_order != ByteOrder::kBig; };
  for (std::size_t i = 0; i < t.fields.size(); ++i) {
    const Type& ft = *t.fields[i].type;
    const unsigned align = std::max(8u, ft.align_bits);
    const bool skip = wanted && !wanted(i);
    if (ft.align_bits % 8 != 0 && ft.align_bits != 1) return false;
    switch (ft.kind) {
      case Kind::kInteger:
      case Kind::kEnum:
        if (ft.size_bits % 8 != 0 || ft.align_bits < 8 || !little(ft) || ft.maps_clock)
          return false;
        if (skip) {
          out.ops.push_back({FlatOp::kSkip, 0, align, ft.size_bits / 8});
        } else {
          out.ops.push_back({ft.is_signed ? FlatOp::kSigned : FlatOp::kUnsigned,
                             static_cast<uint8_t>(ft.size_bits / 8), align, 0});
        }
        break;
      case Kind::kFloat:
        if (!little(ft) || ft.align_bits < 8 || ft.size_bits % 8 != 0) return false;
        out.ops.push_back({skip ? FlatOp::kSkip : FlatOp::kFloat,
                           static_cast<uint8_t>(skip ? 0 : ft.size_bits / 8), align,
                           skip ? ft.size_bits / 8 : 0});
        break;
      case Kind::kString:
        out.ops.push_back({skip ? FlatOp::kSkipString : FlatOp::kString, 0, 8, 0});
        break;
      case Kind::kArray: {
        const Type& e = *ft.element;
        // A length whose count of bytes overflows is left to the general decoder, which
        // refuses it.
        if (e.kind != Kind::kInteger || e.size_bits % 8 != 0 || e.align_bits > e.size_bits ||
            e.align_bits < 8 || ft.length > UINT64_MAX / (e.size_bits / 8))
          return false;
        out.ops.push_back({e.is_text && !skip ? FlatOp::kText : FlatOp::kSkip, 0,
                           std::max(8u, e.align_bits), ft.length * (e.size_bits / 8)});
        break;
      }
      default:
        return false;
    }
  }
  return true;
}

enum class HeaderShape { kGeneral, kCompact, kLarge };

// Whether a stream's event header is one of LTTng's two, laid out exactly as LTTng writes them.
HeaderShape header_shape(const Type& h, bool trace_big_endian) {
  if (trace_big_endian || std::endian::native != std::endian::little) return HeaderShape::kGeneral;
  if (h.kind != Kind::kStruct || h.fields.size() != 2 || h.align_bits != 8)
    return HeaderShape::kGeneral;
  const Type& id = *h.fields[0].type;
  const Type& v = *h.fields[1].type;
  if (h.fields[0].name != "id" || id.kind != Kind::kEnum || v.kind != Kind::kVariant ||
      v.tag_sibling != 0 || v.fields.size() != 2 || id.byte_order == ByteOrder::kBig)
    return HeaderShape::kGeneral;
  const unsigned id_bits = id.size_bits;
  const unsigned ts_bits = id_bits == 5 ? 27 : 32;
  if (!(id_bits == 5 || id_bits == 16)) return HeaderShape::kGeneral;
  const uint64_t extended = id_bits == 5 ? 31 : 65535;
  // The enum maps 0 .. extended-1 to "compact" and extended to "extended".
  int compact_option = -1, extended_option = -1;
  for (std::size_t m = 0; m < id.mappings.size(); ++m) {
    const auto& mp = id.mappings[m];
    if (mp.low == 0 && mp.high == static_cast<int64_t>(extended - 1))
      compact_option = v.option_of_mapping[m];
    if (mp.low == static_cast<int64_t>(extended) && mp.high == mp.low)
      extended_option = v.option_of_mapping[m];
  }
  if (compact_option < 0 || extended_option < 0) return HeaderShape::kGeneral;
  const Type& c = *v.fields[static_cast<std::size_t>(compact_option)].type;
  const Type& e = *v.fields[static_cast<std::size_t>(extended_option)].type;
  auto is_int = [](const Type& t, unsigned bits, bool clock) {
    return (t.kind == Kind::kInteger) && t.size_bits == bits && t.maps_clock == clock &&
           t.byte_order != ByteOrder::kBig && !t.is_signed;
  };
  if (c.kind != Kind::kStruct || c.fields.size() != 1 || !is_int(*c.fields[0].type, ts_bits, true))
    return HeaderShape::kGeneral;
  if (id_bits == 5 && c.fields[0].type->align_bits != 1) return HeaderShape::kGeneral;
  if (id_bits == 16 && (c.fields[0].type->align_bits != 8 || id.align_bits != 8))
    return HeaderShape::kGeneral;
  if (e.kind != Kind::kStruct || e.fields.size() != 2 || e.fields[0].name != "id" ||
      !is_int(*e.fields[0].type, 32, false) || e.fields[0].type->align_bits != 8 ||
      !is_int(*e.fields[1].type, 64, true) || e.fields[1].type->align_bits != 8)
    return HeaderShape::kGeneral;
  return id_bits == 5 ? HeaderShape::kCompact : HeaderShape::kLarge;
}

// Where the first NUL byte lies in [p, p + left), or `left` when there is none. Trace strings are
// mostly names, topics and process names a few words long: their first words are tested here,
// eight bytes at a time, before a call to memchr for the rest.
std::size_t nul_offset(const uint8_t* p, std::size_t left) {
  constexpr uint64_t kOnes = 0x0101010101010101ull, kHighs = 0x8080808080808080ull;
  std::size_t len = 0;
  if constexpr (std::endian::native == std::endian::little) {
    for (; len + 8 <= left && len < 64; len += 8) {
      uint64_t word;
      std::memcpy(&word, p + len, 8);
      // The lowest flagged byte is the first zero byte: flags above a zero byte can be false,
      // below it never are.
      if (const uint64_t zero = (word - kOnes) & ~word & kHighs; zero != 0)
        return len + static_cast<std::size_t>(std::countr_zero(zero)) / 8;
    }
  }
  const void* nul = std::memchr(p + len, 0, left - len);
  return nul != nullptr ? static_cast<std::size_t>(static_cast<const uint8_t*>(nul) - p) : left;
}

// An unsigned integer of `bytes` bytes (1..8) stored little-endian on a little-endian host. The
// usual sizes are loads of their own: a copy of a variable size compiles to a string move, which
// costs more than the rest of a field's decoding.
uint64_t load_little(const uint8_t* p, unsigned bytes) {
  switch (bytes) {
    case 1:
      return *p;
    case 2: {
      uint16_t x;
      std::memcpy(&x, p, 2);
      return x;
    }
    case 4: {
      uint32_t x;
      std::memcpy(&x, p, 4);
      return x;
    }
    case 8: {
      uint64_t x;
      std::memcpy(&x, p, 8);
      return x;
    }
    default: {
      uint64_t x = 0;
      std::memcpy(&x, p, bytes);
      return x;
    }
  }
}

class Decoder {
 public:
  Decoder(const uint8_t* data, uint64_t end_bits, bool trace_big_endian, const std::string& file)
      : data_(data), end_bits_(end_bits), trace_be_(trace_big_endian), file_(file) {}

  uint64_t pos() const { return pos_; }
  void seek(uint64_t bits) { pos_ = bits; }
  void set_end(uint64_t bits) { end_bits_ = bits; }
  uint64_t clock() const { return clock_; }
  void set_clock(uint64_t value) { clock_ = value; }
  void set_clock_updates(bool on) { clock_updates_ = on; }

  [[noreturn]] void fail(const std::string& what) const {
    throw CtfError(file_ + ": " + what + " at byte " + std::to_string(pos_ / 8));
  }

  void align(unsigned bits) {
    if (bits > 1) pos_ = (pos_ + bits - 1) & ~static_cast<uint64_t>(bits - 1);
  }

  uint64_t read_bits(const Type& t) {
    align(t.align_bits);
    const unsigned n = t.size_bits;
    if (pos_ + n > end_bits_) fail("event runs past the end of its packet");
    const bool be =
        t.byte_order == ByteOrder::kNative ? trace_be_ : t.byte_order == ByteOrder::kBig;
    uint64_t v;
    if ((pos_ & 7) == 0 && (n & 7) == 0) {
      const uint8_t* p = data_ + pos_ / 8;
      switch (n) {
        case 8:
          v = *p;
          break;
        case 16: {
          uint16_t x;
          std::memcpy(&x, p, 2);
          v = be ? __builtin_bswap16(x) : x;
          break;
        }
        case 32: {
          uint32_t x;
          std::memcpy(&x, p, 4);
          v = be ? __builtin_bswap32(x) : x;
          break;
        }
        case 64: {
          uint64_t x;
          std::memcpy(&x, p, 8);
          v = be ? __builtin_bswap64(x) : x;
          break;
        }
        default:
          v = read_unaligned(n, be);
      }
    } else {
      v = read_unaligned(n, be);
    }
    pos_ += n;
    if (t.maps_clock && clock_updates_) update_clock(v, n);
    return v;
  }

  // CTF clock update: an n-bit value holds the low bits of the clock; a value
  // below the current low bits means the low bits wrapped once.
  void update_clock(uint64_t v, unsigned n) {
    if (n >= 64) {
      clock_ = v;
      return;
    }
    const uint64_t mask = (uint64_t{1} << n) - 1;
    uint64_t next = (clock_ & ~mask) | v;
    if (v < (clock_ & mask)) next += uint64_t{1} << n;
    clock_ = next;
  }

  static Value value_of(const Type& t, uint64_t bits) {
    Value out;
    if (t.is_signed) {
      if (t.size_bits < 64 && (bits >> (t.size_bits - 1)) & 1) bits |= ~uint64_t{0} << t.size_bits;
      out.tag = Value::Tag::kSigned;
    } else {
      out.tag = Value::Tag::kUnsigned;
    }
    out.u = bits;
    return out;
  }

  std::string_view read_string() {
    align(8);
    const uint64_t start = pos_ / 8, end = end_bits_ / 8;
    const std::size_t left = end > start ? end - start : 0;
    const std::size_t len = nul_offset(data_ + start, left);
    if (len == left) fail("unterminated string");
    pos_ = (start + len + 1) * 8;
    return {reinterpret_cast<const char*>(data_ + start), len};
  }

  // Steps over `count` items of `item_bits` (1 or more) bits each. The count comes from the trace:
  // it is compared with what is left of the packet before it is multiplied, so that no product
  // wraps around and moves the reader backwards.
  void skip(uint64_t count, uint64_t item_bits, const char* what) {
    const uint64_t left = end_bits_ > pos_ ? end_bits_ - pos_ : 0;
    if (count > left / item_bits) fail(std::string(what) + " runs past the end of its packet");
    pos_ += count * item_bits;
  }

  // Text stored as a fixed array or a sequence of 8-bit characters: up to the first NUL.
  std::string_view read_text(uint64_t count) {
    align(8);
    const uint64_t start = pos_ / 8;
    skip(count, 8, "text");
    const uint8_t* p = data_ + start;
    return {reinterpret_cast<const char*>(p), nul_offset(p, count)};
  }

  // Decodes one value of type t. `siblings` holds the integer values of the
  // enclosing struct's earlier fields (for variant tags and sequence lengths).
  // Header decoding records fields named "id" in *id_out.
  Value decode(const Type& t, uint64_t* id_out, bool is_id_field) {
    switch (t.kind) {
      case Kind::kInteger:
      case Kind::kEnum: {
        const uint64_t bits = read_bits(t);
        if (is_id_field && id_out != nullptr) *id_out = bits;
        return value_of(t, bits);
      }
      case Kind::kFloat: {
        const uint64_t bits = read_bits(t);
        Value out;
        out.tag = Value::Tag::kFloat;
        out.f = t.size_bits == 32
                    ? static_cast<double>(std::bit_cast<float>(static_cast<uint32_t>(bits)))
                    : std::bit_cast<double>(bits);
        return out;
      }
      case Kind::kString: {
        Value out;
        out.tag = Value::Tag::kString;
        out.s = read_string();
        return out;
      }
      case Kind::kStruct:
        decode_struct(t, nullptr, id_out);
        return {};
      case Kind::kArray:
        return decode_array(t, t.length, id_out);
      case Kind::kSequence:
      case Kind::kVariant:
        fail("a sequence or variant outside a struct");
    }
    return {};
  }

  Value decode_array(const Type& t, uint64_t count, uint64_t* id_out) {
    const Type& e = *t.element;
    if (e.kind == Kind::kInteger && e.is_text) {
      Value out;
      out.tag = Value::Tag::kString;
      out.s = read_text(count);
      return out;
    }
    if (e.kind == Kind::kInteger && (e.size_bits % 8) == 0 && e.align_bits <= e.size_bits) {
      // Plain integer arrays (gids, uuids): skip in one step.
      align(t.align_bits);
      skip(count, e.size_bits, "array");
      return {};
    }
    align(t.align_bits);
    for (uint64_t i = 0; i < count; ++i) {
      // Elements that take no bits (empty structs) would be decoded `count` times, up to 2^64.
      const uint64_t before = pos_;
      decode(e, id_out, false);
      if (pos_ == before) fail("array of elements that take no bits");
    }
    return {};
  }

  // Decodes a struct; when `out` is given, stores its top-level values there.
  void decode_struct(const Type& t, std::vector<Value>* out, uint64_t* id_out) {
    align(t.align_bits);
    const std::size_t n = t.fields.size();
    // Sibling values for tags and lengths; structs are small.
    uint64_t local[32];
    std::vector<uint64_t> big;
    uint64_t* sib = local;
    if (n > 32) {
      big.resize(n);
      sib = big.data();
    }
    for (std::size_t i = 0; i < n; ++i) {
      const Field& f = t.fields[i];
      const Type& ft = *f.type;
      Value v;
      if (ft.kind == Kind::kVariant) {
        if (ft.tag_sibling < 0) fail("variant tag '" + ft.variant_tag + "' is not resolved");
        v = decode_variant(ft, sib, *t.fields[static_cast<std::size_t>(ft.tag_sibling)].type,
                           id_out);
      } else if (ft.kind == Kind::kSequence) {
        if (ft.length_sibling < 0 || static_cast<std::size_t>(ft.length_sibling) >= i)
          fail("sequence length '" + ft.length_field + "' is not an earlier field");
        v = decode_array(ft, sib[ft.length_sibling], id_out);
      } else {
        v = decode(ft, id_out, id_out != nullptr && f.name == "id");
      }
      sib[i] = v.u;
      if (out != nullptr) out->push_back(v);
    }
  }

  // Decodes a struct compiled to a flat layout (see FlatLayout) into out[0..n).
  void decode_flat(const FlatLayout& layout, Value* out) {
    for (std::size_t i = 0; i < layout.ops.size(); ++i) {
      const FlatOp& op = layout.ops[i];
      pos_ = (pos_ + op.align_bits - 1) & ~static_cast<uint64_t>(op.align_bits - 1);
      const uint64_t start = pos_ / 8;
      Value& v = out[i];
      switch (op.kind) {
        case FlatOp::kUnsigned:
        case FlatOp::kSigned:
        case FlatOp::kFloat: {
          if (pos_ + op.bytes * 8 > end_bits_) fail("event runs past the end of its packet");
          const uint64_t bits = load_little(data_ + start, op.bytes);
          pos_ += op.bytes * 8;
          if (op.kind == FlatOp::kFloat) {
            v.tag = Value::Tag::kFloat;
            v.f = op.bytes == 4
                      ? static_cast<double>(std::bit_cast<float>(static_cast<uint32_t>(bits)))
                      : std::bit_cast<double>(bits);
          } else if (op.kind == FlatOp::kSigned) {
            const unsigned n = op.bytes * 8;
            v.tag = Value::Tag::kSigned;
            v.u = n < 64 && ((bits >> (n - 1)) & 1) ? bits | ~uint64_t{0} << n : bits;
          } else {
            v.tag = Value::Tag::kUnsigned;
            v.u = bits;
          }
          break;
        }
        case FlatOp::kString:
          v.tag = Value::Tag::kString;
          v.s = read_string();
          break;
        case FlatOp::kText:
          v.tag = Value::Tag::kString;
          v.s = read_text(op.count);
          break;
        case FlatOp::kSkip:
          skip(op.count, 8, "event");
          v.tag = Value::Tag::kNone;
          v.u = 0;
          break;
        case FlatOp::kSkipString:
          read_string();
          v.tag = Value::Tag::kNone;
          v.u = 0;
          break;
      }
    }
  }

  // LTTng's compact (5-bit id, 27-bit time) and large (16-bit id, 32-bit time)
  // event headers, each with an extended form (32-bit id, 64-bit time).
  uint64_t decode_lttng_header(HeaderShape shape) {
    pos_ = (pos_ + 7) & ~uint64_t{7};
    const uint8_t* p = data_ + pos_ / 8;
    const uint64_t left = end_bits_ > pos_ ? (end_bits_ - pos_) / 8 : 0;
    auto need = [&](uint64_t bytes) {
      if (left < bytes) fail("event header runs past the end of its packet");
    };
    uint64_t id;
    if (shape == HeaderShape::kCompact) {
      need(1);
      id = p[0] & 31u;
      if (id != 31) {
        need(4);
        uint32_t word;
        std::memcpy(&word, p, 4);
        update_clock(word >> 5, 27);
        pos_ += 32;
        return id;
      }
      p += 1;
      pos_ += 8;
      need(13);
    } else {
      need(2);
      uint16_t id16;
      std::memcpy(&id16, p, 2);
      id = id16;
      if (id != 65535) {
        need(6);
        uint32_t ts;
        std::memcpy(&ts, p + 2, 4);
        update_clock(ts, 32);
        pos_ += 48;
        return id;
      }
      p += 2;
      pos_ += 16;
      need(14);
    }
    uint32_t id32;
    uint64_t ts;
    std::memcpy(&id32, p, 4);
    std::memcpy(&ts, p + 4, 8);
    clock_ = ts;
    pos_ += 96;
    return id32;
  }

  // The option of variant t selected by the value of its tag, an enum of type tag_type.
  Value decode_variant(const Type& t, const uint64_t* siblings, const Type& tag_type,
                       uint64_t* id_out) {
    const auto tag = static_cast<int64_t>(siblings[t.tag_sibling]);
    int option = -1;
    for (std::size_t m = 0; m < tag_type.mappings.size(); ++m) {
      const auto& mp = tag_type.mappings[m];
      if (tag >= mp.low && tag <= mp.high) {
        option = t.option_of_mapping[m];
        break;
      }
    }
    if (option < 0) fail("variant tag value " + std::to_string(tag) + " selects no option");
    const Type& ot = *t.fields[static_cast<std::size_t>(option)].type;
    if (ot.kind == Kind::kStruct) {
      decode_struct(ot, nullptr, id_out);
      return {};
    }
    return decode(ot, id_out,
                  id_out != nullptr && t.fields[static_cast<std::size_t>(option)].name == "id");
  }

 private:
  uint64_t read_unaligned(unsigned n, bool be) {
    uint64_t v = 0;
    if (!be) {
      // Little-endian bit order: bit k of the field is bit (pos+k) counted from
      // each byte's least significant bit.
      for (unsigned k = 0; k < n;) {
        const uint64_t bit = pos_ + k;
        const unsigned in_byte = bit & 7;
        const unsigned take = std::min(8 - in_byte, n - k);
        const uint64_t byte = data_[bit / 8];
        v |= ((byte >> in_byte) & ((1u << take) - 1)) << k;
        k += take;
      }
    } else {
      for (unsigned k = 0; k < n;) {
        const uint64_t bit = pos_ + k;
        const unsigned in_byte = bit & 7;
        const unsigned take = std::min(8 - in_byte, n - k);
        const uint64_t byte = data_[bit / 8];
        v = (v << take) | ((byte >> (8 - in_byte - take)) & ((1u << take) - 1));
        k += take;
      }
    }
    return v;
  }

  const uint8_t* data_;
  uint64_t pos_ = 0;
  uint64_t end_bits_;
  bool trace_be_;
  const std::string& file_;
  uint64_t clock_ = 0;
  bool clock_updates_ = true;
};

constexpr uint64_t kNsPerSecond = 1'000'000'000;

// The frequency of the clock the event times count in. Times are read as integers mapped to a
// clock, without the clock's name: a trace whose clocks run at different frequencies is refused.
uint64_t clock_freq(const Metadata& md, const fs::path& dir) {
  if (md.clocks.empty()) return kNsPerSecond;
  for (const ClockClass& c : md.clocks) {
    if (c.freq != md.clocks.front().freq) {
      throw CtfError(dir.string() + "/metadata: clocks '" + md.clocks.front().name + "' (" +
                     std::to_string(md.clocks.front().freq) + " Hz) and '" + c.name + "' (" +
                     std::to_string(c.freq) + " Hz) differ in frequency");
    }
  }
  return md.clocks.front().freq;
}

// Whether the trace's tracer is one that wrote events after their packet's timestamp_end:
// LTTng-UST before 2.11.0, LTTng-modules before 2.9.13, 2.10.10 and 2.11.0. Versions are read as
// babeltrace2 reads them: a missing minor or patch number counts as 0, a missing major as no
// version at all.
bool writes_events_after_packet_end(const Metadata& md) {
  auto number = [&](std::string_view key) -> std::optional<int64_t> {
    const std::string text = md.env_value(key);
    int64_t n = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
    if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
    return n;
  };
  const std::string tracer = md.env_value("tracer_name");
  const std::optional<int64_t> major = number("tracer_major");
  if (!major) return false;
  const int64_t minor = number("tracer_minor").value_or(0);
  const int64_t patch = number("tracer_patch").value_or(number("tracer_patchlevel").value_or(0));
  if (tracer == "lttng-ust") return *major < 2 || (*major == 2 && minor < 11);
  if (tracer == "lttng-modules") {
    return *major < 2 || (*major == 2 &&
                          (minor < 9 || (minor == 9 && patch < 13) || (minor == 10 && patch < 10)));
  }
  return false;
}

// A time of the trace's clock for a message: seconds with every digit of a nanosecond clock.
std::string clock_text(uint64_t cycles, uint64_t freq) {
  const auto fraction =
      static_cast<uint64_t>(static_cast<unsigned __int128>(cycles % freq) * kNsPerSecond / freq);
  char text[48];
  std::snprintf(text, sizeof text, "%" PRIu64 ".%09" PRIu64 " s", cycles / freq, fraction);
  return text;
}

// Marks the packets of one stream whose own times are out of order, and sets each packet's
// timestamp_end to the latest time its events may have (`known_end`: whether its timestamp_end
// can be trusted; if not, the next packet's begin bounds its events). A packet that begins after
// its end is defective; so are both packets of a pair where the later one begins before the end
// of the one before it that is left in (which of the two holds the wrong time cannot be told).
// Every packet left in then begins at or after the end of each one before it: with the events
// inside their packets' times, none goes back from one packet to the next.
void check_packet_times(std::vector<Packet>& packets, const std::vector<bool>& known_end,
                        uint64_t freq, const std::string& file) {
  auto byte = [](const Packet& p) { return std::to_string(p.start_bits / 8); };
  auto mark = [&](Packet& p, const std::string& what) {
    if (p.defect.empty()) p.defect = file + ": packet at byte " + byte(p) + " " + what;
  };
  // A packet without a clock value continues the clock of the packet before it: its times are
  // unknown in a stream where others give theirs (LTTng writes it in every packet).
  const bool timed_stream =
      std::any_of(packets.begin(), packets.end(), [](const Packet& p) { return p.has_clock; });
  std::vector<std::size_t> timed;  // packets with a clock that do not begin after their end
  for (std::size_t i = 0; i < packets.size(); ++i) {
    Packet& p = packets[i];
    if (!p.has_clock) {
      if (timed_stream) mark(p, "has no timestamp_begin, unlike the other packets of its stream");
      continue;
    }
    if (known_end[i] && p.timestamp_begin > p.timestamp_end) {
      mark(p, "begins at " + clock_text(p.timestamp_begin, freq) + ", after its end at " +
                  clock_text(p.timestamp_end, freq));
      continue;
    }
    if (!known_end[i]) p.timestamp_end = UINT64_MAX;
    if (!timed.empty() && !known_end[timed.back()])
      packets[timed.back()].timestamp_end = p.timestamp_begin;
    timed.push_back(i);
  }
  std::vector<std::size_t> kept;
  for (const std::size_t i : timed) {
    Packet& p = packets[i];
    if (!kept.empty() && p.timestamp_begin < packets[kept.back()].timestamp_end) {
      Packet& before = packets[kept.back()];
      const std::string ends = (known_end[kept.back()] ? "ends at " : "runs to ") +
                               clock_text(before.timestamp_end, freq);
      mark(before, ends + ", after the packet at byte " + byte(p) + " begins at " +
                       clock_text(p.timestamp_begin, freq));
      mark(p, "begins at " + clock_text(p.timestamp_begin, freq) + ", before the packet at byte " +
                  byte(before) + " " + ends);
      kept.pop_back();
      continue;
    }
    kept.push_back(i);
  }
}

int index_of(const TypePtr& t, std::string_view name) {
  if (!t) return -1;
  for (std::size_t i = 0; i < t->fields.size(); ++i) {
    if (t->fields[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace

Trace::Trace(const fs::path& dir) : dir_(dir) {
  metadata_ = read_metadata(dir / "metadata");
  clock_freq_ = clock_freq(metadata_, dir);
  events_after_packet_end_ = writes_events_after_packet_end(metadata_);
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file()) continue;
    const std::string name = entry.path().filename().string();
    if (name == "metadata" || name.starts_with(".")) continue;
    stream_files_.push_back(entry.path());
  }
  if (ec) throw CtfError("cannot list " + dir.string() + ": " + ec.message());
  std::sort(stream_files_.begin(), stream_files_.end());
  for (const auto& file : stream_files_) {
    auto m = std::make_unique<Mapped>();
    const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw CtfError("cannot open " + file.string());
    struct stat st {};
    if (fstat(fd, &st) != 0) {
      ::close(fd);
      throw CtfError("cannot stat " + file.string());
    }
    m->size = static_cast<std::size_t>(st.st_size);
    if (m->size > 0) {
      void* p = mmap(nullptr, m->size, PROT_READ, MAP_PRIVATE, fd, 0);
      if (p == MAP_FAILED) {
        ::close(fd);
        throw CtfError("cannot map " + file.string());
      }
      madvise(p, m->size, MADV_SEQUENTIAL);
      m->data = static_cast<const uint8_t*>(p);
    }
    ::close(fd);
    mapped_.push_back(std::move(m));
  }
}

Trace::~Trace() = default;
Trace::Trace(Trace&&) noexcept = default;
Trace& Trace::operator=(Trace&&) noexcept = default;

std::size_t Trace::total_bytes() const {
  std::size_t n = 0;
  for (const auto& m : mapped_) n += m->size;
  return n;
}

int Trace::stream_context_index(uint64_t stream_id, std::string_view name) const {
  const StreamClass* sc = metadata_.stream(stream_id);
  return sc ? index_of(sc->event_context, name) : -1;
}

StreamStats Trace::read_stream(std::size_t index,
                               const std::function<void(const Event&)>& on_event) {
  StreamIndex i = index_stream(index);
  // The first pass marks the defective packets, whose events the second leaves out.
  read_packets(index, i.packets, [](const Event&) {});
  i.stats.events = read_packets(index, i.packets, on_event).events;
  return i.stats;
}

StreamIndex Trace::index_stream(std::size_t index) const {
  const Mapped& m = *mapped_.at(index);
  StreamIndex out;
  out.stats.file = stream_files_[index].string();
  if (m.size == 0) return out;
  const Metadata& md = metadata_;
  Decoder d(m.data, m.size * 8, md.big_endian, out.stats.file);
  d.set_clock_updates(false);
  std::vector<Value> header_values, context_values;
  const int magic = md.packet_header ? index_of(md.packet_header, "magic") : -1;
  const int sid = md.packet_header ? index_of(md.packet_header, "stream_id") : -1;
  uint64_t last_discarded = 0;
  bool have_seq = false;
  uint64_t last_seq = 0;
  std::vector<bool> known_end;
  const uint64_t file_bits = m.size * 8;
  uint64_t packet_start = 0;
  while (packet_start < file_bits) {
    d.set_end(file_bits);
    d.seek(packet_start);
    uint64_t stream_id = 0;
    if (md.packet_header) {
      header_values.clear();
      d.decode_struct(*md.packet_header, &header_values, nullptr);
      if (magic >= 0 && header_values[static_cast<std::size_t>(magic)].u != kPacketMagic)
        d.fail("bad packet magic (not a CTF stream, or corrupt)");
      if (sid >= 0) stream_id = header_values[static_cast<std::size_t>(sid)].u;
    }
    Packet p;
    p.stream_class = md.stream(stream_id);
    if (p.stream_class == nullptr) d.fail("unknown stream id " + std::to_string(stream_id));
    uint64_t content_bits = file_bits - packet_start, packet_bits = content_bits;
    bool end_known = false;
    if (const TypePtr& pc = p.stream_class->packet_context) {
      context_values.clear();
      d.decode_struct(*pc, &context_values, nullptr);
      auto get = [&](std::string_view name) -> const Value* {
        const int i = index_of(pc, name);
        return i >= 0 ? &context_values[static_cast<std::size_t>(i)] : nullptr;
      };
      if (const Value* v = get("content_size")) content_bits = v->u;
      if (const Value* v = get("packet_size")) packet_bits = v->u;
      if (const Value* v = get("timestamp_begin")) {
        p.has_clock = true;
        p.timestamp_begin = v->u;
      }
      const Value* end = get("timestamp_end");
      if (end != nullptr) p.timestamp_end = end->u;
      // A session that crashed leaves the end of its last packets 0 (babeltrace2's "LTTng crash
      // quirk"): their events are bounded by the next packet's begin instead.
      end_known =
          end != nullptr && !events_after_packet_end_ && !(end->u == 0 && p.timestamp_begin != 0);
      if (const Value* v = get("cpu_id")) p.cpu_id = static_cast<uint32_t>(v->u);
      if (const Value* v = get("events_discarded")) {
        // A running count per stream: what it gained since the previous packet.
        if (v->u >= last_discarded) out.stats.discarded_events += v->u - last_discarded;
        last_discarded = v->u;
      }
      if (const Value* v = get("packet_seq_num")) {
        if (have_seq && v->u > last_seq + 1) out.stats.lost_packets += v->u - last_seq - 1;
        have_seq = true;
        last_seq = v->u;
      }
    }
    // Compared with what is left of the file: a size near 2^64 would wrap packet_start + size
    // back to an earlier packet, and indexing would never end.
    if (packet_bits == 0 || content_bits > packet_bits || packet_bits > file_bits - packet_start)
      d.fail("packet size " + std::to_string(packet_bits / 8) + " bytes does not fit the file");
    p.start_bits = packet_start;
    p.events_bits = d.pos();
    p.content_end_bits = packet_start + content_bits;
    p.end_bits = packet_start + packet_bits;
    known_end.push_back(end_known);
    out.packets.push_back(p);
    packet_start += packet_bits;
  }
  out.stats.packets = out.packets.size();
  check_packet_times(out.packets, known_end, clock_freq_, out.stats.file);
  return out;
}

namespace {

// The packets' pages mapped in one call, on this thread: a page fault each 64 KiB costs
// microseconds in a virtual machine. Without MADV_POPULATE_READ (Linux < 5.14), faults map them.
void map_pages_of(const uint8_t* data, std::size_t size, std::span<const Packet> packets) {
  const auto page = static_cast<uint64_t>(sysconf(_SC_PAGESIZE));
  const uint64_t from = packets.front().start_bits / 8 / page * page;
  const uint64_t to = std::min<uint64_t>(packets.back().end_bits / 8, size);
  if (to > from) madvise(const_cast<uint8_t*>(data) + from, to - from, MADV_POPULATE_READ);
}

// Why an event at `cycles` cannot be where it is in packet `p`: after its end, before its begin,
// or before the event before it (at `earliest`).
std::string event_time_defect(const std::string& file, const Packet& p, const std::string& event,
                              uint64_t cycles, uint64_t earliest, uint64_t freq) {
  const std::string where = file + ": packet at byte " + std::to_string(p.start_bits / 8) +
                            ": event '" + event + "' at " + clock_text(cycles, freq);
  if (cycles > p.timestamp_end)
    return where + " is after the packet's end at " + clock_text(p.timestamp_end, freq);
  if (p.has_clock && cycles < p.timestamp_begin)
    return where + " is before the packet's begin at " + clock_text(p.timestamp_begin, freq);
  return where + " is before the event before it at " + clock_text(earliest, freq);
}

}  // namespace

PacketsRead Trace::read_packets(std::size_t index, std::span<Packet> packets,
                                const std::function<void(const Event&)>& on_event,
                                const FieldSelection* selection) const {
  const Mapped& m = *mapped_.at(index);
  PacketsRead read;
  if (m.size == 0 || packets.empty()) return read;
  map_pages_of(m.data, m.size, packets);
  const Metadata& md = metadata_;
  const std::string file = stream_files_[index].string();
  Decoder d(m.data, m.size * 8, md.big_endian, file);
  std::vector<Value> payload, event_context;
  // Layouts compiled on first use, per stream class and event class.
  struct Compiled {
    bool tried = false;
    bool flat = false;
    FlatLayout layout;
  };
  // Keyed by the type and the class that selects its fields (types may be shared).
  std::map<std::pair<const void*, const void*>, Compiled> compiled;
  auto layout_of = [&](const TypePtr& t, const void* selector,
                       const std::function<bool(std::size_t)>& wanted) -> const FlatLayout* {
    Compiled& c = compiled[{t.get(), selector}];
    if (!c.tried) {
      c.tried = true;
      c.flat = compile_flat(*t, md.big_endian, wanted, c.layout);
    }
    return c.flat ? &c.layout : nullptr;
  };
  // Payload layouts of the current stream class, by event id (compiled once).
  const StreamClass* layouts_for = nullptr;
  std::vector<const FlatLayout*> payload_layouts;
  std::vector<uint8_t> payload_flat;
  HeaderShape shape = HeaderShape::kGeneral;
  const FlatLayout* context_layout = nullptr;
  // Clock cycles to nanoseconds, which every reader of event times counts in (LTTng's clocks
  // count nanoseconds; LTTNG_UST_CLOCK_PLUGIN and other producers may not).
  const uint64_t freq = clock_freq_;
  auto ns_of = [&](uint64_t cycles) {
    if (freq == kNsPerSecond) return cycles;
    const unsigned __int128 ns = static_cast<unsigned __int128>(cycles) * kNsPerSecond / freq;
    if (ns > UINT64_MAX) d.fail("event time overflows 64 bits of nanoseconds");
    return static_cast<uint64_t>(ns);
  };

  // A packet without a clock of its own continues the one before it: after a defective packet,
  // its times are unknown (in a stream none of whose packets gives its clock).
  bool after_defect = false;
  for (Packet& p : packets) {
    if (p.defect.empty() && !p.has_clock && after_defect) {
      p.defect = file + ": packet at byte " + std::to_string(p.start_bits / 8) +
                 " has no clock value of its own and follows a defective packet";
      ++read.defective_packets;
    }
    after_defect = !p.defect.empty();
    if (after_defect) continue;
    const StreamClass* sc = p.stream_class;
    d.seek(p.events_bits);
    d.set_end(p.content_end_bits);
    if (p.has_clock) d.set_clock(p.timestamp_begin);
    d.set_clock_updates(true);
    // The time the next event may not be before: the packet's begin, then each event's time.
    uint64_t earliest = d.clock();
    if (layouts_for != sc) {
      layouts_for = sc;
      shape =
          sc->event_header ? header_shape(*sc->event_header, md.big_endian) : HeaderShape::kGeneral;
      std::function<bool(std::size_t)> context_wanted;
      if (selection != nullptr && selection->stream_context)
        context_wanted = [&](std::size_t f) { return selection->stream_context(*sc, f); };
      context_layout =
          sc->event_context ? layout_of(sc->event_context, sc, context_wanted) : nullptr;
      payload_layouts.assign(sc->events_by_id.size(), nullptr);
      payload_flat.assign(sc->events_by_id.size(), 0);
      for (std::size_t i = 0; i < sc->events_by_id.size(); ++i) {
        const EventClass* ec = sc->events_by_id[i];
        if (ec == nullptr || ec->context) continue;
        std::function<bool(std::size_t)> wanted;
        if (selection != nullptr && selection->payload)
          wanted = [&](std::size_t f) { return selection->payload(*ec, f); };
        payload_layouts[i] = ec->fields ? layout_of(ec->fields, ec, wanted) : nullptr;
        payload_flat[i] = !ec->fields || payload_layouts[i] != nullptr;
      }
      if (sc->event_context) event_context.resize(sc->event_context->fields.size());
    }

    while (true) {
      // Events end where the next header would not fit (trailing padding).
      if (d.pos() >= p.content_end_bits) break;
      const uint64_t event_start = d.pos();
      uint64_t id = 0;
      if (shape != HeaderShape::kGeneral) {
        id = d.decode_lttng_header(shape);
      } else if (sc->event_header) {
        d.decode_struct(*sc->event_header, nullptr, &id);
      }
      const EventClass* ec = id < sc->events_by_id.size() ? sc->events_by_id[id] : nullptr;
      if (ec == nullptr) d.fail("unknown event id " + std::to_string(id));
      if (context_layout != nullptr) {
        d.decode_flat(*context_layout, event_context.data());
      } else if (sc->event_context) {
        event_context.clear();
        d.decode_struct(*sc->event_context, &event_context, nullptr);
      }
      if (payload_flat[id]) {
        const FlatLayout* layout = payload_layouts[id];
        payload.resize(layout ? layout->ops.size() : 0);
        if (layout) d.decode_flat(*layout, payload.data());
      } else {
        if (ec->context) d.decode_struct(*ec->context, nullptr, nullptr);
        payload.clear();
        if (ec->fields) d.decode_struct(*ec->fields, &payload, nullptr);
      }
      // Metadata whose events have no header and no fields would make a packet of endless
      // events (found by fuzz_ctf_trace).
      if (d.pos() == event_start)
        d.fail("event '" + ec->name +
               "' takes no bits: its metadata gives it no header and no fields");
      // Checked in clock cycles, after the wrap of a compact time is applied: a corrupt time
      // shows as a step back or, read as a wrap, as a step past the packet's end.
      const uint64_t cycles = d.clock();
      if (cycles < earliest || cycles > p.timestamp_end) [[unlikely]] {
        p.defect = event_time_defect(file, p, ec->name, cycles, earliest, freq);
        ++read.defective_packets;
        after_defect = true;
        break;
      }
      earliest = cycles;
      Event ev;
      ev.cls = ec;
      ev.timestamp = ns_of(cycles);
      ev.cpu_id = p.cpu_id;
      ev.fields = payload;
      ev.stream_context = event_context;
      ++read.events;
      on_event(ev);
    }
  }
  return read;
}

std::vector<fs::path> find_traces(const fs::path& root) {
  std::vector<fs::path> out;
  std::error_code ec;
  if (!fs::is_directory(root, ec)) throw CtfError(root.string() + " is not a folder");
  if (fs::is_regular_file(root / "metadata")) out.push_back(root);
  for (auto it = fs::recursive_directory_iterator(root, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (it->is_directory() && fs::is_regular_file(it->path() / "metadata"))
      out.push_back(it->path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace robotperf::tracing::ctf
