#include "robotperf/msgs/dynamic.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

#include "robotperf/msgs/cdr.hpp"
#include "robotperf/msgs/definitions.hpp"

namespace robotperf::msgs::dynamic {
namespace {

namespace fs = std::filesystem;

const std::map<std::string_view, Primitive>& primitive_names() {
  static const std::map<std::string_view, Primitive> names{
      {"bool", Primitive::kBool},       {"byte", Primitive::kByte},
      {"char", Primitive::kChar},       {"int8", Primitive::kInt8},
      {"uint8", Primitive::kUint8},     {"int16", Primitive::kInt16},
      {"uint16", Primitive::kUint16},   {"int32", Primitive::kInt32},
      {"uint32", Primitive::kUint32},   {"int64", Primitive::kInt64},
      {"uint64", Primitive::kUint64},   {"float32", Primitive::kFloat32},
      {"float64", Primitive::kFloat64}, {"string", Primitive::kString},
      {"wstring", Primitive::kWString},
  };
  return names;
}

// The parts of a .srv (request, response) or .action (goal, result, feedback) text: the lines
// between separator lines "---". A .msg text is one part.
std::vector<std::string> interface_parts(std::string_view text) {
  std::vector<std::string> parts(1);
  std::istringstream lines{std::string(text)};
  std::string line;
  while (std::getline(lines, line)) {
    const auto begin = line.find_first_not_of(" \t\r");
    const auto end = line.find_last_not_of(" \t\r");
    if (begin != std::string::npos && line.substr(begin, end - begin + 1) == "---") {
      parts.emplace_back();
    } else {
      parts.back() += line + "\n";
    }
  }
  return parts;
}

// Definitions of the standard types services and actions are built from, for bags whose schemas
// do not carry them: robotperf's compiled-in ones, and these two.
std::string standard_definition(const std::string& type) {
  if (type == "service_msgs/msg/ServiceEventInfo") {
    return "uint8 REQUEST_SENT = 0\nuint8 REQUEST_RECEIVED = 1\nuint8 RESPONSE_SENT = 2\n"
           "uint8 RESPONSE_RECEIVED = 3\nuint8 event_type\nbuiltin_interfaces/Time stamp\n"
           "char[16] client_gid\nint64 sequence_number\n";
  }
  if (type == "unique_identifier_msgs/msg/UUID") return "uint8[16] uuid\n";
  return ros2msg_schema(type).value();
}

// The service's or action's name in the name of a type derived from it ("AddTwoInts" for
// "AddTwoInts_Event"); a name without a derived type's suffix is the interface's own.
std::string interface_name(std::string name) {
  static const char* const kSuffixes[] = {"_SendGoal_Request",
                                          "_SendGoal_Response",
                                          "_SendGoal_Event",
                                          "_GetResult_Request",
                                          "_GetResult_Response",
                                          "_GetResult_Event",
                                          "_FeedbackMessage",
                                          "_Request",
                                          "_Response",
                                          "_Event",
                                          "_Goal",
                                          "_Result",
                                          "_Feedback"};
  for (const char* suffix : kSuffixes) {
    if (name.size() > std::strlen(suffix) && name.ends_with(suffix)) {
      name.resize(name.size() - std::strlen(suffix));
      break;
    }
  }
  return name;
}

std::string package_of(const std::string& type) {
  return type.substr(0, type.find('/'));
}

std::size_t parse_size(std::string_view text, const std::string& context) {
  std::size_t n = 0;
  if (text.empty()) throw DefinitionError(context + ": missing array size");
  for (char c : text) {
    if (c < '0' || c > '9')
      throw DefinitionError(context + ": bad array size '" + std::string(text) + "'");
    n = n * 10 + static_cast<std::size_t>(c - '0');
    if (n > (1u << 30)) throw DefinitionError(context + ": array size too large");
  }
  return n;
}

FieldType parse_type(std::string_view token, const std::string& package,
                     const std::string& context) {
  FieldType t;
  if (const auto open = token.find('['); open != std::string_view::npos) {
    if (token.back() != ']') throw DefinitionError(context + ": malformed array type");
    const std::string_view inside = token.substr(open + 1, token.size() - open - 2);
    if (inside.empty()) {
      t.array = ArrayKind::kUnbounded;
    } else if (inside.starts_with("<=")) {
      t.array = ArrayKind::kBounded;
      t.array_size = parse_size(inside.substr(2), context);
    } else {
      t.array = ArrayKind::kFixed;
      t.array_size = parse_size(inside, context);
    }
    token = token.substr(0, open);
  }
  // Bounded strings (string<=N) encode as plain strings; the bound is part of the type's hash.
  if (const auto bound = token.find("<="); bound != std::string_view::npos) {
    t.string_bound = parse_size(token.substr(bound + 2), context);
    token = token.substr(0, bound);
    if (token != "string" && token != "wstring")
      throw DefinitionError(context + ": only strings can be bounded");
  }
  if (auto it = primitive_names().find(token); it != primitive_names().end()) {
    t.primitive = it->second;
    return t;
  }
  if (token.empty()) throw DefinitionError(context + ": missing type");
  for (char c : token) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '/'))
      throw DefinitionError(context + ": bad type name '" + std::string(token) + "'");
  }
  t.primitive = Primitive::kMessage;
  if (token == "Header") {
    t.message_type = "std_msgs/msg/Header";
  } else if (token.find('/') == std::string_view::npos) {
    t.message_type = package + "/msg/" + std::string(token);
  } else {
    t.message_type = normalize_type_name(token);
  }
  return t;
}

