#include "robotperf/msgs/type_hash.hpp"

#include <openssl/evp.h>

#include <array>
#include <map>
#include <mutex>
#include <set>
#include <stdexcept>
#include <vector>

#include "robotperf/msgs/definitions.hpp"

namespace robotperf::msgs {
namespace {

using dynamic::ArrayKind;
using dynamic::Primitive;

// type_description_interfaces/msg/FieldType's ids. A .msg `char` is an IDL uint8 and `byte` an
// octet, as rosidl_adapter translates them.
int base_type_id(const dynamic::FieldType& t) {
  switch (t.primitive) {
    case Primitive::kMessage:
      return 1;
    case Primitive::kInt8:
      return 2;
    case Primitive::kUint8:
    case Primitive::kChar:
      return 3;
    case Primitive::kInt16:
      return 4;
    case Primitive::kUint16:
      return 5;
    case Primitive::kInt32:
      return 6;
    case Primitive::kUint32:
      return 7;
    case Primitive::kInt64:
      return 8;
    case Primitive::kUint64:
      return 9;
    case Primitive::kFloat32:
      return 10;
    case Primitive::kFloat64:
      return 11;
    case Primitive::kBool:
      return 15;
    case Primitive::kByte:
      return 16;
    case Primitive::kString:
      return t.string_bound > 0 ? 21 : 17;
    case Primitive::kWString:
      return t.string_bound > 0 ? 22 : 18;
  }
  throw std::logic_error("unhandled primitive");
}

int type_id(const dynamic::FieldType& t) {
  switch (t.array) {
    case ArrayKind::kNone:
      return base_type_id(t);
    case ArrayKind::kFixed:
      return base_type_id(t) + 48;
    case ArrayKind::kBounded:
      return base_type_id(t) + 96;
    case ArrayKind::kUnbounded:
      return base_type_id(t) + 144;
  }
  throw std::logic_error("unhandled array kind");
}

void append_field(std::string& out, const std::string& name, const dynamic::FieldType& t) {
  const std::size_t capacity =
      t.array == ArrayKind::kFixed || t.array == ArrayKind::kBounded ? t.array_size : 0;
  out += "{\"name\": \"" + name + "\", \"type\": {\"type_id\": " + std::to_string(type_id(t)) +
         ", \"capacity\": " + std::to_string(capacity) +
         ", \"string_capacity\": " + std::to_string(t.string_bound) + ", \"nested_type_name\": \"" +
         t.message_type + "\"}}";
}

// {"type_name": ..., "fields": [...]}. An empty message has the one member IDL gives it.
void append_individual(std::string& out, const dynamic::MessageDefinition& def) {
  out += "{\"type_name\": \"" + def.type + "\", \"fields\": [";
  if (def.fields.empty()) {
    dynamic::FieldType placeholder;
    placeholder.primitive = Primitive::kUint8;
    append_field(out, "structure_needs_at_least_one_member", placeholder);
  }
  for (std::size_t i = 0; i < def.fields.size(); ++i) {
    if (i > 0) out += ", ";
    append_field(out, def.fields[i].name, def.fields[i].type);
  }
  out += "]}";
}

// With a stack of its own: a schema can chain types deeper than the call stack goes.
void collect_referenced(const dynamic::TypeRegistry& registry, const std::string& type,
                        std::set<std::string>& found) {
  std::vector<std::string> todo{type};
  while (!todo.empty()) {
    const std::string t = std::move(todo.back());
    todo.pop_back();
    for (const auto& field : registry.get(t).fields) {
      if (field.type.primitive == Primitive::kMessage &&
          found.insert(field.type.message_type).second) {
        todo.push_back(field.type.message_type);
      }
    }
  }
}

std::string sha256_hex(const std::string& text) {
  std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
  unsigned int size = 0;
  if (EVP_Digest(text.data(), text.size(), digest.data(), &size, EVP_sha256(), nullptr) != 1) {
    throw std::runtime_error("SHA-256 failed (libcrypto)");
  }
  static constexpr char kHex[] = "0123456789abcdef";
  std::string hex;
  for (unsigned int i = 0; i < size; ++i) {
    hex += kHex[digest[i] >> 4];
    hex += kHex[digest[i] & 0xf];
  }
  return hex;
}

}  // namespace

std::string type_description_json(const dynamic::TypeRegistry& registry, const std::string& type) {
  std::set<std::string> referenced;  // sorted by name, as REP 2011 orders them
  collect_referenced(registry, type, referenced);
  std::string out = "{\"type_description\": ";
  append_individual(out, registry.get(type));
  out += ", \"referenced_type_descriptions\": [";
  bool first = true;
  for (const auto& name : referenced) {
    if (!first) out += ", ";
    first = false;
    append_individual(out, registry.get(name));
  }
  out += "]}";
  return out;
}

std::string type_hash(const dynamic::TypeRegistry& registry, const std::string& type) {
  return "RIHS01_" + sha256_hex(type_description_json(registry, type));
}

std::optional<std::string> builtin_type_hash(std::string_view ros_type) {
  static std::mutex mutex;
  static std::map<std::string, std::optional<std::string>, std::less<>> cache;
  std::lock_guard lock(mutex);
  if (auto it = cache.find(ros_type); it != cache.end()) return it->second;
  std::optional<std::string> hash;
  if (const auto schema = ros2msg_schema(ros_type)) {
    dynamic::TypeRegistry registry;
    registry.add_ros2msg(std::string(ros_type), *schema);
    hash = type_hash(registry, std::string(ros_type));
  }
  cache.emplace(std::string(ros_type), hash);
  return hash;
}

}  // namespace robotperf::msgs
