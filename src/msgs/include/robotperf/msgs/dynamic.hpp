// A CDR codec driven by .msg definitions: decodes a message of any type whose
// definition is known into a tree of values, and encodes the tree back to the
// same bytes. Definitions come from a folder of .msg files, one .msg text, or
// a bag's "ros2msg" schema (the type's .msg followed by its dependencies).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

namespace robotperf::msgs::dynamic {

// A definition that cannot be parsed or a type whose definition is unknown.
class DefinitionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class Primitive {
  kBool,
  kByte,
  kChar,
  kInt8,
  kUint8,
  kInt16,
  kUint16,
  kInt32,
  kUint32,
  kInt64,
  kUint64,
  kFloat32,
  kFloat64,
  kString,
  kWString,
  kMessage,  // a nested message, named by FieldType::message_type
};

enum class ArrayKind { kNone, kFixed, kBounded, kUnbounded };

struct FieldType {
  Primitive primitive = Primitive::kInt32;
  std::string message_type;  // "pkg/msg/Type" when primitive == kMessage
  ArrayKind array = ArrayKind::kNone;
  std::size_t array_size = 0;    // the size (fixed) or the bound (bounded)
  std::size_t string_bound = 0;  // N of string<=N (wstring<=N); 0: unbounded
};

struct Field {
  std::string name;
  FieldType type;
};

struct MessageDefinition {
  std::string type;  // "pkg/msg/Type"
  std::vector<Field> fields;
  std::string text;  // the .msg text it was parsed from
};

// "pkg/Type" or "pkg/msg/Type" -> "pkg/msg/Type".
std::string normalize_type_name(std::string_view name);

// Parses one .msg text; nested types without a package are in `type`'s package.
MessageDefinition parse_msg(const std::string& type, std::string_view text);

class TypeRegistry {
 public:
  void add(MessageDefinition definition);
  void add_msg(const std::string& type, std::string_view text) { add(parse_msg(type, text)); }
  // A bag schema: `type`'s .msg, then "====...\nMSG: pkg/Type\n<text>" sections. A section
  // holding a .srv or .action text defines the types derived from it (add_interface); Jazzy's
  // schema of a service event type has no text of its own and starts with such a section
  // ("SRV: pkg/srv/Name").
  void add_ros2msg(const std::string& type, std::string_view schema);
  // A service's (pkg/srv/...) or action's (pkg/action/...) text, named by any type derived from
  // it: defines <Name>_Request, _Response and _Event (ServiceEventInfo info, request[<=1],
  // response[<=1]), or for actions <Name>_Goal, _Result, _Feedback, _FeedbackMessage and the
  // _SendGoal and _GetResult services with their events.
  void add_interface(const std::string& type, std::string_view text);
  // Every .msg (.srv, .action) under `dir`: as <pkg>/msg/<Type>.msg, or directly in `dir` (then in
  // package `package`, default the folder's name, or its parent's for a folder named "msg").
  // Returns how many.
  std::size_t add_directory(const std::filesystem::path& dir, const std::string& package = "");
  // Defines `type` and the types it needs that are still unknown from .msg (.srv, .action) files
  // a flat folder gave without a package (add_directory with no `package`), matched by name: a
  // flat folder of test_msgs files serves test_msgs/msg/Arrays whatever the folder is called, and
  // one holding AddTwoInts.srv serves example_interfaces/srv/AddTwoInts_Event. Returns how many.
  std::size_t adopt(const std::string& type);

  bool contains(const std::string& type) const;
  // Throws DefinitionError naming the type, and what needs it, when unknown.
  const MessageDefinition& get(const std::string& type) const;
  // Checks that every type `type` depends on is known.
  void check_complete(const std::string& type) const;
  // `type`'s definition as a bag's ros2msg schema: its .msg text, then each type it depends on
  // as "====...\nMSG: pkg/Type\n<text>". Throws DefinitionError when one is unknown.
  std::string ros2msg_schema(const std::string& type) const;

 private:
  std::map<std::string, MessageDefinition> types_;
  // "msg/Name", "srv/Name" or "action/Name" -> the file's text, from flat folders.
  std::map<std::string, std::string> unpackaged_;
};

struct Value;
using Struct = std::vector<std::pair<std::string, Value>>;
using List = std::vector<Value>;
using Bytes = std::vector<uint8_t>;

// Integers keep their signedness, float32 and float64 are held as double
// (exact), byte-sized arrays as Bytes, wstrings as UTF-32 code units.
struct Value {
  std::variant<bool, int64_t, uint64_t, double, std::string, std::u32string, Bytes, List, Struct>
      data;

  // The field `name` of a struct value; throws std::out_of_range.
  const Value& operator[](const std::string& name) const;
  Value& operator[](const std::string& name);
};

// Decodes a CDR payload (with its 4-byte header); throws CdrError when
// malformed and DefinitionError when a type is unknown.
Value decode(const TypeRegistry& registry, const std::string& type,
             std::span<const uint8_t> payload);
// Encodes back: the bytes decode() read, with alignment padding written as
// zeros and no trailing padding.
std::vector<uint8_t> encode(const TypeRegistry& registry, const std::string& type,
                            const Value& value);

// YAML text like `ros2 topic echo`; arrays longer than `max_array` elements
// are summarised.
std::string to_yaml(const Value& value, std::size_t max_array = 64);

}  // namespace robotperf::msgs::dynamic
