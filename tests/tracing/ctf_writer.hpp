// Writes small CTF 1.8 traces laid out as LTTng-UST 2.13 writes them (same
// TSDL, packet header and context, compact or large event headers, vpid/vtid/
// procname event context), with events and timestamps chosen by the test.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

namespace robotperf::tracing::testing {

enum class FieldKind { kU64, kI64, kI32, kHex64, kString, kF64, kGid };

struct FieldDef {
  std::string name;
  FieldKind kind;
};

using FieldValue = std::variant<uint64_t, int64_t, double, std::string>;

class CtfWriter {
 public:
  enum class Header { kCompact, kLarge };

  CtfWriter(std::filesystem::path dir, Header header, bool packetized_metadata, int streams = 1)
      : dir_(std::move(dir)),
        header_(header),
        packetized_(packetized_metadata),
        streams_(streams) {}

  // The frequency of the trace's clock: timestamps given to event() count its cycles.
  void clock_frequency(uint64_t hz) { clock_freq_ = hz; }

  uint32_t define(const std::string& name, std::vector<FieldDef> fields) {
    defs_.push_back({name, std::move(fields)});
    return static_cast<uint32_t>(defs_.size() - 1);
  }
  uint32_t id(const std::string& name) const {
    for (std::size_t i = 0; i < defs_.size(); ++i) {
      if (defs_[i].name == name) return static_cast<uint32_t>(i);
    }
    throw std::invalid_argument("undefined event " + name);
  }

  // Appends an event to stream `stream` (timestamps must not decrease within a stream).
  void event(int stream, const std::string& name, uint64_t ts, int32_t vpid, int32_t vtid,
             const std::vector<FieldValue>& values) {
    const uint32_t eid = id(name);
    Stream& s = stream_(stream);
    if (!s.open) open_packet(s, ts, stream);
    Bytes& b = s.packet;
    const uint64_t delta = ts - s.last_ts;
    const bool compact_id = header_ == Header::kCompact ? eid < 31 : eid < 65535;
    const unsigned ts_bits = header_ == Header::kCompact ? 27 : 32;
    const bool compact = compact_id && ts >= s.last_ts && delta < (uint64_t{1} << ts_bits);
    if (header_ == Header::kCompact) {
      if (compact) {
        const uint32_t word = eid | (static_cast<uint32_t>(ts & ((1u << 27) - 1)) << 5);
        put(b, word);
      } else {
        b.push_back(31);  // 5-bit id "extended", then padding to the byte
        put(b, eid);
        put(b, ts);
      }
    } else {
      if (compact) {
        put(b, static_cast<uint16_t>(eid));
        put(b, static_cast<uint32_t>(ts));
      } else {
        put(b, static_cast<uint16_t>(65535));
        put(b, eid);
        put(b, ts);
      }
    }
    s.last_ts = ts;
    s.end_ts = ts;
    put(b, vpid);
    put(b, vtid);
    char procname[17] = {};
    std::strncpy(procname, "robotperf", sizeof procname - 1);
    b.insert(b.end(), procname, procname + 17);
    const auto& def = defs_[eid];
    if (values.size() != def.fields.size())
      throw std::invalid_argument("wrong value count for " + name);
    for (std::size_t i = 0; i < values.size(); ++i) {
      switch (def.fields[i].kind) {
        case FieldKind::kU64:
        case FieldKind::kHex64:
          put(b, std::get<uint64_t>(values[i]));
          break;
        case FieldKind::kI64:
          put(b, std::get<int64_t>(values[i]));
          break;
        case FieldKind::kI32:
          put(b, static_cast<int32_t>(std::get<int64_t>(values[i])));
          break;
        case FieldKind::kF64:
          put(b, std::get<double>(values[i]));
          break;
        case FieldKind::kString: {
          const auto& str = std::get<std::string>(values[i]);
          b.insert(b.end(), str.begin(), str.end());
          b.push_back(0);
          break;
        }
        case FieldKind::kGid:
          for (int k = 0; k < 24; ++k) b.push_back(static_cast<uint8_t>(k));
          break;
      }
    }
  }

  // Closes the current packet of `stream`; the next one reports this running
  // count of discarded events.
  void end_packet(int stream, uint64_t discarded_so_far = 0) {
    Stream& s = stream_(stream);
    if (s.open) close_packet(s);
    s.discarded = discarded_so_far;
  }