template <class T>
Value integer(T v) {
  if constexpr (std::is_signed_v<T>) {
    return Value{static_cast<int64_t>(v)};
  } else {
    return Value{static_cast<uint64_t>(v)};
  }
}

class Decoder {
 public:
  Decoder(const TypeRegistry& registry, std::span<const uint8_t> payload)
      : registry_(registry), reader_(payload) {}

  Value message(const std::string& type, int depth) {
    if (depth > 64) throw DefinitionError(type + ": nesting deeper than 64 levels");
    const MessageDefinition& def = registry_.get(type);
    Struct out;
    if (def.fields.empty()) {
      uint8_t placeholder;
      reader_(placeholder);
      return Value{std::move(out)};
    }
    for (const Field& f : def.fields) out.emplace_back(f.name, field(f.type, depth));
    return Value{std::move(out)};
  }

 private:
  Value field(const FieldType& t, int depth) {
    if (t.array == ArrayKind::kNone) return single(t, depth);
    std::size_t n = t.array_size;
    if (t.array != ArrayKind::kFixed) {
      uint32_t count;
      reader_(count);
      if (count > reader_.remaining())
        throw CdrError("CDR sequence length " + std::to_string(count) + " exceeds payload");
      if (t.array == ArrayKind::kBounded && count > t.array_size) {
        throw CdrError("CDR sequence of " + std::to_string(count) + " elements exceeds its bound " +
                       std::to_string(t.array_size));
      }
      n = count;
    }
    // Each element takes at least a byte; checked before anything is allocated for them.
    if (n > reader_.remaining())
      throw CdrError("CDR array of " + std::to_string(n) + " elements exceeds payload");
    if (byte_like(t.primitive)) {
      Bytes bytes(n);
      for (auto& b : bytes) reader_(b);
      return Value{std::move(bytes)};
    }
    // A Value is larger than most elements on the wire: the list grows as they decode, so a
    // forged count costs no more memory than the payload holds.
    List list;
    list.reserve(std::min(n, reader_.remaining() / sizeof(Value)));
    for (std::size_t i = 0; i < n; ++i) list.push_back(single(t, depth));
    return Value{std::move(list)};
  }

  static bool byte_like(Primitive p) {
    return p == Primitive::kByte || p == Primitive::kChar || p == Primitive::kUint8;
  }

  template <class T>
  T get() {
    T v;
    reader_(v);
    return v;
  }

