// A reader of CTF 1.8 traces as LTTng writes them: the TSDL metadata (plain
// or packetised), and the binary streams (packet headers and contexts, compact
// and large event headers, event contexts and payloads). Written for speed:
// streams are memory-mapped, field layouts are resolved once per event class,
// strings are views into the mapped files.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace robotperf::tracing::ctf {

// A trace that cannot be read: says which file and what is wrong.
class CtfError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Type;
using TypePtr = std::shared_ptr<const Type>;

enum class Kind { kInteger, kFloat, kString, kStruct, kArray, kSequence, kVariant, kEnum };
enum class ByteOrder { kNative, kLittle, kBig };  // native = the trace's byte_order

struct EnumMapping {
  std::string label;
  int64_t low = 0;
  int64_t high = 0;
};

struct Field {
  std::string name;  // as in the metadata, leading '_' removed (CTF's escaping)
  TypePtr type;
};

struct Type {
  Kind kind = Kind::kInteger;
  unsigned align_bits = 8;
  // Integers, enum containers and floats.
  unsigned size_bits = 0;
  bool is_signed = false;
  ByteOrder byte_order = ByteOrder::kNative;
  bool is_text = false;     // 8-bit integer with an encoding: arrays of it are strings
  bool maps_clock = false;  // `map = clock.<name>.value`
  unsigned mant_dig = 0;    // floats
  // Enums.
  std::vector<EnumMapping> mappings;
  // Structs and variants.
  std::vector<Field> fields;
  std::string variant_tag;  // the enum field selecting a variant's option
  // Resolved when the tag is a sibling enum field (as LTTng writes it):
  // the sibling's index, and the option selected by each of its mappings (-1: none).
  int tag_sibling = -1;
  std::vector<int> option_of_mapping;
  // Arrays and sequences.
  TypePtr element;
  uint64_t length = 0;       // arrays
  std::string length_field;  // sequences: the integer field holding the length
  int length_sibling = -1;   // its index among the enclosing struct's fields
};

struct EventClass {
  uint64_t id = 0;
  uint64_t stream_id = 0;
  std::string name;  // "provider:event"
  int loglevel = -1;
  TypePtr context;  // optional per-event context
  TypePtr fields;   // a struct (or null for no payload)
  // Index of a top-level payload field, or -1.
  int field_index(std::string_view field_name) const;
};

struct StreamClass {
  uint64_t id = 0;
  TypePtr packet_context;
  TypePtr event_header;
  TypePtr event_context;
  std::vector<const EventClass*> events_by_id;  // index = event id, null for gaps
};

struct ClockClass {
  std::string name;
  uint64_t freq = 1'000'000'000;
  int64_t offset_s = 0;
  int64_t offset = 0;  // cycles
};

// The decoded metadata of one trace (one folder with a `metadata` file).
struct Metadata {
  bool big_endian = false;
  TypePtr packet_header;
  std::vector<std::pair<std::string, std::string>> env;  // env block, values as text
  std::vector<ClockClass> clocks;
  std::vector<StreamClass> streams;
  std::vector<std::unique_ptr<EventClass>> events;

  const StreamClass* stream(uint64_t id) const;
  std::string env_value(std::string_view key) const;
};

// Parses TSDL text. Throws CtfError naming the line of a syntax error.
Metadata parse_metadata_text(std::string_view tsdl);
// Reads a metadata file, plain text or packetised as LTTng writes it.
Metadata read_metadata(const std::filesystem::path& file);

// One decoded scalar value (top-level payload and stream-context fields).
struct Value {
  enum class Tag : uint8_t { kNone, kUnsigned, kSigned, kFloat, kString };
  Tag tag = Tag::kNone;
  uint64_t u = 0;  // kUnsigned, and the bits of kSigned
  double f = 0;
  std::string_view s;

  int64_t as_int() const {
    return tag == Tag::kFloat ? static_cast<int64_t>(f) : static_cast<int64_t>(u);
  }
  uint64_t as_uint() const { return tag == Tag::kFloat ? static_cast<uint64_t>(f) : u; }
};

struct Event {
  const EventClass* cls = nullptr;
  // Nanoseconds of the trace's clock: its cycles divided by its frequency. The clock's offset
  // (from the epoch) is not added: event times compare with the traced programs' own readings of
  // that clock (CLOCK_MONOTONIC for LTTng).
  uint64_t timestamp = 0;
  uint32_t cpu_id = 0;
  std::span<const Value> fields;          // top-level payload fields, in declaration order
  std::span<const Value> stream_context;  // top-level stream event-context fields
};

struct StreamStats {
  std::string file;
  uint64_t packets = 0;
  uint64_t events = 0;
  uint64_t discarded_events = 0;  // from the packets' events_discarded counters
  uint64_t lost_packets = 0;      // gaps in packet_seq_num
};