  void finish() {
    std::filesystem::create_directories(dir_);
    for (int i = 0; i < streams_; ++i) {
      Stream& s = stream_(i);
      if (s.open) close_packet(s);
      std::ofstream(dir_ / ("channel0_" + std::to_string(i)), std::ios::binary)
          .write(reinterpret_cast<const char*>(s.file.data()),
                 static_cast<std::streamsize>(s.file.size()));
    }
    const std::string text = metadata();
    std::ofstream out(dir_ / "metadata", std::ios::binary);
    if (!packetized_) {
      out << text;
      return;
    }
    // Metadata packets as LTTng writes them: 37-byte header, then text; the
    // text is split over several packets to exercise reassembly.
    constexpr std::size_t kChunk = 1000;
    for (std::size_t off = 0; off < text.size(); off += kChunk) {
      const std::string part = text.substr(off, kChunk);
      Bytes p;
      put(p, uint32_t{0x75D11D57});
      for (int k = 0; k < 16; ++k) p.push_back(0x11);
      put(p, uint32_t{0});                                         // checksum
      put(p, static_cast<uint32_t>((37 + part.size()) * 8));       // content_size
      put(p, static_cast<uint32_t>((37 + part.size() + 64) * 8));  // packet_size
      p.insert(p.end(), {0, 0, 0, 1, 8});
      p.insert(p.end(), part.begin(), part.end());
      p.resize(p.size() + 64, 0);
      out.write(reinterpret_cast<const char*>(p.data()), static_cast<std::streamsize>(p.size()));
    }
  }

 private:
  using Bytes = std::vector<uint8_t>;
  struct Def {
    std::string name;
    std::vector<FieldDef> fields;
  };
  struct Stream {
    Bytes file, packet;
    bool open = false;
    uint64_t begin_ts = 0, end_ts = 0, last_ts = 0, seq = 0, discarded = 0;
    std::size_t context_offset = 0;
  };

  template <class T>
  static void put(Bytes& b, T v) {
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    b.insert(b.end(), p, p + sizeof v);
  }
  template <class T>
  static void put_at(Bytes& b, std::size_t off, T v) {
    std::memcpy(b.data() + off, &v, sizeof v);
  }

  Stream& stream_(int i) {
    if (i < 0 || i >= streams_) throw std::invalid_argument("no such stream");
    return s_[i];
  }

  // One stream per CPU, as LTTng's per-CPU buffers: own instance id and cpu_id.
  void open_packet(Stream& s, uint64_t ts, int cpu) {
    s.open = true;
    s.packet.clear();
    s.begin_ts = s.last_ts = s.end_ts = ts;
    put(s.packet, uint32_t{0xC1FC1FC1});
    for (int k = 0; k < 16; ++k) s.packet.push_back(0x11);
    put(s.packet, uint32_t{0});                 // stream_id
    put(s.packet, static_cast<uint64_t>(cpu));  // stream_instance_id
    s.context_offset = s.packet.size();
    put(s.packet, ts);                          // timestamp_begin
    put(s.packet, uint64_t{0});                 // timestamp_end
    put(s.packet, uint64_t{0});                 // content_size
    put(s.packet, uint64_t{0});                 // packet_size
    put(s.packet, s.seq++);                     // packet_seq_num
    put(s.packet, s.discarded);                 // events_discarded
    put(s.packet, static_cast<uint32_t>(cpu));  // cpu_id
  }

  void close_packet(Stream& s) {
    const std::size_t content = s.packet.size();
    const std::size_t size = (content + 255) / 256 * 256;
    put_at(s.packet, s.context_offset + 8, s.end_ts);
    put_at(s.packet, s.context_offset + 16, static_cast<uint64_t>(content * 8));
    put_at(s.packet, s.context_offset + 24, static_cast<uint64_t>(size * 8));
    s.packet.resize(size, 0);
    s.file.insert(s.file.end(), s.packet.begin(), s.packet.end());
    s.open = false;
  }

  static std::string field_tsdl(const FieldDef& f) {
    const std::string n = "_" + f.name;
    switch (f.kind) {
      case FieldKind::kU64:
        return "integer { size = 64; align = 8; signed = 0; encoding = none; base = 10; } " + n +
               ";";
      case FieldKind::kI64:
        return "integer { size = 64; align = 8; signed = 1; encoding = none; base = 10; } " + n +
               ";";
      case FieldKind::kI32:
        return "integer { size = 32; align = 8; signed = 1; encoding = none; base = 10; } " + n +
               ";";
      case FieldKind::kHex64:
        return "integer { size = 64; align = 8; signed = 0; encoding = none; base = 16; } " + n +
               ";";
      case FieldKind::kString:
        return "string " + n + ";";
      case FieldKind::kF64:
        return "floating_point { exp_dig = 11; mant_dig = 53; align = 8; } " + n + ";";
      case FieldKind::kGid:
        return "integer { size = 8; align = 8; signed = 0; encoding = none; base = 10; } " + n +
               "[24];";
    }
    return {};
  }