  Value single(const FieldType& t, int depth) {
    switch (t.primitive) {
      case Primitive::kBool:
        return Value{get<bool>()};
      case Primitive::kByte:
      case Primitive::kChar:
      case Primitive::kUint8:
        return integer(get<uint8_t>());
      case Primitive::kInt8:
        return integer(get<int8_t>());
      case Primitive::kInt16:
        return integer(get<int16_t>());
      case Primitive::kUint16:
        return integer(get<uint16_t>());
      case Primitive::kInt32:
        return integer(get<int32_t>());
      case Primitive::kUint32:
        return integer(get<uint32_t>());
      case Primitive::kInt64:
        return integer(get<int64_t>());
      case Primitive::kUint64:
        return integer(get<uint64_t>());
      case Primitive::kFloat32:
        return Value{static_cast<double>(get<float>())};
      case Primitive::kFloat64:
        return Value{get<double>()};
      case Primitive::kString:
        return Value{get<std::string>()};
      case Primitive::kWString: {
        // Fast DDS's encoding: a count of characters, each as 4 bytes.
        const auto n = get<uint32_t>();
        if (n > reader_.remaining() / 4) throw CdrError("CDR wstring length exceeds payload");
        std::u32string s(n, U'\0');
        for (auto& c : s) c = get<uint32_t>();
        return Value{std::move(s)};
      }
      case Primitive::kMessage:
        return message(t.message_type, depth + 1);
    }
    throw DefinitionError("unknown primitive");
  }

  const TypeRegistry& registry_;
  CdrReader reader_;
};

class Encoder {
 public:
  Encoder(const TypeRegistry& registry, std::vector<uint8_t>& out)
      : registry_(registry), writer_(out) {}

  void message(const std::string& type, const Value& v, int depth) {
    if (depth > 64) throw DefinitionError(type + ": nesting deeper than 64 levels");
    const MessageDefinition& def = registry_.get(type);
    const auto& s = as<Struct>(v, type);
    if (def.fields.empty()) {
      writer_(uint8_t{0});
      return;
    }
    if (s.size() != def.fields.size())
      throw std::invalid_argument(type + ": value has " + std::to_string(s.size()) +
                                  " fields, the definition " + std::to_string(def.fields.size()));
    for (std::size_t i = 0; i < s.size(); ++i) field(def.fields[i], s[i].second, depth);
  }

 private:
  template <class T>
  static const T& as(const Value& v, const std::string& what) {
    if (const T* p = std::get_if<T>(&v.data)) return *p;
    throw std::invalid_argument(what + ": value of the wrong kind");
  }

  void field(const Field& f, const Value& v, int depth) {
    const FieldType& t = f.type;
    if (t.array == ArrayKind::kNone) return single(t, v, f.name, depth);
    const bool bytes = std::holds_alternative<Bytes>(v.data);
    const std::size_t n = bytes ? std::get<Bytes>(v.data).size() : as<List>(v, f.name).size();
    if (t.array == ArrayKind::kFixed && n != t.array_size)
      throw std::invalid_argument(f.name + ": array of " + std::to_string(n) + " elements, not " +
                                  std::to_string(t.array_size));
    if (t.array != ArrayKind::kFixed) writer_(static_cast<uint32_t>(n));
    if (bytes) {
      for (uint8_t b : std::get<Bytes>(v.data)) writer_(b);
      return;
    }
    for (const Value& e : std::get<List>(v.data)) single(t, e, f.name, depth);
  }

  static uint64_t unsigned_of(const Value& v, const std::string& name) {
    if (auto p = std::get_if<uint64_t>(&v.data)) return *p;
    if (auto p = std::get_if<int64_t>(&v.data)) return static_cast<uint64_t>(*p);
    if (auto p = std::get_if<bool>(&v.data)) return *p;
    throw std::invalid_argument(name + ": not an integer");
  }
  static double real_of(const Value& v, const std::string& name) {
    if (auto p = std::get_if<double>(&v.data)) return *p;
    if (auto p = std::get_if<int64_t>(&v.data)) return static_cast<double>(*p);
    if (auto p = std::get_if<uint64_t>(&v.data)) return static_cast<double>(*p);
    throw std::invalid_argument(name + ": not a number");
  }

