// CDR (XCDR1, little-endian) encoding as ROS 2 puts it on the wire and into bags.
//
// A message type describes its fields once, with `visit_fields(visitor, msg)`;
// the same description drives sizing (CdrSizer), writing (CdrWriter) and
// reading (CdrReader), so the three can never disagree.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace robotperf::msgs {

// The 4-byte encapsulation header: CDR_LE representation, options 0.
inline constexpr std::array<uint8_t, 4> kCdrLittleEndianHeader{0x00, 0x01, 0x00, 0x00};
inline constexpr std::size_t kEncapsulationSize = 4;

// Thrown when a payload is truncated, malformed or not little-endian CDR.
class CdrError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

template <class T>
concept CdrPrimitive = std::is_arithmetic_v<T>;

namespace detail {
constexpr std::size_t pad_to(std::size_t offset, std::size_t align) {
  return (align - offset % align) % align;
}
}  // namespace detail

// Computes the exact serialized size (encapsulation header included).
class CdrSizer {
 public:
  std::size_t size() const { return kEncapsulationSize + offset_; }

  template <CdrPrimitive T>
  void operator()(const T&) {
    offset_ += detail::pad_to(offset_, sizeof(T)) + sizeof(T);
  }
  void operator()(const std::string& s) {
    (*this)(uint32_t{});
    offset_ += s.size() + 1;
  }
  template <class T>
  void operator()(const std::vector<T>& seq) {
    (*this)(uint32_t{});
    elements(seq.data(), seq.size());
  }
  template <class T, std::size_t N>
  void operator()(const std::array<T, N>& arr) {
    elements(arr.data(), N);
  }
  template <class T>
  requires(!CdrPrimitive<T>) void operator()(const T& m) { visit_fields(*this, m); }

 private:
  template <class T>
  void elements(const T* data, std::size_t n) {
    if constexpr (CdrPrimitive<T>) {
      if (n == 0) return;
      offset_ += detail::pad_to(offset_, sizeof(T)) + n * sizeof(T);
    } else {
      for (std::size_t i = 0; i < n; ++i) (*this)(data[i]);
    }
  }
  std::size_t offset_ = 0;
};

// Writes into a caller-provided buffer of exactly CdrSizer::size() bytes, or
// into a growable vector.
class CdrWriter {
 public:
  // Writes into `out` (which must hold the whole message) and emits the header.
  explicit CdrWriter(std::span<uint8_t> out) : buf_(out.data()), cap_(out.size()) { header(); }
  // Appends to `out`, which is cleared first, and emits the header.
  explicit CdrWriter(std::vector<uint8_t>& out) : vec_(&out) {
    out.clear();
    header();
  }

  // Bytes written so far, header included.
  std::size_t size() const { return kEncapsulationSize + offset_; }

  template <CdrPrimitive T>
  void operator()(const T& v) {
    align(sizeof(T));
    put(&v, sizeof(T));
  }
  void operator()(const std::string& s) {
    (*this)(static_cast<uint32_t>(s.size() + 1));
    put(s.data(), s.size());
    const char nul = 0;
    put(&nul, 1);
  }
  template <class T>
  void operator()(const std::vector<T>& seq) {
    (*this)(static_cast<uint32_t>(seq.size()));
    elements(seq.data(), seq.size());
  }
  template <class T, std::size_t N>
  void operator()(const std::array<T, N>& arr) {
    elements(arr.data(), N);
  }
  template <class T>
  requires(!CdrPrimitive<T>) void operator()(const T& m) { visit_fields(*this, m); }

 private:
  static_assert(std::endian::native == std::endian::little,
                "robotperf assumes a little-endian host");

  void header() {
    const auto& h = kCdrLittleEndianHeader;
    raw(h.data(), h.size());
  }
  void align(std::size_t a) {
    static constexpr uint8_t zeros[8] = {};
    put(zeros, detail::pad_to(offset_, a));
  }
  void put(const void* p, std::size_t n) {
    raw(p, n);
    offset_ += n;
  }
  void raw(const void* p, std::size_t n) {
    if (n == 0) return;
    const std::size_t at = written_;
    if (vec_) {
      vec_->resize(at + n);
      std::memcpy(vec_->data() + at, p, n);
    } else {
      if (at + n > cap_) throw CdrError("CDR output buffer too small");
      std::memcpy(buf_ + at, p, n);
    }
    written_ += n;
  }
  template <class T>
  void elements(const T* data, std::size_t n) {
    if constexpr (CdrPrimitive<T> && !std::is_same_v<T, bool>) {
      if (n == 0) return;
      align(sizeof(T));
      put(data, n * sizeof(T));
    } else {
      for (std::size_t i = 0; i < n; ++i) (*this)(data[i]);
    }
  }