// One packet of a stream: where it lies and what its context says. Its events can be decoded
// on their own when it gives its first clock value (timestamp_begin, as LTTng writes).
//
// The times of a stream's events never go back: within a packet each event is at or after the
// one before it, and all lie in [timestamp_begin, timestamp_end]; a packet begins at or after the
// end of the packet before it. A packet that breaks this (a corrupt byte in a time) is defective:
// its events are not read, so that a wrong time does not become a wrong latency. So is a packet
// without timestamp_begin in a stream whose other packets have theirs: its times are unknown.
struct Packet {
  const StreamClass* stream_class = nullptr;
  uint64_t start_bits = 0;   // of the packet header
  uint64_t events_bits = 0;  // of its first event
  uint64_t content_end_bits = 0;
  uint64_t end_bits = 0;  // of the packet, padding included
  bool has_clock = false;
  uint64_t timestamp_begin = 0;
  // The latest time (clock cycles) its events may have: its timestamp_end, or the next packet's
  // timestamp_begin where timestamp_end is missing or known to be wrong (LTTng before 2.11 wrote
  // events after it; a crashed session leaves it 0); UINT64_MAX when neither is known.
  uint64_t timestamp_end = UINT64_MAX;
  uint32_t cpu_id = 0;
  // Why its events are not read, one line naming the stream file and the packet's byte offset;
  // empty when they are.
  std::string defect;
};

// A stream's packets in file order, and the stream's counters from their contexts (its events
// are not counted: that takes decoding them).
struct StreamIndex {
  std::vector<Packet> packets;
  StreamStats stats;
};

// What one Trace::read_packets call did.
struct PacketsRead {
  uint64_t events = 0;  // given to the caller
  // Packets it found defective by their events' times, and marked so (Packet::defect). Events
  // of theirs before the defective one were given to the caller already.
  uint64_t defective_packets = 0;
};

// The fields a reader uses. The others are stepped over without being decoded, and their Values
// are left with tag kNone: a reader of a few fields of millions of events saves most of their
// decoding (a string must still be scanned for its end). Asked once per event class and stream
// class, before any of their events is decoded.
struct FieldSelection {
  // Whether top-level payload field `field` of events of class `ec` is used.
  std::function<bool(const EventClass& ec, std::size_t field)> payload;
  // Whether top-level stream event-context field `field` of stream class `sc` is used.
  std::function<bool(const StreamClass& sc, std::size_t field)> stream_context;
};

// One trace: a folder holding `metadata` and its stream files.
class Trace {
 public:
  explicit Trace(const std::filesystem::path& dir);
  ~Trace();
  Trace(Trace&&) noexcept;
  Trace& operator=(Trace&&) noexcept;

  const Metadata& metadata() const { return metadata_; }
  const std::filesystem::path& dir() const { return dir_; }
  std::size_t stream_count() const { return stream_files_.size(); }
  // The size of all stream files together.
  std::size_t total_bytes() const;

  // Decodes every event of stream `index`, in stream order (time order within
  // the stream), calling `on_event` for each. The Event and its views are valid
  // during the call only; string views stay valid while the Trace lives. The events of defective
  // packets are left out (found by decoding the stream once more beforehand).
  StreamStats read_stream(std::size_t index, const std::function<void(const Event&)>& on_event);

  // Reads the packet headers and contexts of stream `index`, without its events, and marks the
  // packets whose times are out of order (see Packet).
  StreamIndex index_stream(std::size_t index) const;
  // Decodes the events of `packets` (consecutive packets of stream `index`'s index, in order),
  // calling `on_event` for each. Stream parts whose first packet has its clock can be decoded on
  // different threads at once: a Trace is only read, and each call writes its own packets only.
  // With `selection`, only the fields it selects are decoded (where the layout allows stepping
  // over the others). Defective packets are stepped over; a packet found defective here (an
  // event out of order or out of the packet's times) is marked, and decoding goes on with the
  // next one: a caller that must not use any of its events decodes the packets again.
  PacketsRead read_packets(std::size_t index, std::span<Packet> packets,
                           const std::function<void(const Event&)>& on_event,
                           const FieldSelection* selection = nullptr) const;

  // Index of a stream event-context field ("vpid", "vtid", "procname"), or -1.
  int stream_context_index(uint64_t stream_id, std::string_view name) const;

 private:
  struct Mapped;
  std::filesystem::path dir_;
  Metadata metadata_;
  uint64_t clock_freq_ = 0;  // Hz, of the clock the event times count in
  // The tracer is one that wrote events after their packet's timestamp_end (LTTng-UST before
  // 2.11, LTTng-modules before 2.9.13, 2.10.10 and 2.11, as babeltrace2 documents).
  bool events_after_packet_end_ = false;
  std::vector<std::filesystem::path> stream_files_;
  std::vector<std::unique_ptr<Mapped>> mapped_;
};

// Every folder under `root` (root included) that holds a CTF `metadata` file,
// sorted. A trace recorded with per-process buffers has one per process.
std::vector<std::filesystem::path> find_traces(const std::filesystem::path& root);

}  // namespace robotperf::tracing::ctf