  void single(const FieldType& t, const Value& v, const std::string& name, int depth) {
    switch (t.primitive) {
      case Primitive::kBool:
        return writer_(unsigned_of(v, name) != 0);
      case Primitive::kByte:
      case Primitive::kChar:
      case Primitive::kUint8:
        return writer_(static_cast<uint8_t>(unsigned_of(v, name)));
      case Primitive::kInt8:
        return writer_(static_cast<int8_t>(unsigned_of(v, name)));
      case Primitive::kInt16:
        return writer_(static_cast<int16_t>(unsigned_of(v, name)));
      case Primitive::kUint16:
        return writer_(static_cast<uint16_t>(unsigned_of(v, name)));
      case Primitive::kInt32:
        return writer_(static_cast<int32_t>(unsigned_of(v, name)));
      case Primitive::kUint32:
        return writer_(static_cast<uint32_t>(unsigned_of(v, name)));
      case Primitive::kInt64:
        return writer_(static_cast<int64_t>(unsigned_of(v, name)));
      case Primitive::kUint64:
        return writer_(unsigned_of(v, name));
      case Primitive::kFloat32:
        return writer_(static_cast<float>(real_of(v, name)));
      case Primitive::kFloat64:
        return writer_(real_of(v, name));
      case Primitive::kString:
        return writer_(as<std::string>(v, name));
      case Primitive::kWString: {
        const auto& s = as<std::u32string>(v, name);
        writer_(static_cast<uint32_t>(s.size()));
        for (char32_t c : s) writer_(static_cast<uint32_t>(c));
        return;
      }
      case Primitive::kMessage:
        return message(t.message_type, v, depth + 1);
    }
  }

  const TypeRegistry& registry_;
  CdrWriter writer_;
};

std::string yaml_string(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

std::string scalar(const Value& v) {
  return std::visit(
      [](const auto& x) -> std::string {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, bool>) {
          return x ? "true" : "false";
        } else if constexpr (std::is_same_v<T, int64_t> || std::is_same_v<T, uint64_t>) {
          return std::to_string(x);
        } else if constexpr (std::is_same_v<T, double>) {
          // The shortest text that reads back to the same double.
          char buf[32];
          const auto end = std::to_chars(buf, buf + sizeof(buf), x).ptr;
          std::string s(buf, end);
          if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
          return s;
        } else if constexpr (std::is_same_v<T, std::string>) {
          return yaml_string(x);
        } else if constexpr (std::is_same_v<T, std::u32string>) {
          std::string ascii;
          for (char32_t c : x) ascii += c < 0x80 ? static_cast<char>(c) : '?';
          return yaml_string(ascii);
        } else {
          return "";
        }
      },
      v.data);
}

void emit(std::ostringstream& out, const Value& v, int indent, std::size_t max_array);

void emit_list_items(std::ostringstream& out, const List& list, int indent, std::size_t max_array) {
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  for (const Value& e : list) {
    if (std::holds_alternative<Struct>(e.data)) {
      out << pad << "-\n";
      emit(out, e, indent + 2, max_array);
    } else if (std::holds_alternative<List>(e.data) || std::holds_alternative<Bytes>(e.data)) {
      out << pad << "- ";
      emit(out, e, indent + 2, max_array);
    } else {
      out << pad << "- " << scalar(e) << "\n";
    }
  }
}

void emit(std::ostringstream& out, const Value& v, int indent, std::size_t max_array) {
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  if (const auto* s = std::get_if<Struct>(&v.data)) {
    for (const auto& [name, field] : *s) {
      if (std::holds_alternative<Struct>(field.data)) {
        out << pad << name << ":\n";
        emit(out, field, indent + 2, max_array);
      } else if (std::holds_alternative<List>(field.data) ||
                 std::holds_alternative<Bytes>(field.data)) {
        out << pad << name << ":";
        emit(out, field, indent, max_array);
      } else {
        out << pad << name << ": " << scalar(field) << "\n";
      }
    }
    return;
  }
  if (const auto* b = std::get_if<Bytes>(&v.data)) {
    if (b->size() > max_array) {
      out << " '<" << b->size() << " bytes>'\n";
      return;
    }
    out << (b->empty() ? " []\n" : "\n");
    for (uint8_t x : *b) out << pad << "- " << static_cast<unsigned>(x) << "\n";
    return;
  }
  if (const auto* l = std::get_if<List>(&v.data)) {
    if (l->size() > max_array) {
      out << " '<sequence of " << l->size() << " elements>'\n";
      return;
    }
    out << (l->empty() ? " []\n" : "\n");
    emit_list_items(out, *l, indent, max_array);
    return;
  }
  out << pad << scalar(v) << "\n";
}

}  // namespace