  uint8_t* buf_ = nullptr;
  std::size_t cap_ = 0;
  std::vector<uint8_t>* vec_ = nullptr;
  std::size_t written_ = 0;  // bytes in the output, header included
  std::size_t offset_ = 0;   // alignment origin: the byte after the header
};

// Reads a payload that starts with the encapsulation header. Throws CdrError
// on truncation, a big-endian or non-CDR header, or absurd lengths. Trailing
// padding after the last field is ignored, as ROS 2 readers do.
class CdrReader {
 public:
  explicit CdrReader(std::span<const uint8_t> in) : data_(in.data()), size_(in.size()) {
    if (size_ < kEncapsulationSize) throw CdrError("CDR payload shorter than its 4-byte header");
    if (data_[0] != 0x00 || data_[1] != 0x01) {
      throw CdrError("CDR payload is not little-endian plain CDR (encapsulation " +
                     std::to_string(data_[0]) + "," + std::to_string(data_[1]) + ")");
    }
    data_ += kEncapsulationSize;
    size_ -= kEncapsulationSize;
  }

  // Bytes of the body consumed so far (header excluded).
  std::size_t offset() const { return offset_; }
  std::size_t remaining() const { return size_ - offset_; }

  template <CdrPrimitive T>
  void operator()(T& v) {
    align(sizeof(T));
    if constexpr (std::is_same_v<T, bool>) {
      uint8_t b;
      get(&b, 1);
      v = b != 0;
    } else {
      get(&v, sizeof(T));
    }
  }
  void operator()(std::string& s) {
    uint32_t len;
    (*this)(len);
    if (len == 0) {  // Some writers emit a zero length for the empty string.
      s.clear();
      return;
    }
    need(len);
    const char* p = reinterpret_cast<const char*>(data_ + offset_);
    if (p[len - 1] != '\0') throw CdrError("CDR string is not NUL-terminated");
    s.assign(p, len - 1);
    offset_ += len;
  }
  template <class T>
  void operator()(std::vector<T>& seq) {
    uint32_t n;
    (*this)(n);
    // Each element takes at least one byte: reject counts the payload cannot hold.
    if (n > remaining())
      throw CdrError("CDR sequence length " + std::to_string(n) + " exceeds payload");
    if constexpr (sizeof(T) == 1 && CdrPrimitive<T> && !std::is_same_v<T, bool>) {
      // Byte sequences (image data) are constructed straight from the payload:
      // resize() would first zero-fill megabytes that are overwritten at once.
      need(n);
      const auto* first = reinterpret_cast<const T*>(data_ + offset_);
      seq.assign(first, first + n);
      offset_ += n;
    } else if constexpr (CdrPrimitive<T>) {
      if (n > remaining() / sizeof(T))
        throw CdrError("CDR sequence length " + std::to_string(n) + " exceeds payload");
      seq.resize(n);
      elements(seq.data(), n);
    } else {
      // An element in memory can be far larger than its least bytes on the wire (a
      // TransformStamped: 128 bytes against at least 72): elements are added as they decode, so a
      // forged count costs no more memory than the payload holds.
      seq.clear();
      seq.reserve(std::min<std::size_t>(n, remaining() / sizeof(T)));
      for (uint32_t i = 0; i < n; ++i) (*this)(seq.emplace_back());
    }
  }
  template <class T, std::size_t N>
  void operator()(std::array<T, N>& arr) {
    elements(arr.data(), N);
  }
  template <class T>
  requires(!CdrPrimitive<T>) void operator()(T& m) { visit_fields(*this, m); }

 private:
  void align(std::size_t a) {
    const std::size_t pad = detail::pad_to(offset_, a);
    need(pad);
    offset_ += pad;
  }
  void need(std::size_t n) const {
    if (n > size_ - offset_) throw CdrError("CDR payload truncated");
  }
  void get(void* p, std::size_t n) {
    need(n);
    std::memcpy(p, data_ + offset_, n);
    offset_ += n;
  }
  template <class T>
  void elements(T* data, std::size_t n) {
    if constexpr (CdrPrimitive<T> && !std::is_same_v<T, bool>) {
      if (n == 0) return;
      align(sizeof(T));
      get(data, n * sizeof(T));
    } else {
      for (std::size_t i = 0; i < n; ++i) (*this)(data[i]);
    }
  }

  const uint8_t* data_;
  std::size_t size_;
  std::size_t offset_ = 0;
};

// Convenience: serialize a whole message into a new buffer.
template <class T>
std::vector<uint8_t> to_cdr(const T& msg) {
  std::vector<uint8_t> out;
  CdrSizer sizer;
  sizer(msg);
  out.reserve(sizer.size());
  CdrWriter w(out);
  w(msg);
  return out;
}

// Convenience: deserialize a whole message.
template <class T>
T from_cdr(std::span<const uint8_t> payload) {
  T msg{};
  CdrReader r(payload);
  r(msg);
  return msg;
}

}  // namespace robotperf::msgs