  std::string metadata() const {
    std::string m = R"(/* CTF 1.8 */

typealias integer { size = 8; align = 8; signed = false; } := uint8_t;
typealias integer { size = 16; align = 8; signed = false; } := uint16_t;
typealias integer { size = 32; align = 8; signed = false; } := uint32_t;
typealias integer { size = 64; align = 8; signed = false; } := uint64_t;
typealias integer { size = 64; align = 8; signed = false; } := unsigned long;
typealias integer { size = 5; align = 1; signed = false; } := uint5_t;
typealias integer { size = 27; align = 1; signed = false; } := uint27_t;

trace {
	major = 1;
	minor = 8;
	uuid = "11111111-1111-1111-1111-111111111111";
	byte_order = le;
	packet.header := struct {
		uint32_t magic;
		uint8_t  uuid[16];
		uint32_t stream_id;
		uint64_t stream_instance_id;
	};
};

env {
	hostname = "test";
	domain = "ust";
	tracer_name = "lttng-ust";
	tracer_major = 2;
	tracer_minor = 13;
};

clock {
	name = "monotonic";
	uuid = "22222222-2222-2222-2222-222222222222";
	description = "Monotonic Clock";
	freq = )";
    m += std::to_string(clock_freq_);
    m += R"(; /* Frequency, in Hz */
	/* clock value offset from Epoch is: offset * (1/freq) */
	offset = 1700000000000000000;
};

typealias integer {
	size = 27; align = 1; signed = false;
	map = clock.monotonic.value;
} := uint27_clock_monotonic_t;

typealias integer {
	size = 32; align = 8; signed = false;
	map = clock.monotonic.value;
} := uint32_clock_monotonic_t;

typealias integer {
	size = 64; align = 8; signed = false;
	map = clock.monotonic.value;
} := uint64_clock_monotonic_t;

struct packet_context {
	uint64_clock_monotonic_t timestamp_begin;
	uint64_clock_monotonic_t timestamp_end;
	uint64_t content_size;
	uint64_t packet_size;
	uint64_t packet_seq_num;
	unsigned long events_discarded;
	uint32_t cpu_id;
};

struct event_header_compact {
	enum : uint5_t { compact = 0 ... 30, extended = 31 } id;
	variant <id> {
		struct {
			uint27_clock_monotonic_t timestamp;
		} compact;
		struct {
			uint32_t id;
			uint64_clock_monotonic_t timestamp;
		} extended;
	} v;
} align(8);

struct event_header_large {
	enum : uint16_t { compact = 0 ... 65534, extended = 65535 } id;
	variant <id> {
		struct {
			uint32_clock_monotonic_t timestamp;
		} compact;
		struct {
			uint32_t id;
			uint64_clock_monotonic_t timestamp;
		} extended;
	} v;
} align(8);

)";
    m += "stream {\n\tid = 0;\n\tevent.header := struct ";
    m += header_ == Header::kCompact ? "event_header_compact" : "event_header_large";
    m += R"(;
	packet.context := struct packet_context;
	event.context := struct {
		integer { size = 32; align = 8; signed = 1; encoding = none; base = 10; } _vpid;
		integer { size = 32; align = 8; signed = 1; encoding = none; base = 10; } _vtid;
		integer { size = 8; align = 8; signed = 1; encoding = UTF8; base = 10; } _procname[17];
	};
};

)";
    for (std::size_t i = 0; i < defs_.size(); ++i) {
      m += "event {\n\tname = \"" + defs_[i].name + "\";\n\tid = " + std::to_string(i) +
           ";\n\tstream_id = 0;\n\tloglevel = 13;\n\tfields := struct {\n";
      for (const auto& f : defs_[i].fields) m += "\t\t" + field_tsdl(f) + "\n";
      m += "\t};\n};\n\n";
    }
    return m;
  }

  std::filesystem::path dir_;
  Header header_;
  bool packetized_;
  int streams_;
  uint64_t clock_freq_ = 1'000'000'000;
  std::vector<Def> defs_;
  std::map<int, Stream> s_;
};