std::string normalize_type_name(std::string_view name) {
  std::string s(name);
  const auto first = s.find('/');
  if (first == std::string::npos) return s;
  const auto last = s.rfind('/');
  if (first == last) return s.substr(0, first) + "/msg/" + s.substr(first + 1);
  return s;
}

MessageDefinition parse_msg(const std::string& type, std::string_view text) {
  MessageDefinition def;
  def.type = normalize_type_name(type);
  def.text = std::string(text);
  const std::string package = package_of(def.type);
  std::size_t line_no = 0;
  std::istringstream lines{std::string(text)};
  std::string line;
  while (std::getline(lines, line)) {
    ++line_no;
    const std::string context = def.type + " line " + std::to_string(line_no);
    std::istringstream tokens(line);
    std::string type_token;
    std::string name;
    if (!(tokens >> type_token) || type_token[0] == '#') continue;
    if (!(tokens >> name) || name[0] == '#')
      throw DefinitionError(context + ": field '" + type_token + "' has no name");
    // Constants (NAME=value) take no space on the wire.
    if (name.find('=') != std::string::npos) continue;
    std::string rest;
    if (tokens >> rest && rest[0] == '=') continue;
    for (char c : name) {
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_'))
        throw DefinitionError(context + ": bad field name '" + name + "'");
    }
    def.fields.push_back({name, parse_type(type_token, package, context)});
  }
  // rosidl gives a type without fields (std_msgs/msg/Empty) one uint8 member, which CDR carries.
  if (def.fields.empty()) {
    def.fields.push_back({"structure_needs_at_least_one_member", {Primitive::kUint8, "", {}, 0}});
  }
  return def;
}

void TypeRegistry::add(MessageDefinition definition) {
  types_[definition.type] = std::move(definition);
}

void TypeRegistry::add_ros2msg(const std::string& type, std::string_view schema) {
  // Sections are separated by a line of '=' and start with "MSG: pkg/Type".
  std::string current = normalize_type_name(type);
  std::string text;
  std::istringstream lines{std::string(schema)};
  std::string line;
  auto flush = [&] {
    if (!current.empty()) {
      // A .srv or .action text (parts between "---" lines), as rosbag2 records the definition
      // of a service's or action's types.
      if (interface_parts(text).size() > 1) {
        add_interface(current, text);
      } else {
        add(parse_msg(current, text));
      }
    }
    text.clear();
  };
  bool expect_name = false;
  bool first_line = true;
  while (std::getline(lines, line)) {
    const bool leading = std::exchange(first_line, false);
    if (line.size() >= 10 && line.find_first_not_of('=') == std::string::npos) {
      // A schema that starts with a section has no text for `type` itself (Jazzy's service event
      // schemas): `type` is not a type without fields, it comes from the section.
      if (!leading) flush();
      current.clear();
      expect_name = true;
      continue;
    }
    if (expect_name) {
      const auto colon = line.find(": ");
      const std::string kind = line.substr(0, colon);
      if (colon == std::string::npos || (kind != "MSG" && kind != "SRV" && kind != "ACTION"))
        throw DefinitionError(type + ": ros2msg schema section without a 'MSG: pkg/Type' line");
      current = normalize_type_name(line.substr(colon + 2));
      expect_name = false;
      continue;
    }
    text += line + "\n";
  }
  flush();
}

