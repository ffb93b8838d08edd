// The Cyclone DDS transport: ROS 2-compatible DDS endpoints (docs/design.md §2) on Cyclone DDS's C
// API.
//
// Each message type gets a keyless sertype under its ROS 2 DDS type name (as rmw_cyclonedds
// registers one), whose serdata is the message's plain-CDR bytes, encapsulation header included:
// a write serializes the message once, straight into the buffer Cyclone sends from; a take
// decodes the received bytes into a robotperf message. No XTypes type information is announced,
// so remote endpoints match by type name, as with the Fast DDS transport.
#include "cyclonedds_transport.hpp"

#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <dds/ddsi/ddsi_sertype.h>
#include <dds/ddsi/q_radmin.h>
#include <dlfcn.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <new>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <system_error>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "participant_transport.hpp"
#include "peer_table.hpp"
#include "robotperf/tracing/tracepoints.hpp"

namespace robotperf::rmw {
namespace {

// --- The sertype and serdata: a message type as Cyclone sees it ----------------------------------

// A sertype that knows the robotperf TypeSupport of its messages.
struct MessageSertype {
  ddsi_sertype base;  // first, so that Cyclone's pointer is also ours
  const msgs::TypeSupport* type;
};
static_assert(std::is_standard_layout_v<MessageSertype>);

// One sample: its CDR bytes (encapsulation header included), zero-padded to a multiple of 4 as
// Cyclone may read up to the next 4-byte boundary.
struct CdrSample {
  ddsi_serdata base;  // first, as above
  uint8_t* bytes;
  uint32_t size;
  int64_t reception_ns;  // when it reached this process (wall clock)
};
static_assert(std::is_standard_layout_v<CdrSample>);

// The encapsulation header alone: what keyless "key" samples (unregister, dispose) carry.
constexpr std::array<uint8_t, 4> kHeaderOnly = {0x00, 0x01, 0x00, 0x00};

const msgs::TypeSupport& type_of(const ddsi_sertype* sertype) {
  return *reinterpret_cast<const MessageSertype*>(sertype)->type;
}
CdrSample* as_sample(ddsi_serdata* d) {
  return reinterpret_cast<CdrSample*>(d);
}
const CdrSample* as_sample(const ddsi_serdata* d) {
  return reinterpret_cast<const CdrSample*>(d);
}

// A sample with room for `size` bytes; null when out of memory (Cyclone's convention).
CdrSample* new_sample(const ddsi_sertype* sertype, ddsi_serdata_kind kind, std::size_t size) {
  if (size > std::numeric_limits<uint32_t>::max() - 3) return nullptr;
  auto* sample = new (std::nothrow) CdrSample{};
  if (sample == nullptr) return nullptr;
  const std::size_t capacity = std::max<std::size_t>(4, (size + 3) & ~std::size_t{3});
  // Not calloc: the bytes are written at once (serialized or received), and zeroing megabytes
  // first would cost a pass over them; only the padding must be zero.
  sample->bytes = static_cast<uint8_t*>(std::malloc(capacity));
  if (sample->bytes == nullptr) {
    delete sample;
    return nullptr;
  }
  std::memset(sample->bytes + size, 0, capacity - size);
  sample->size = static_cast<uint32_t>(size);
  sample->reception_ns = wall_now_ns();
  ddsi_serdata_init(&sample->base, sertype, kind);
  return sample;
}

ddsi_serdata* header_only_sample(const ddsi_sertype* sertype) {
  CdrSample* sample = new_sample(sertype, SDK_KEY, kHeaderOnly.size());
  if (sample == nullptr) return nullptr;
  std::memcpy(sample->bytes, kHeaderOnly.data(), kHeaderOnly.size());
  return &sample->base;
}

// Keyless: every sample belongs to the one instance.
bool serdata_eqkey(const ddsi_serdata*, const ddsi_serdata*) {
  return true;
}

uint32_t serdata_size(const ddsi_serdata* d) {
  return as_sample(d)->size;
}

void serdata_free(ddsi_serdata* d) {
  CdrSample* sample = as_sample(d);
  std::free(sample->bytes);
  delete sample;
}

// Received over the network, in fragments that may overlap; the first holds the header.
ddsi_serdata* serdata_from_ser(const ddsi_sertype* sertype, ddsi_serdata_kind kind,
                               const nn_rdata* fragment, std::size_t size) {
  CdrSample* sample = new_sample(sertype, kind, size);
  if (sample == nullptr) return nullptr;
  std::size_t filled = 0;
  for (; fragment != nullptr && filled < size; fragment = fragment->nextfrag) {
    if (fragment->min > filled || fragment->maxp1 <= filled) continue;
    const unsigned char* payload =
        NN_RMSG_PAYLOADOFF(fragment->rmsg, NN_RDATA_PAYLOAD_OFF(fragment));
    const std::size_t end = std::min<std::size_t>(fragment->maxp1, size);
    std::memcpy(sample->bytes + filled, payload + (filled - fragment->min), end - filled);
    filled = end;
  }
  return &sample->base;
}

ddsi_serdata* serdata_from_ser_iov(const ddsi_sertype* sertype, ddsi_serdata_kind kind,
                                   ddsrt_msg_iovlen_t count, const ddsrt_iovec_t* iov,
                                   std::size_t size) {
  CdrSample* sample = new_sample(sertype, kind, size);
  if (sample == nullptr) return nullptr;
  std::size_t filled = 0;
  for (ddsrt_msg_iovlen_t i = 0; i < count && filled < size; ++i) {
    const std::size_t n = std::min<std::size_t>(iov[i].iov_len, size - filled);
    std::memcpy(sample->bytes + filled, iov[i].iov_base, n);
    filled += n;
  }
  return &sample->base;
}

ddsi_serdata* serdata_from_keyhash(const ddsi_sertype* sertype, const ddsi_keyhash*) {
  return header_only_sample(sertype);
}

// Exceptions must not unwind through Cyclone: a message that cannot be written fails the write.
bool sertype_serialize_into(const ddsi_sertype* sertype, const void* message, void* out,
                            std::size_t size) {
  try {
    type_of(sertype).serialize(message, std::span<uint8_t>(static_cast<uint8_t*>(out), size));
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

// A write: the message is serialized once, into the buffer Cyclone sends from.
ddsi_serdata* serdata_from_sample(const ddsi_sertype* sertype, ddsi_serdata_kind kind,
                                  const void* message) {
  if (kind != SDK_DATA) return header_only_sample(sertype);
  const std::size_t size = type_of(sertype).serialized_size(message);
  CdrSample* sample = new_sample(sertype, kind, size);
  if (sample == nullptr) return nullptr;
  if (!sertype_serialize_into(sertype, message, sample->bytes, size)) {
    serdata_free(&sample->base);
    return nullptr;
  }
  // Cyclone sends whole 4-byte words: the padding it adds is counted in the low bits of the
  // encapsulation options, as XTypes 1.3 (7.6.3.1.2) specifies, so that readers know the end.
  const auto padding = static_cast<uint8_t>((4 - size % 4) % 4);
  sample->bytes[3] |= padding;
  sample->size += padding;
  return &sample->base;
}

void serdata_to_ser(const ddsi_serdata* d, std::size_t offset, std::size_t size, void* out) {
  std::memcpy(out, as_sample(d)->bytes + offset, size);
}

ddsi_serdata* serdata_to_ser_ref(const ddsi_serdata* d, std::size_t offset, std::size_t size,
                                 ddsrt_iovec_t* ref) {
  ref->iov_base = as_sample(d)->bytes + offset;
  ref->iov_len = static_cast<ddsrt_iov_len_t>(size);
  return ddsi_serdata_ref(d);
}

void serdata_to_ser_unref(ddsi_serdata* d, const ddsrt_iovec_t*) {
  ddsi_serdata_unref(d);
}

// Decodes into a robotperf message; false (never an exception) when the payload is malformed.
bool serdata_to_sample(const ddsi_serdata* d, void* message, void**, void*) {
  const CdrSample* sample = as_sample(d);
  if (d->kind != SDK_DATA) return true;  // keyless: there are no key fields to fill in
  try {
    type_of(d->type).deserialize(std::span<const uint8_t>(sample->bytes, sample->size), message);
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

// Instances are looked up by key: keyless samples all share the empty one.
ddsi_serdata* serdata_to_untyped(const ddsi_serdata* d) {
  ddsi_serdata* key = header_only_sample(d->type);
  if (key != nullptr) key->type = nullptr;
  return key;
}

bool serdata_untyped_to_sample(const ddsi_sertype*, const ddsi_serdata*, void*, void**, void*) {
  return true;
}

std::size_t serdata_print(const ddsi_sertype* sertype, const ddsi_serdata* d, char* buf,
                          std::size_t size) {
  const int n = std::snprintf(buf, size, "%s, %u CDR bytes", type_of(sertype).ros_type.c_str(),
                              as_sample(d)->size);
  return n < 0 ? 0 : static_cast<std::size_t>(n);
}

void serdata_get_keyhash(const ddsi_serdata*, ddsi_keyhash* out, bool) {
  std::memset(out->value, 0, sizeof out->value);
}

const ddsi_serdata_ops kSerdataOps = {
    .eqkey = serdata_eqkey,
    .get_size = serdata_size,
    .from_ser = serdata_from_ser,
    .from_ser_iov = serdata_from_ser_iov,
    .from_keyhash = serdata_from_keyhash,
    .from_sample = serdata_from_sample,
    .to_ser = serdata_to_ser,
    .to_ser_ref = serdata_to_ser_ref,
    .to_ser_unref = serdata_to_ser_unref,
    .to_sample = serdata_to_sample,
    .to_untyped = serdata_to_untyped,
    .untyped_to_sample = serdata_untyped_to_sample,
    .free = serdata_free,
    .print = serdata_print,
    .get_keyhash = serdata_get_keyhash,
    .get_sample_size = nullptr,
    .from_iox_buffer = nullptr,
};

void sertype_free(ddsi_sertype* sertype) {
  ddsi_sertype_fini(sertype);
  delete reinterpret_cast<MessageSertype*>(sertype);
}

// The transport never lets Cyclone allocate or free application samples: it takes serialized
// samples (dds_takecdr) and writes its own messages. These satisfy the interface's contract for
// the cases Cyclone itself can reach: zeroing is a no-op, "arrays" are the caller's pointers.
void sertype_zero_samples(const ddsi_sertype*, void*, std::size_t) {}
void sertype_realloc_samples(void** ptrs, const ddsi_sertype*, void* old, std::size_t,
                             std::size_t) {
  ptrs[0] = old;
}
void sertype_free_samples(const ddsi_sertype*, void**, std::size_t, dds_free_op_t) {}

// Cyclone DDS shares equal sertypes across a domain's topics in this process. A type's typed and
// serialized (SerializedMessage) supports share its name but not its sample layout: each is its
// own sertype, so that a bag's Playback and the graph's nodes keep theirs.
bool sertype_equal(const ddsi_sertype* a, const ddsi_sertype* b) {
  return &type_of(a) == &type_of(b);
}
uint32_t sertype_hash(const ddsi_sertype* sertype) {
  return static_cast<uint32_t>(std::hash<std::string>{}(type_of(sertype).ros_type));
}

std::size_t sertype_serialized_size(const ddsi_sertype* sertype, const void* message) {
  return type_of(sertype).serialized_size(message);
}
const ddsi_sertype_ops kSertypeOps = {
    .version = ddsi_sertype_v0,
    .arg = nullptr,
    .free = sertype_free,
    .zero_samples = sertype_zero_samples,
    .realloc_samples = sertype_realloc_samples,
    .free_samples = sertype_free_samples,
    .equal = sertype_equal,
    .hash = sertype_hash,
    .type_id = nullptr,
    .type_map = nullptr,
    .type_info = nullptr,
    .derive_sertype = nullptr,
    .get_serialized_size = sertype_serialized_size,
    .serialize_into = sertype_serialize_into,
};

ddsi_sertype* new_sertype(const msgs::TypeSupport& type) {
  auto* sertype = new MessageSertype{};
  sertype->type = &type;
  ddsi_sertype_init_flags(&sertype->base, type.dds_type.c_str(), &kSertypeOps, &kSerdataOps,
                          DDSI_SERTYPE_FLAG_TOPICKIND_NO_KEY);
  sertype->base.allowed_data_representation = DDS_DATA_REPRESENTATION_FLAG_XCDR1;
  return &sertype->base;
}

// --- Entities ------------------------------------------------------------------------------------

std::string error_text(dds_return_t rc) {
  return dds_strretcode(rc);
}

// Owns one Cyclone entity (participant, topic, reader, writer, ...).
class Entity {
 public:
  explicit Entity(dds_entity_t handle = 0) : handle_(handle) {}
  Entity(const Entity&) = delete;
  Entity& operator=(const Entity&) = delete;
  ~Entity() {
    if (handle_ > 0) dds_delete(handle_);
  }
  dds_entity_t get() const { return handle_; }

 private:
  dds_entity_t handle_;
};

// A QoS object that frees itself.
using QosPtr = std::unique_ptr<dds_qos_t, decltype(&dds_delete_qos)>;
QosPtr new_qos() {
  return QosPtr(dds_create_qos(), &dds_delete_qos);
}

ParticipantId participant_id(const dds_guid_t& guid) {
  ParticipantId id;
  std::memcpy(id.data(), guid.v, id.size());
  return id;
}

// rmw's GID of an endpoint or participant: its 16-byte GUID.
Gid gid_of(const dds_guid_t& guid) {
  Gid gid{};
  std::memcpy(gid.data(), guid.v, gid.size());
  return gid;
}
Gid gid_of(dds_entity_t entity) {
  dds_guid_t guid{};
  dds_get_guid(entity, &guid);
  return gid_of(guid);
}

// The GID as ros2 tracepoints record it: zero-padded to RMW_GID_STORAGE_SIZE.
std::array<uint8_t, ROBOTPERF_ROS2_GID_STORAGE_SIZE> traced_gid(dds_entity_t endpoint) {
  std::array<uint8_t, ROBOTPERF_ROS2_GID_STORAGE_SIZE> out{};
  const Gid gid = gid_of(endpoint);
  std::memcpy(out.data(), gid.data(), gid.size());
  return out;
}

QosPtr endpoint_qos(const QoS& qos, const std::string& user_data) {
  QosPtr out = new_qos();
  if (!user_data.empty()) dds_qset_userdata(out.get(), user_data.data(), user_data.size());
  // A reliable writer whose readers do not keep up blocks at most this long, then fails the write.
  constexpr dds_duration_t kMaxBlocking = DDS_SECS(1);
  dds_qset_reliability(out.get(),
                       qos.reliability == Reliability::kReliable ? DDS_RELIABILITY_RELIABLE
                                                                 : DDS_RELIABILITY_BEST_EFFORT,
                       kMaxBlocking);
  dds_qset_durability(out.get(), qos.durability == Durability::kTransientLocal
                                     ? DDS_DURABILITY_TRANSIENT_LOCAL
                                     : DDS_DURABILITY_VOLATILE);
  const bool keep_last = qos.history == History::kKeepLast;
  const dds_history_kind_t history = keep_last ? DDS_HISTORY_KEEP_LAST : DDS_HISTORY_KEEP_ALL;
  // ROS 2 reads depth 0 as "system default", which is 1 in Cyclone DDS.
  const int32_t depth =
      keep_last ? static_cast<int32_t>(qos.depth == 0 ? 1 : qos.depth) : DDS_LENGTH_UNLIMITED;
  dds_qset_history(out.get(), history, depth);
  if (qos.durability == Durability::kTransientLocal) {
    // Cyclone keeps for late joiners what the durability service's history says (KEEP_LAST 1 by
    // default), not the writer's: the same as the history, as rmw_cyclonedds sets it.
    dds_qset_durability_service(out.get(), 0, history, depth, DDS_LENGTH_UNLIMITED,
                                DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
  }
  const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(out.get(), 1, &xcdr1);
  return out;
}

// What discovery tells about the other participants of the domain, read from Cyclone's built-in
// topics whenever asked.
class PeerDirectory {
 public:
  explicit PeerDirectory(dds_entity_t participant)
      : participants_(
            dds_create_reader(participant, DDS_BUILTIN_TOPIC_DCPSPARTICIPANT, nullptr, nullptr)),
        publications_(
            dds_create_reader(participant, DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr)),
        subscriptions_(
            dds_create_reader(participant, DDS_BUILTIN_TOPIC_DCPSSUBSCRIPTION, nullptr, nullptr)) {
    if (participants_.get() < 0 || publications_.get() < 0 || subscriptions_.get() < 0) {
      throw TransportError("cyclonedds: cannot read the built-in discovery topics");
    }
  }

  // Those announced so far but `self`, including those that have left since.
  std::vector<PeerParticipant> peers(const ParticipantId& self) {
    take_all<dds_builtintopic_participant_t>(
        participants_.get(), [&](const auto& p, const auto& info) {
          if (!info.valid_data) {  // it left: only its key is known
            table_.announce(participant_id(p.key));
            return;
          }
          table_.announce(participant_id(p.key), [&](PeerParticipant& peer) {
            void* bytes = nullptr;
            std::size_t size = 0;
            if (dds_qget_userdata(p.qos, &bytes, &size) && bytes != nullptr) {
              peer.user_data.assign(static_cast<const char*>(bytes), size);
            }
            dds_free(bytes);
            char* name = nullptr;
            if (dds_qget_entity_name(p.qos, &name) && name != nullptr) peer.name = name;
            dds_free(name);
          });
        });
    for (dds_entity_t reader : {publications_.get(), subscriptions_.get()}) {
      take_all<dds_builtintopic_endpoint_t>(reader, [&](const auto& e, const auto& info) {
        // An endpoint's GUID starts with its participant's prefix; one that left has only its key,
        // or, when its announcement was still unread, that announcement in a non-alive instance.
        const ParticipantId participant = participant_id(e.key);
        if (!info.valid_data || info.instance_state != DDS_IST_ALIVE) {
          table_.remove_endpoint(participant, gid_of(e.key));
        } else if (e.topic_name != nullptr) {
          table_.add_endpoint(participant, describe(e, reader == publications_.get()));
        }
      });
    }
    return table_.peers(self);
  }
  PeerTable& table() { return table_; }

 private:
  static PeerEndpoint describe(const dds_builtintopic_endpoint_t& e, bool writer) {
    PeerEndpoint endpoint;
    endpoint.gid = gid_of(e.key);
    endpoint.writer = writer;
    endpoint.topic = e.topic_name;
    if (e.type_name != nullptr) endpoint.dds_type = e.type_name;
    dds_reliability_kind_t reliability{};
    dds_duration_t max_blocking = 0;
    if (dds_qget_reliability(e.qos, &reliability, &max_blocking)) {
      endpoint.qos.reliability = reliability == DDS_RELIABILITY_RELIABLE ? Reliability::kReliable
                                                                         : Reliability::kBestEffort;
    }
    dds_durability_kind_t durability{};
    if (dds_qget_durability(e.qos, &durability)) {
      endpoint.qos.durability = durability == DDS_DURABILITY_VOLATILE ? Durability::kVolatile
                                                                      : Durability::kTransientLocal;
    }
    void* bytes = nullptr;
    std::size_t size = 0;
    if (dds_qget_userdata(e.qos, &bytes, &size) && bytes != nullptr) {
      endpoint.type_hash =
          user_data_value(std::string_view(static_cast<const char*>(bytes), size), "typehash");
    }
    dds_free(bytes);
    return endpoint;
  }

  template <class Sample, class Visit>
  static void take_all(dds_entity_t reader, Visit visit) {
    constexpr std::size_t kBatch = 16;
    while (true) {
      std::array<void*, kBatch> samples{};
      std::array<dds_sample_info_t, kBatch> infos{};
      const dds_return_t n = dds_take(reader, samples.data(), infos.data(), kBatch, kBatch);
      if (n <= 0) return;
      for (dds_return_t i = 0; i < n; ++i) {
        visit(*static_cast<const Sample*>(samples[i]), infos[i]);
      }
      dds_return_loan(reader, samples.data(), n);
    }
  }

  Entity participants_, publications_, subscriptions_;
  PeerTable table_;
};

// Cyclone's defaults, but for the sockets' receive buffers: up to 8 MiB where the system allows
// (net.core.rmem_max), from 1 MiB. Fast DDS sends a large sample as one burst of 64 KiB
// fragments; a fragment the socket drops is never repaired by a Cyclone 0.10 reader (it
// acknowledges the sample before it is complete), so the buffer must hold the largest burst.
// The domain's configuration: large receive buffers, and ROS_STATIC_PEERS as rmw_cyclonedds adds
// them: unicast discovery peers beside multicast, reached at the ports of a participant index,
// which each participant then takes (Cyclone's default leaves it unknowable to the peers).
std::string domain_config() {
  std::string discovery;
  const std::vector<std::string> peers = static_peers_from_environment();
  if (!peers.empty()) {
    discovery =
        "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
        "<MaxAutoParticipantIndex>32</MaxAutoParticipantIndex><Peers>";
    for (const auto& peer : peers) discovery += "<Peer address=\"" + peer + "\"/>";
    discovery += "</Peers></Discovery>";
  }
  return "<CycloneDDS><Domain><Internal><SocketReceiveBufferSize min=\"default\" max=\"8MiB\"/>"
         "</Internal>" +
         discovery + "</Domain></CycloneDDS>";
}

// The domains this process created with domain_config(), shared by its participants: Cyclone
// deletes an explicitly created domain (and everything in it) only when told to, so the last
// participant on it does. Without CYCLONEDDS_URI only: the user's configuration otherwise applies
// as is.
//
// It also keeps the participants of one domain alike in DDS Security. Cyclone DDS 0.10 delivers
// between the participants of one process directly, without authentication or access control, and
// a domain that has both secured and unsecured participants crashes it (creating a topic after a
// secured participant joined unsecured ones dereferences null) or refuses the unsecured one.
class DomainRegistry {
 public:
  static DomainRegistry& instance() {
    static DomainRegistry registry;
    return registry;
  }
  // `security`: the DDS Security of the participant about to join (nullopt: none).
  void acquire(dds_domainid_t id, const std::optional<SecurityFiles>& security) {
    std::lock_guard lock(mutex_);
    if (auto it = domains_.find(id); it != domains_.end()) {
      if (it->second.security != security) throw mixed_security(id, it->second.security, security);
      ++it->second.users;
      return;
    }
    Domain domain{.security = security};
    const char* uri = std::getenv("CYCLONEDDS_URI");
    if (uri == nullptr || *uri == '\0') {
      domain.handle = dds_create_domain(id, domain_config().c_str());
      if (domain.handle < 0) {
        throw TransportError("cyclonedds: cannot create domain " + std::to_string(id) + ": " +
                             error_text(domain.handle));
      }
    }
    domains_.emplace(id, std::move(domain));
  }
  void release(dds_domainid_t id) {
    std::lock_guard lock(mutex_);
    auto it = domains_.find(id);
    if (it == domains_.end() || --it->second.users > 0) return;
    if (it->second.handle > 0) dds_delete(it->second.handle);
    domains_.erase(it);
  }

 private:
  struct Domain {
    std::optional<SecurityFiles> security;
    dds_entity_t handle = 0;  // 0: Cyclone's own, configured by CYCLONEDDS_URI
    int users = 1;
  };

  static std::string security_text(const std::optional<SecurityFiles>& security) {
    return security ? "DDS Security (enclave " + security->enclave + " of " +
                          security->certificate.parent_path().string() + ")"
                    : "no DDS Security";
  }
  static TransportError mixed_security(dds_domainid_t id,
                                       const std::optional<SecurityFiles>& present,
                                       const std::optional<SecurityFiles>& joining) {
    return TransportError("cyclonedds: the participants of this process on domain " +
                          std::to_string(id) + " have " + security_text(present) +
                          "; Cyclone DDS 0.10 cannot add one with " + security_text(joining) +
                          " to them (use another domain or process)");
  }

  std::mutex mutex_;
  std::map<dds_domainid_t, Domain> domains_;
};

// Holds this participant's use of its domain.
class DomainUse {
 public:
  DomainUse(int id, const std::optional<SecurityFiles>& security)
      : id_(static_cast<dds_domainid_t>(id)) {
    DomainRegistry::instance().acquire(id_, security);
  }
  DomainUse(const DomainUse&) = delete;
  DomainUse& operator=(const DomainUse&) = delete;
  ~DomainUse() { DomainRegistry::instance().release(id_); }

 private:
  dds_domainid_t id_;
};

// A DDS Security plug-in of Cyclone DDS (libdds_security_<name>.so), by full path: the one beside
// the libddsc this process runs. Debian installs them in a folder of their own (libddsc0debian/),
// off the loader's path; its libddsc falls back to that folder for a bare name
// ("dds_security_auth", as rmw_cyclonedds gives it), other builds need not, and a copy on the
// loader's path would win.
std::string security_plugin(const std::string& name) {
  const std::string file = "libdds_security_" + name + ".so";
  Dl_info loaded{};
  if (dladdr(reinterpret_cast<void*>(&dds_create_participant), &loaded) == 0 ||
      loaded.dli_fname == nullptr) {
    throw TransportError("cyclonedds: cannot find where libddsc is loaded from, to load " + file);
  }
  const std::filesystem::path folder = std::filesystem::path(loaded.dli_fname).parent_path();
  for (const auto& candidate : {folder / "libddsc0debian" / file, folder / file}) {
    std::error_code ignored;
    if (std::filesystem::is_regular_file(candidate, ignored)) return candidate.string();
  }
  throw TransportError("cyclonedds: DDS Security plug-in " + file + " not found in " +
                       (folder / "libddsc0debian").string() + " nor " + folder.string() +
                       " (Debian package libddsc0debian)");
}

// DDS Security with Cyclone's built-in plug-ins (PKI-DH authentication, Access-Permissions
// access control, AES-GCM-GMAC encryption), configured through participant properties as
// rmw_cyclonedds configures them. Property names: dds/security/dds_security_api_defs.h.
void add_security(const SecurityFiles& files, dds_qos_t* qos) {
  auto uri = [](const std::filesystem::path& file) { return "file:" + file.string(); };
  // The plug-in libraries and their entry points (plug-in name, library suffix, entry suffix).
  for (const auto& [plugin, library, entry] :
       {std::tuple{"auth", "auth", "authentication"}, std::tuple{"access", "ac", "access_control"},
        std::tuple{"crypto", "crypto", "crypto"}}) {
    const std::string prefix = std::string("dds.sec.") + plugin + ".library.";
    dds_qset_prop(qos, (prefix + "path").c_str(), security_plugin(library).c_str());
    dds_qset_prop(qos, (prefix + "init").c_str(), (std::string("init_") + entry).c_str());
    dds_qset_prop(qos, (prefix + "finalize").c_str(), (std::string("finalize_") + entry).c_str());
  }
  dds_qset_prop(qos, "dds.sec.auth.identity_ca", uri(files.identity_ca).c_str());
  dds_qset_prop(qos, "dds.sec.auth.identity_certificate", uri(files.certificate).c_str());
  dds_qset_prop(qos, "dds.sec.auth.private_key", uri(files.private_key).c_str());
  dds_qset_prop(qos, "dds.sec.access.permissions_ca", uri(files.permissions_ca).c_str());
  dds_qset_prop(qos, "dds.sec.access.governance", uri(files.governance).c_str());
  dds_qset_prop(qos, "dds.sec.access.permissions", uri(files.permissions).c_str());
}

// The participant and its topics. Publisher and subscription handles keep it alive, so they may
// outlive their Transport.
class Participant {
 public:
  explicit Participant(const TransportOptions& options)
      : domain_(options.domain_id, options.security),
        participant_(create_participant(options)),
        peers_(participant_.get()) {
    dds_guid_t guid;
    if (dds_get_guid(participant_.get(), &guid) != DDS_RETCODE_OK) {
      throw TransportError("cyclonedds: cannot read the participant's GUID");
    }
    id_ = participant_id(guid);
    nodes_.emplace(gid_of(guid), options.ros_distro);
  }

  dds_entity_t handle() const { return participant_.get(); }
  ParticipantId id() const { return id_; }
  std::vector<PeerParticipant> peers() { return peers_.peers(id_); }
  PeerTable& peer_table() { return peers_.table(); }
  LocalNodes& nodes() { return *nodes_; }

  // The topic, created on first use; a second type is an error. Endpoints of one type name with
  // different TypeSupports (typed, serialized) get a topic entity each, with its own sertype, so
  // that each (de)serializes its own messages.
  dds_entity_t topic(const EndpointTopic& endpoint_topic, const msgs::TypeSupport& type) {
    const std::string& dds_name = endpoint_topic.dds_name;
    std::lock_guard lock(mutex_);
    auto it = topics_.find(dds_name);
    if (it != topics_.end()) {
      if (it->second.dds_type != type.dds_type) {
        throw TransportError("cyclonedds: topic " + endpoint_topic.name + " already has type " +
                             it->second.dds_type + ", not " + type.dds_type);
      }
      if (auto entity = it->second.entities.find(&type); entity != it->second.entities.end())
        return entity->second->get();
    }
    ddsi_sertype* sertype = new_sertype(type);
    // Cyclone takes the sertype over (or replaces it with an equal one it already has).
    const dds_entity_t topic = dds_create_topic_sertype(participant_.get(), dds_name.c_str(),
                                                        &sertype, nullptr, nullptr, nullptr);
    if (topic < 0) {
      throw TransportError("cyclonedds: cannot create topic " + dds_name + ": " +
                           error_text(topic));
    }
    auto& entry = topics_[dds_name];
    entry.dds_type = type.dds_type;
    entry.entities.emplace(&type, std::make_unique<Entity>(topic));
    return topic;
  }

 private:
  static dds_entity_t create_participant(const TransportOptions& options) {
    check_secured_domain("cyclonedds", options);
    QosPtr qos = new_qos();
    const std::string user_data = participant_user_data(options);
    dds_qset_userdata(qos.get(), user_data.data(), user_data.size());
    dds_qset_entity_name(qos.get(), "robotperf");
    if (options.security) add_security(*options.security, qos.get());
    // The domain's configuration comes from CYCLONEDDS_URI when set, as with rmw_cyclonedds.
    const dds_entity_t participant =
        dds_create_participant(static_cast<dds_domainid_t>(options.domain_id), qos.get(), nullptr);
    if (participant < 0) {
      throw TransportError(
          "cyclonedds: cannot create a participant on domain " + std::to_string(options.domain_id) +
          ": " + error_text(participant) +
          (options.security
               ? " (DDS Security, enclave " + options.security->enclave +
                     ": are its keystore files valid, its permissions for this domain?)"
               : " (check CYCLONEDDS_URI, if set)"));
    }
    return participant;
  }

  struct TopicEntry {
    std::string dds_type;
    std::map<const msgs::TypeSupport*, std::unique_ptr<Entity>> entities;
  };

  DomainUse domain_;  // first: the domain outlives the participant
  Entity participant_;
  PeerDirectory peers_;
  ParticipantId id_{};
  std::optional<LocalNodes> nodes_;
  std::mutex mutex_;
  std::map<std::string, TopicEntry> topics_;
};

// Throws when Cyclone could not create the endpoint; otherwise traces its creation.
template <class Handle>
void check_endpoint(dds_entity_t endpoint, const Handle* handle, const std::string& topic) {
  constexpr bool kPublisher = std::is_base_of_v<PublisherHandle, Handle>;
  if (endpoint < 0) {
    throw TransportError(std::string("cyclonedds: cannot create a ") +
                         (kPublisher ? "writer" : "reader") + " on " + topic + ": " +
                         error_text(endpoint));
  }
  if constexpr (kPublisher) {
    if (lttng_ust_tracepoint_enabled(ros2, rmw_publisher_init)) {
      lttng_ust_do_tracepoint(ros2, rmw_publisher_init, handle, traced_gid(endpoint).data());
    }
  } else if (lttng_ust_tracepoint_enabled(ros2, rmw_subscription_init)) {
    lttng_ust_do_tracepoint(ros2, rmw_subscription_init, handle, traced_gid(endpoint).data());
  }
}

class CycloneddsPublisher final : public PublisherHandle {
 public:
  CycloneddsPublisher(std::shared_ptr<Participant> participant, const EndpointTopic& topic,
                      const msgs::TypeSupport& type, const QoS& qos, const NodeName& node)
      : participant_(std::move(participant)),
        topic_(topic.name),
        writer_(dds_create_writer(
            participant_->handle(), participant_->topic(topic, type),
            endpoint_qos(qos, endpoint_user_data(type, participant_->nodes().distro())).get(),
            nullptr)) {
    check_endpoint(writer_.get(), this, topic_);
    node_.emplace(participant_->nodes(), node, gid_of(writer_.get()), true);
  }

  void publish(MessagePtr msg) override {
    if (!msg) throw TransportError("cyclonedds: cannot publish a null message on " + topic_);
    // The source timestamp is taken here so that rmw_publish and the subscriber's rmw_take carry
    // the same one, traced or not.
    const int64_t now = wall_now_ns();
    lttng_ust_tracepoint(ros2, rmw_publish, this, msg.get(), now);
    const dds_return_t rc = dds_write_ts(writer_.get(), msg.get(), now);
    if (rc != DDS_RETCODE_OK) {
      throw TransportError(
          "cyclonedds: write on " + topic_ + " failed: " + error_text(rc) +
          (rc == DDS_RETCODE_TIMEOUT ? " (reliable readers did not acknowledge within 1 s)" : ""));
    }
  }

  std::size_t matched_subscriptions() const override {
    dds_publication_matched_status_t status{};
    dds_get_publication_matched_status(writer_.get(), &status);
    return status.current_count;
  }

 private:
  // Declared first: destroyed last, after the writer it created.
  std::shared_ptr<Participant> participant_;
  std::string topic_;
  Entity writer_;
  std::optional<NodeEndpoint> node_;  // last: withdrawn before the writer is deleted
};

class CycloneddsSubscription;
using ListenerPtr = std::unique_ptr<dds_listener_t, decltype(&dds_delete_listener)>;
ListenerPtr data_available_listener(CycloneddsSubscription* subscription);

class CycloneddsSubscription final : public SubscriptionHandle {
 public:
  CycloneddsSubscription(std::shared_ptr<Participant> participant, const EndpointTopic& topic,
                         const msgs::TypeSupport& type, const QoS& qos,
                         std::function<void()> on_ready, const NodeName& node)
      : participant_(std::move(participant)),
        topic_(topic.name),
        type_(type),
        on_ready_(std::move(on_ready)),
        reader_(dds_create_reader(
            participant_->handle(), participant_->topic(topic, type),
            endpoint_qos(qos, endpoint_user_data(type, participant_->nodes().distro())).get(),
            data_available_listener(this).get())) {
    check_endpoint(reader_.get(), this, topic_);
    node_.emplace(participant_->nodes(), node, gid_of(reader_.get()), false);
  }
  ~CycloneddsSubscription() override {
    // No listener call may reach a subscription being destroyed.
    dds_set_listener(reader_.get(), nullptr);
  }

  void notify() { on_ready_(); }

  MessagePtr take(MessageInfo* info) override {
    while (true) {
      ddsi_serdata* data = nullptr;
      dds_sample_info_t sample_info{};
      const dds_return_t n = dds_takecdr(reader_.get(), &data, 1, &sample_info, DDS_ANY_STATE);
      if (n == 0) return nullptr;
      if (n < 0) {
        throw TransportError("cyclonedds: take on " + topic_ + " failed: " + error_text(n));
      }
      std::unique_ptr<ddsi_serdata, decltype(&ddsi_serdata_unref)> hold(data, &ddsi_serdata_unref);
      // Samples without data only announce writer/instance state changes.
      if (!sample_info.valid_data) continue;
      std::shared_ptr<void> msg = type_.create();
      // A malformed payload is dropped, as a DDS reader drops it.
      if (!serdata_to_sample(data, msg.get(), nullptr, nullptr)) continue;
      lttng_ust_tracepoint(ros2, rmw_take, this, msg.get(), sample_info.source_timestamp, 1);
      if (info != nullptr) {
        info->source_timestamp_ns = sample_info.source_timestamp;
        info->reception_timestamp_ns = as_sample(data)->reception_ns;
        info->from_intra_process = false;
        info->sender = sender_of(sample_info.publication_handle);
      }
      return msg;
    }
  }

  std::size_t matched_publishers() const override {
    dds_subscription_matched_status_t status{};
    dds_get_subscription_matched_status(reader_.get(), &status);
    return status.current_count;
  }

 private:
  // The participant of a matched writer, looked up once per writer.
  ParticipantId sender_of(dds_instance_handle_t writer) {
    if (auto it = senders_.find(writer); it != senders_.end()) return it->second;
    ParticipantId id{};
    if (dds_builtintopic_endpoint_t* e = dds_get_matched_publication_data(reader_.get(), writer)) {
      id = participant_id(e->participant_key);
      dds_builtintopic_free_endpoint(e);
    }
    senders_.emplace(writer, id);
    return id;
  }

  std::shared_ptr<Participant> participant_;
  std::string topic_;
  const msgs::TypeSupport& type_;
  std::function<void()> on_ready_;
  Entity reader_;
  std::map<dds_instance_handle_t, ParticipantId> senders_;
  std::optional<NodeEndpoint> node_;  // last: withdrawn before the reader is deleted
};

// Cyclone copies the listener into the reader, which calls `notify` from its receive threads.
ListenerPtr data_available_listener(CycloneddsSubscription* subscription) {
  ListenerPtr listener(dds_create_listener(subscription), &dds_delete_listener);
  dds_lset_data_available(listener.get(), [](dds_entity_t, void* self) {
    static_cast<CycloneddsSubscription*>(self)->notify();
  });
  return listener;
}

}  // namespace

std::shared_ptr<void> use_cyclonedds_domain(int domain_id) {
  return std::make_shared<DomainUse>(domain_id, std::nullopt);
}

std::unique_ptr<Transport> make_cyclonedds_transport(const TransportOptions& options) {
  return std::make_unique<
      ParticipantTransport<Participant, CycloneddsPublisher, CycloneddsSubscription>>("cyclonedds",
                                                                                      options);
}

}  // namespace robotperf::rmw