// The ros2_tracing layout a test trace imitates: robotperf's own (Jazzy's), or Humble's, whose
// rmw_publish records no publisher handle and no timestamp.
enum class Ros2Layout { kJazzy, kHumble };

// The robotperf and ros2 event classes robotperf's analysis reads, with the
// field layout of src/tracing/tracepoints; `state_output_field` false: run_begin as robotperf
// wrote it before it recorded whether the output is a state stream.
inline void define_robotperf_events(CtfWriter& w, Ros2Layout layout = Ros2Layout::kJazzy,
                                    bool state_output_field = true) {
  using K = FieldKind;
  std::vector<FieldDef> run_begin = {{"benchmark", K::kString},    {"rmw", K::kString},
                                     {"count", K::kU64},           {"warmup", K::kU64},
                                     {"period_ns", K::kI64},       {"min_samples", K::kU64},
                                     {"max_loss_percent", K::kF64}};
  if (state_output_field) run_begin.push_back({"state_output", K::kI32});
  w.define("robotperf:run_begin", std::move(run_begin));
  w.define("robotperf:run_join", {{"run_pid", K::kI32}});
  w.define("robotperf:run_end", {{"sent", K::kU64}});
  w.define("robotperf:input", {{"node", K::kString},
                               {"message_id", K::kI64},
                               {"index", K::kU64},
                               {"scheduled_ns", K::kI64}});
  for (const char* e : {"robotperf:output", "robotperf:publish", "robotperf:callback_entry"}) {
    w.define(
        e,
        {{"node", K::kString}, {"topic", K::kString}, {"message_id", K::kI64}, {"size", K::kU64}});
  }
  for (const char* e : {"robotperf:kernel_init", "robotperf:kernel_fini"}) {
    w.define(
        e,
        {{"node", K::kString}, {"kernel", K::kString}, {"message_id", K::kI64}, {"size", K::kU64}});
  }
  for (const char* e : {"robotperf:device_begin", "robotperf:device_end"}) {
    w.define(
        e,
        {{"node", K::kString}, {"stage", K::kString}, {"message_id", K::kI64}, {"size", K::kU64}});
  }
  w.define("ros2:rcl_node_init", {{"node_handle", K::kHex64},
                                  {"rmw_handle", K::kHex64},
                                  {"node_name", K::kString},
                                  {"namespace", K::kString}});
  w.define("ros2:rmw_publisher_init", {{"rmw_publisher_handle", K::kHex64}, {"gid", K::kGid}});
  for (const char* e : {"ros2:rcl_publisher_init", "ros2:rcl_subscription_init"}) {
    const bool pub = std::string(e) == "ros2:rcl_publisher_init";
    w.define(e, {{pub ? "publisher_handle" : "subscription_handle", K::kHex64},
                 {"node_handle", K::kHex64},
                 {pub ? "rmw_publisher_handle" : "rmw_subscription_handle", K::kHex64},
                 {"topic_name", K::kString},
                 {"queue_depth", K::kU64}});
  }
  w.define("ros2:rclcpp_subscription_init",
           {{"subscription_handle", K::kHex64}, {"subscription", K::kHex64}});
  w.define("ros2:rclcpp_subscription_callback_added",
           {{"subscription", K::kHex64}, {"callback", K::kHex64}});
  w.define("ros2:rcl_timer_init", {{"timer_handle", K::kHex64}, {"period", K::kI64}});
  w.define("ros2:rclcpp_timer_callback_added",
           {{"timer_handle", K::kHex64}, {"callback", K::kHex64}});
  w.define("ros2:rclcpp_timer_link_node",
           {{"timer_handle", K::kHex64}, {"node_handle", K::kHex64}});
  w.define("ros2:callback_start", {{"callback", K::kHex64}, {"is_intra_process", K::kI32}});
  w.define("ros2:callback_end", {{"callback", K::kHex64}});
  if (layout == Ros2Layout::kHumble) {
    w.define("ros2:rmw_publish", {{"message", K::kHex64}});
  } else {
    w.define("ros2:rmw_publish",
             {{"rmw_publisher_handle", K::kHex64}, {"message", K::kHex64}, {"timestamp", K::kI64}});
  }
  w.define("ros2:rclcpp_callback_register", {{"callback", K::kHex64}, {"symbol", K::kString}});
  w.define("ros2:rmw_take", {{"rmw_subscription_handle", K::kHex64},
                             {"message", K::kHex64},
                             {"source_timestamp", K::kI64},
                             {"taken", K::kI32}});
}

}  // namespace robotperf::tracing::testing