void TypeRegistry::add_interface(const std::string& type, std::string_view text) {
  const std::string full = normalize_type_name(type);
  const auto first = full.find('/');
  const auto last = full.rfind('/');
  const std::string package = full.substr(0, first);
  const std::string kind = full.substr(first + 1, last - first - 1);
  const std::string base = interface_name(full.substr(last + 1));
  const std::vector<std::string> parts = interface_parts(text);
  if ((kind != "srv" || parts.size() != 2) && (kind != "action" || parts.size() != 3)) {
    throw DefinitionError(full + ": a definition with " + std::to_string(parts.size()) +
                          " parts between '---' lines is neither a service (2, pkg/srv/...) nor "
                          "an action (3, pkg/action/...)");
  }
  const std::string prefix = package + "/" + kind + "/" + base;
  // The types ROS 2 generates around them use these standard types, when the registry lacks them.
  for (const char* standard : {"builtin_interfaces/msg/Time", "service_msgs/msg/ServiceEventInfo",
                               "unique_identifier_msgs/msg/UUID"}) {
    if (!contains(standard)) add_ros2msg(standard, standard_definition(standard));
  }
  const auto event = [&](const std::string& service) {
    add_msg(service + "_Event", "service_msgs/ServiceEventInfo info\n" + service +
                                    "_Request[<=1] request\n" + service +
                                    "_Response[<=1] response\n");
  };
  if (kind == "srv") {
    add_msg(prefix + "_Request", parts[0]);
    add_msg(prefix + "_Response", parts[1]);
    event(prefix);
    return;
  }
  add_msg(prefix + "_Goal", parts[0]);
  add_msg(prefix + "_Result", parts[1]);
  add_msg(prefix + "_Feedback", parts[2]);
  add_msg(prefix + "_FeedbackMessage",
          "unique_identifier_msgs/UUID goal_id\n" + prefix + "_Feedback feedback\n");
  add_msg(prefix + "_SendGoal_Request",
          "unique_identifier_msgs/UUID goal_id\n" + prefix + "_Goal goal\n");
  add_msg(prefix + "_SendGoal_Response", "bool accepted\nbuiltin_interfaces/Time stamp\n");
  event(prefix + "_SendGoal");
  add_msg(prefix + "_GetResult_Request", "unique_identifier_msgs/UUID goal_id\n");
  add_msg(prefix + "_GetResult_Response", "int8 status\n" + prefix + "_Result result\n");
  event(prefix + "_GetResult");
}

std::size_t TypeRegistry::add_directory(const fs::path& dir, const std::string& package) {
  if (!fs::is_directory(dir)) throw DefinitionError(dir.string() + ": no such directory");
  // A flat folder's package is a guess: the folder's name, or its parent's for a folder named
  // "msg" (<pkg>/msg given directly). Its files are also kept by name, for adopt().
  const fs::path canonical = fs::weakly_canonical(dir);
  const std::string guess = !package.empty() ? package
                            : canonical.filename() == "msg"
                                ? canonical.parent_path().filename().string()
                                : canonical.filename().string();
  std::size_t n = 0;
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator();
       ++it) {
    const fs::directory_entry& entry = *it;
    const std::string extension = entry.path().extension().string();
    if (!entry.is_regular_file() ||
        (extension != ".msg" && extension != ".srv" && extension != ".action"))
      continue;
    const std::string kind = extension.substr(1);
    const fs::path parent = entry.path().parent_path();
    // By depth, not by comparing paths: "a/msg/" (as shell completion gives it) is "a/msg" too.
    const bool flat = it.depth() == 0;
    const std::string pkg =
        parent.filename() == kind && !flat ? parent.parent_path().filename().string() : guess;
    std::ifstream in(entry.path());
    std::stringstream text;
    text << in.rdbuf();
    const std::string name = entry.path().stem().string();
    try {
      if (kind == "msg") {
        add_msg(pkg + "/msg/" + name, text.str());
      } else {
        add_interface(pkg + "/" + kind + "/" + name, text.str());
      }
    } catch (const DefinitionError& e) {
      throw DefinitionError(entry.path().string() + ": " + e.what());
    }
    if (flat && package.empty()) unpackaged_[kind + "/" + name] = text.str();
    ++n;
  }
  return n;
}

std::size_t TypeRegistry::adopt(const std::string& type) {
  std::size_t adopted = 0;
  std::set<std::string> seen;
  std::vector<std::string> todo = {normalize_type_name(type)};
  while (!todo.empty()) {
    const std::string t = todo.back();
    todo.pop_back();
    if (!seen.insert(t).second) continue;
    if (!contains(t)) {
      // "pkg/msg/Name" is served by a flat Name.msg; "pkg/srv/Name_Event" (any type derived from
      // a service or action) by a flat Name.srv (Name.action).
      const auto first = t.find('/');
      const auto last = t.rfind('/');
      const std::string kind = t.substr(first + 1, last - first - 1);
      const std::string name = t.substr(last + 1);
      auto flat = unpackaged_.find(kind + "/" + (kind == "msg" ? name : interface_name(name)));
      if (flat == unpackaged_.end()) continue;
      if (kind == "msg") {
        add_msg(t, flat->second);
      } else {
        add_interface(t, flat->second);
      }
      ++adopted;
    }
    for (const Field& f : get(t).fields) {
      if (f.type.primitive == Primitive::kMessage) todo.push_back(f.type.message_type);
    }
  }
  return adopted;
}

bool TypeRegistry::contains(const std::string& type) const {
  return types_.contains(normalize_type_name(type));
}

const MessageDefinition& TypeRegistry::get(const std::string& type) const {
  auto it = types_.find(normalize_type_name(type));
  if (it == types_.end())
    throw DefinitionError("no definition of " + type + " (give its .msg or a bag that carries it)");
  return it->second;
}

// The walks over a type's dependencies keep their own stacks: a schema can chain types deeper than
// the call stack goes (decode() refuses more than 64 levels, but only after these walks).
void TypeRegistry::check_complete(const std::string& type) const {
  std::set<std::string> seen;
  std::vector<std::pair<std::string, std::string>> todo{{normalize_type_name(type), ""}};
  while (!todo.empty()) {
    const auto [t, needed_by] = std::move(todo.back());
    todo.pop_back();
    if (!seen.insert(t).second) continue;
    if (!contains(t)) {
      throw DefinitionError("no definition of " + t +
                            (needed_by.empty() ? "" : " (used by " + needed_by + ")"));
    }
    // Pushed last field first, so that the first field's types are checked first.
    const auto& fields = get(t).fields;
    for (auto f = fields.rbegin(); f != fields.rend(); ++f) {
      if (f->type.primitive == Primitive::kMessage) todo.emplace_back(f->type.message_type, t);
    }
  }
}

std::string TypeRegistry::ros2msg_schema(const std::string& type) const {
  check_complete(type);
  const std::string root = normalize_type_name(type);
  // Dependencies depth first, in field order, each once: a type's own first, then the next
  // field's.
  std::vector<std::string> order;
  std::set<std::string> listed{root};
  struct Visit {
    const MessageDefinition* def;
    std::size_t next_field;
  };
  std::vector<Visit> stack{{&get(root), 0}};
  while (!stack.empty()) {
    Visit& v = stack.back();
    if (v.next_field == v.def->fields.size()) {
      stack.pop_back();
      continue;
    }
    const FieldType& field = v.def->fields[v.next_field++].type;
    if (field.primitive != Primitive::kMessage || !listed.insert(field.message_type).second)
      continue;
    order.push_back(field.message_type);
    stack.push_back({&get(field.message_type), 0});
  }
  std::string out = get(root).text;
  for (const std::string& dep : order) {
    if (!out.empty() && out.back() != '\n') out += '\n';
    // "pkg/msg/Type" is named "pkg/Type" after MSG:, as rosbag2 writes it.
    std::string name = dep;
    if (const auto at = name.find("/msg/"); at != std::string::npos) name.erase(at, 4);
    out += std::string(80, '=') + "\nMSG: " + name + "\n" + get(dep).text;
  }
  return out;
}

const Value& Value::operator[](const std::string& name) const {
  for (const auto& [n, v] : std::get<Struct>(data)) {
    if (n == name) return v;
  }
  throw std::out_of_range("no field " + name);
}

Value& Value::operator[](const std::string& name) {
  return const_cast<Value&>(static_cast<const Value&>(*this)[name]);
}

Value decode(const TypeRegistry& registry, const std::string& type,
             std::span<const uint8_t> payload) {
  registry.check_complete(type);
  Decoder d(registry, payload);
  return d.message(normalize_type_name(type), 0);
}

std::vector<uint8_t> encode(const TypeRegistry& registry, const std::string& type,
                            const Value& value) {
  registry.check_complete(type);
  std::vector<uint8_t> out;
  Encoder e(registry, out);
  e.message(normalize_type_name(type), value, 0);
  return out;
}

std::string to_yaml(const Value& value, std::size_t max_array) {
  std::ostringstream out;
  emit(out, value, 0, max_array);
  return out.str();
}

}  // namespace robotperf::msgs::dynamic
