// TSDL (CTF 1.8 metadata) parser: the declarations LTTng writes — typealias,
// trace, env, clock, stream, event, named structs, integer, floating_point,
// string, enum, variant, arrays and sequences — plus typedef. Unknown
// top-level blocks (callsite, ...) are skipped.
#include <cctype>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "robotperf/tracing/ctf.hpp"

namespace robotperf::tracing::ctf {
namespace {

struct Token {
  enum class K { kIdent, kNumber, kString, kPunct, kEnd } k = K::kEnd;
  std::string text;
  int line = 0;
};

std::vector<Token> tokenize(std::string_view s) {
  std::vector<Token> out;
  int line = 1;
  std::size_t i = 0;
  auto error = [&](const std::string& what) {
    return CtfError("metadata line " + std::to_string(line) + ": " + what);
  };
  while (i < s.size()) {
    const char c = s[i];
    if (c == '\n') {
      ++line;
      ++i;
    } else if (std::isspace(static_cast<unsigned char>(c)) || c == '\0') {
      ++i;
    } else if (c == '/' && i + 1 < s.size() && s[i + 1] == '*') {
      const std::size_t end = s.find("*/", i + 2);
      if (end == std::string_view::npos) throw error("unterminated comment");
      for (std::size_t j = i; j < end; ++j) line += s[j] == '\n';
      i = end + 2;
    } else if (c == '/' && i + 1 < s.size() && s[i + 1] == '/') {
      while (i < s.size() && s[i] != '\n') ++i;
    } else if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
      std::size_t j = i;
      while (j < s.size() && (std::isalnum(static_cast<unsigned char>(s[j])) || s[j] == '_')) ++j;
      out.push_back({Token::K::kIdent, std::string(s.substr(i, j - i)), line});
      i = j;
    } else if (std::isdigit(static_cast<unsigned char>(c)) ||
               (c == '-' && i + 1 < s.size() &&
                std::isdigit(static_cast<unsigned char>(s[i + 1])))) {
      std::size_t j = i + 1;
      while (j < s.size() && (std::isalnum(static_cast<unsigned char>(s[j])))) ++j;
      out.push_back({Token::K::kNumber, std::string(s.substr(i, j - i)), line});
      i = j;
    } else if (c == '"') {
      std::string text;
      std::size_t j = i + 1;
      while (j < s.size() && s[j] != '"') {
        if (s[j] == '\\' && j + 1 < s.size()) ++j;
        text += s[j++];
      }
      if (j >= s.size()) throw error("unterminated string");
      out.push_back({Token::K::kString, std::move(text), line});
      i = j + 1;
    } else if (s.substr(i, 3) == "...") {
      out.push_back({Token::K::kPunct, "...", line});
      i += 3;
    } else if (s.substr(i, 2) == ":=") {
      out.push_back({Token::K::kPunct, ":=", line});
      i += 2;
    } else if (std::strchr("{}()[];:=,<>.+*", c) != nullptr) {
      out.push_back({Token::K::kPunct, std::string(1, c), line});
      ++i;
    } else {
      throw error(std::string("unexpected character '") + c + "'");
    }
  }
  out.push_back({Token::K::kEnd, "", line});
  return out;
}

int64_t parse_number(const std::string& text, int line) {
  try {
    std::size_t used = 0;
    int64_t v;
    if (text.starts_with("-")) {
      v = std::stoll(text, &used, 0);
    } else {
      v = static_cast<int64_t>(std::stoull(text, &used, 0));
    }
    // Integer suffixes (u, l, ul) are allowed by TSDL.
    for (std::size_t k = used; k < text.size(); ++k) {
      if (std::strchr("uUlL", text[k]) == nullptr) throw std::invalid_argument(text);
    }
    return v;
  } catch (const std::exception&) {
    throw CtfError("metadata line " + std::to_string(line) + ": bad number '" + text + "'");
  }
}

std::string field_name(const std::string& declared) {
  // CTF escapes identifiers that could clash with keywords with a leading '_'.
  return declared.starts_with('_') ? declared.substr(1) : declared;
}

using MutableType = std::shared_ptr<Type>;

class Parser {
 public:
  explicit Parser(std::vector<Token> tokens) : t_(std::move(tokens)) {}

  Metadata parse() {
    while (peek().k != Token::K::kEnd) top_level();
    for (auto& e : md_.events) {
      StreamClass* sc = nullptr;
      for (auto& s : md_.streams) {
        if (s.id == e->stream_id) sc = &s;
      }
      if (sc == nullptr) {
        // A trace with one implicit stream may omit the stream block.
        md_.streams.push_back(StreamClass{});
        md_.streams.back().id = e->stream_id;
        sc = &md_.streams.back();
      }
      if (e->id > 1'000'000) throw CtfError("event id " + std::to_string(e->id) + " is too large");
      if (sc->events_by_id.size() <= e->id) sc->events_by_id.resize(e->id + 1, nullptr);
      sc->events_by_id[e->id] = e.get();
    }
    md_.big_endian = big_endian_;
    return std::move(md_);
  }

 private:
  const Token& peek(std::size_t ahead = 0) const {
    return t_[std::min(pos_ + ahead, t_.size() - 1)];
  }
  const Token& next() {
    const Token& tok = t_[pos_];
    if (pos_ + 1 < t_.size()) ++pos_;
    return tok;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw CtfError("metadata line " + std::to_string(peek().line) + ": " + what + " (at '" +
                   peek().text + "')");
  }
  bool accept(const char* punct) {
    if (peek().k == Token::K::kPunct && peek().text == punct) {
      next();
      return true;
    }
    return false;
  }
  void expect(const char* punct) {
    if (!accept(punct)) fail(std::string("expected '") + punct + "'");
  }
  bool is_ident(const char* word, std::size_t ahead = 0) const {
    return peek(ahead).k == Token::K::kIdent && peek(ahead).text == word;
  }
  std::string ident() {
    if (peek().k != Token::K::kIdent) fail("expected a name");
    return next().text;
  }
  static bool is_type_keyword(const std::string& w) {
    return w == "integer" || w == "floating_point" || w == "string" || w == "struct" ||
           w == "enum" || w == "variant";
  }

  void skip_block() {
    expect("{");
    int depth = 1;
    while (depth > 0) {
      if (peek().k == Token::K::kEnd) fail("unterminated block");
      const Token& tok = next();
      if (tok.k == Token::K::kPunct && tok.text == "{") ++depth;
      if (tok.k == Token::K::kPunct && tok.text == "}") --depth;
    }
  }

  void top_level() {
    if (accept(";")) return;
    const std::string word = ident();
    if (word == "typealias") {
      TypePtr type = type_specifier();
      expect(":=");
      std::string name;
      while (peek().k == Token::K::kIdent) name += (name.empty() ? "" : " ") + next().text;
      if (name.empty()) fail("typealias without a name");
      aliases_[name] = type;
      expect(";");
    } else if (word == "typedef") {
      TypePtr type = type_specifier();
      std::vector<std::string> words;
      while (peek().k == Token::K::kIdent) words.push_back(next().text);
      if (words.empty()) fail("typedef without a name");
      std::string name;
      for (const auto& w : words) name += (name.empty() ? "" : " ") + w;
      aliases_[name] = type;
      expect(";");
    } else if (word == "struct" || word == "enum" || word == "variant") {
      --pos_;
      type_specifier();  // a named declaration registers itself
      expect(";");
    } else if (word == "trace") {
      block(
          [&](const std::string& key, const std::vector<Token>& value) {
            if (key == "byte_order" && !value.empty()) {
              big_endian_ = value[0].text == "be" || value[0].text == "network";
            } else if (key == "major" && !value.empty() && value[0].text != "1") {
              fail("CTF major version " + value[0].text + " is not supported (1.8 is)");
            }
          },
          [&](const std::string& key, TypePtr type) {
            if (key == "packet.header") md_.packet_header = std::move(type);
          });
      expect(";");
    } else if (word == "env") {
      block(
          [&](const std::string& key, const std::vector<Token>& value) {
            md_.env.emplace_back(key, value.empty() ? "" : value[0].text);
          },
          [](const std::string&, TypePtr) {});
      expect(";");
    } else if (word == "clock") {
      ClockClass clock;
      int64_t freq = static_cast<int64_t>(clock.freq);
      block(
          [&](const std::string& key, const std::vector<Token>& value) {
            if (value.empty()) return;
            if (key == "name") clock.name = value[0].text;
            if (key == "freq") freq = parse_number(value[0].text, value[0].line);
            if (key == "offset") clock.offset = parse_number(value[0].text, value[0].line);
            if (key == "offset_s") clock.offset_s = parse_number(value[0].text, value[0].line);
          },
          [](const std::string&, TypePtr) {});
      // Event times are divided by it.
      if (freq <= 0) fail("clock '" + clock.name + "' with frequency " + std::to_string(freq));
      clock.freq = static_cast<uint64_t>(freq);
      md_.clocks.push_back(clock);
      expect(";");
    } else if (word == "stream") {
      StreamClass sc;
      block(
          [&](const std::string& key, const std::vector<Token>& value) {
            if (key == "id" && !value.empty())
              sc.id = static_cast<uint64_t>(parse_number(value[0].text, value[0].line));
          },
          [&](const std::string& key, TypePtr type) {
            if (key == "packet.context") sc.packet_context = std::move(type);
            if (key == "event.header") sc.event_header = std::move(type);
            if (key == "event.context") sc.event_context = std::move(type);
          });
      md_.streams.push_back(std::move(sc));
      expect(";");
    } else if (word == "event") {
      auto ec = std::make_unique<EventClass>();
      block(
          [&](const std::string& key, const std::vector<Token>& value) {
            if (value.empty()) return;
            if (key == "name") ec->name = value[0].text;
            if (key == "id")
              ec->id = static_cast<uint64_t>(parse_number(value[0].text, value[0].line));
            if (key == "stream_id")
              ec->stream_id = static_cast<uint64_t>(parse_number(value[0].text, value[0].line));
            if (key == "loglevel")
              ec->loglevel = static_cast<int>(parse_number(value[0].text, value[0].line));
          },
          [&](const std::string& key, TypePtr type) {
            if (key == "fields") ec->fields = std::move(type);
            if (key == "context") ec->context = std::move(type);
          });
      md_.events.push_back(std::move(ec));
      expect(";");
    } else {
      // callsite and other blocks robotperf does not need.
      skip_block();
      accept(";");
    }
  }

  // `{ key = value; key.path := type; ... }`
  template <class OnValue, class OnType>
  void block(OnValue on_value, OnType on_type) {
    expect("{");
    while (!accept("}")) {
      if (peek().k == Token::K::kEnd) fail("unterminated block");
      if (accept(";")) continue;
      std::string key;
      while (peek().k == Token::K::kIdent || (peek().k == Token::K::kPunct && peek().text == ".")) {
        key += next().text;
      }
      if (key.empty()) fail("expected an attribute name");
      if (accept(":=")) {
        on_type(key, type_specifier());
      } else {
        expect("=");
        std::vector<Token> value;
        while (!(peek().k == Token::K::kPunct && peek().text == ";")) {
          if (peek().k == Token::K::kEnd) fail("unterminated attribute");
          value.push_back(next());
        }
        on_value(key, value);
      }
      expect(";");
    }
  }

  // `{ key = value; ... }` of integer, floating_point and string.
  std::vector<std::pair<std::string, std::string>> attributes() {
    std::vector<std::pair<std::string, std::string>> out;
    block(
        [&](const std::string& key, const std::vector<Token>& value) {
          std::string text;
          for (const auto& v : value) text += v.text;
          out.emplace_back(key, text);
        },
        [&](const std::string& key, TypePtr) { fail("unexpected type assignment " + key); });
    return out;
  }

  ByteOrder byte_order_of(const std::string& v) {
    if (v == "le") return ByteOrder::kLittle;
    if (v == "be" || v == "network") return ByteOrder::kBig;
    if (v == "native") return ByteOrder::kNative;
    fail("unknown byte_order " + v);
  }

  TypePtr integer_type() {
    auto t = std::make_shared<Type>();
    t->kind = Kind::kInteger;
    bool align_given = false;
    for (const auto& [k, v] : attributes()) {
      if (k == "size") t->size_bits = static_cast<unsigned>(parse_number(v, peek().line));
      if (k == "align") {
        t->align_bits = static_cast<unsigned>(parse_number(v, peek().line));
        align_given = true;
      }
      if (k == "signed") t->is_signed = v == "true" || v == "1" || v == "TRUE";
      if (k == "byte_order") t->byte_order = byte_order_of(v);
      if (k == "encoding") t->is_text = v == "UTF8" || v == "ASCII" || v == "utf8" || v == "ascii";
      if (k == "map") t->maps_clock = v.starts_with("clock.");
    }
    if (t->size_bits == 0 || t->size_bits > 64) fail("integer size must be 1..64 bits");
    if (!align_given) t->align_bits = t->size_bits % 8 == 0 ? 8 : 1;
    if (t->align_bits == 0 || (t->align_bits & (t->align_bits - 1)) != 0)
      fail("alignment must be a power of two");
    if (t->size_bits != 8) t->is_text = false;
    return t;
  }

  TypePtr float_type() {
    auto t = std::make_shared<Type>();
    t->kind = Kind::kFloat;
    unsigned exp = 0;
    bool align_given = false;
    for (const auto& [k, v] : attributes()) {
      if (k == "exp_dig") exp = static_cast<unsigned>(parse_number(v, peek().line));
      if (k == "mant_dig") t->mant_dig = static_cast<unsigned>(parse_number(v, peek().line));
      if (k == "byte_order") t->byte_order = byte_order_of(v);
      if (k == "align") {
        t->align_bits = static_cast<unsigned>(parse_number(v, peek().line));
        align_given = true;
      }
    }
    t->size_bits = exp + t->mant_dig;
    if (!((exp == 8 && t->mant_dig == 24) || (exp == 11 && t->mant_dig == 53)))
      fail("only 32- and 64-bit IEEE 754 floating point is supported");
    if (!align_given) t->align_bits = 8;
    return t;
  }

  // After `struct`/`variant`/`enum`: the optional name.
  std::string optional_name() {
    if (peek().k == Token::K::kIdent) return next().text;
    return {};
  }

  TypePtr type_specifier() {
    if (peek().k != Token::K::kIdent) fail("expected a type");
    const std::string word = peek().text;
    if (word == "integer") {
      next();
      return integer_type();
    }
    if (word == "floating_point") {
      next();
      return float_type();
    }
    if (word == "string") {
      next();
      auto t = std::make_shared<Type>();
      t->kind = Kind::kString;
      t->align_bits = 8;
      if (peek().k == Token::K::kPunct && peek().text == "{") attributes();
      return t;
    }
    if (word == "struct") {
      next();
      const std::string name = optional_name();
      if (!(peek().k == Token::K::kPunct && peek().text == "{")) {
        auto it = structs_.find(name);
        if (it == structs_.end()) fail("unknown struct " + name);
        return it->second;
      }
      auto t = std::make_shared<Type>();
      t->kind = Kind::kStruct;
      t->align_bits = 1;
      field_list(*t);
      if (is_ident("align")) {
        next();
        expect("(");
        const Token& n = next();
        t->align_bits =
            std::max<unsigned>(t->align_bits, static_cast<unsigned>(parse_number(n.text, n.line)));
        expect(")");
      }
      if (!name.empty()) structs_[name] = t;
      return t;
    }
    if (word == "variant") {
      next();
      const std::string name = optional_name();
      std::string tag;
      if (accept("<")) {
        while (!accept(">")) {
          if (peek().k == Token::K::kEnd) fail("unterminated variant tag");
          tag += next().text;
        }
      }
      if (!(peek().k == Token::K::kPunct && peek().text == "{")) {
        auto it = variants_.find(name);
        if (it == variants_.end()) fail("unknown variant " + name);
        auto t = std::make_shared<Type>(*it->second);
        if (!tag.empty()) t->variant_tag = tag;
        return t;
      }
      auto t = std::make_shared<Type>();
      t->kind = Kind::kVariant;
      t->align_bits = 1;
      t->variant_tag = tag;
      field_list(*t);
      if (!name.empty()) variants_[name] = t;
      return t;
    }
    if (word == "enum") {
      next();
      const std::string name = optional_name();
      TypePtr base;
      if (accept(":")) {
        if (peek().k == Token::K::kIdent && peek().text == "integer") {
          next();
          base = integer_type();
        } else {
          std::string alias;
          while (peek().k == Token::K::kIdent) alias += (alias.empty() ? "" : " ") + next().text;
          base = lookup_alias(alias);
        }
      } else {
        base = lookup_alias("int");
      }
      if (!(peek().k == Token::K::kPunct && peek().text == "{")) {
        auto it = enums_.find(name);
        if (it == enums_.end()) fail("unknown enum " + name);
        return it->second;
      }
      if (base->kind != Kind::kInteger) fail("an enum needs an integer container");
      auto t = std::make_shared<Type>(*base);
      t->kind = Kind::kEnum;
      expect("{");
      int64_t next_value = 0;
      while (!accept("}")) {
        if (accept(",")) continue;
        if (peek().k != Token::K::kIdent && peek().k != Token::K::kString)
          fail("expected an enum label");
        EnumMapping m;
        m.label = next().text;
        m.low = m.high = next_value;
        if (accept("=")) {
          const Token& lo = next();
          m.low = m.high = parse_number(lo.text, lo.line);
          if (accept("...")) {
            const Token& hi = next();
            m.high = parse_number(hi.text, hi.line);
          }
        }
        next_value = m.high + 1;
        t->mappings.push_back(std::move(m));
      }
      if (!name.empty()) enums_[name] = t;
      return t;
    }
    // A type alias, possibly several words ("unsigned long").
    std::string alias;
    while (peek().k == Token::K::kIdent && !is_type_keyword(peek().text)) {
      // Stop before the declarator: the last identifier of a field declaration.
      const std::string candidate = alias.empty() ? peek().text : alias + " " + peek().text;
      if (!alias.empty() && !aliases_.contains(candidate)) break;
      alias = candidate;
      next();
    }
    return lookup_alias(alias);
  }

  TypePtr lookup_alias(const std::string& name) {
    auto it = aliases_.find(name);
    if (it == aliases_.end()) fail("unknown type '" + name + "'");
    return it->second;
  }

  // `{ type name[len]; ... }` into a struct or variant, resolving
  // sibling-tagged variants and sibling-length sequences.
  void field_list(Type& owner) {
    expect("{");
    while (!accept("}")) {
      if (peek().k == Token::K::kEnd) fail("unterminated field list");
      if (accept(";")) continue;
      TypePtr type = type_specifier();
      do {
        const std::string declared = ident();
        TypePtr t = type;
        std::vector<std::string> dims;
        while (accept("[")) {
          std::string dim;
          while (!accept("]")) {
            if (peek().k == Token::K::kEnd) fail("unterminated array length");
            dim += next().text;
          }
          dims.push_back(dim);
        }
        for (auto it = dims.rbegin(); it != dims.rend(); ++it) {
          auto arr = std::make_shared<Type>();
          arr->element = t;
          arr->align_bits = t->align_bits;
          if (!it->empty() && (std::isdigit(static_cast<unsigned char>((*it)[0])))) {
            arr->kind = Kind::kArray;
            arr->length = static_cast<uint64_t>(parse_number(*it, peek().line));
          } else {
            arr->kind = Kind::kSequence;
            arr->length_field = *it;
            const std::string last = field_name(it->substr(it->rfind('.') + 1));
            for (std::size_t i = 0; i < owner.fields.size(); ++i) {
              if (owner.fields[i].name == last) arr->length_sibling = static_cast<int>(i);
            }
          }
          t = arr;
        }
        if (t->kind == Kind::kVariant && !t->variant_tag.empty()) t = resolve_variant_tag(owner, t);
        owner.fields.push_back({field_name(declared), t});
        if (owner.kind == Kind::kStruct)
          owner.align_bits = std::max(owner.align_bits, t->align_bits);
      } while (accept(","));
      expect(";");
    }
  }

  TypePtr resolve_variant_tag(const Type& owner, const TypePtr& variant) {
    const std::string& tag = variant->variant_tag;
    const std::string last = field_name(tag.substr(tag.rfind('.') + 1));
    for (std::size_t i = 0; i < owner.fields.size(); ++i) {
      const Field& f = owner.fields[i];
      if (f.name != last || f.type->kind != Kind::kEnum) continue;
      auto t = std::make_shared<Type>(*variant);
      t->tag_sibling = static_cast<int>(i);
      t->option_of_mapping.assign(f.type->mappings.size(), -1);
      for (std::size_t m = 0; m < f.type->mappings.size(); ++m) {
        for (std::size_t o = 0; o < t->fields.size(); ++o) {
          if (field_name(f.type->mappings[m].label) == t->fields[o].name)
            t->option_of_mapping[m] = static_cast<int>(o);
        }
      }
      return t;
    }
    fail("variant tag '" + tag + "' is not an enum field before it in the same struct");
  }

  std::vector<Token> t_;
  std::size_t pos_ = 0;
  bool big_endian_ = false;
  Metadata md_;
  std::map<std::string, TypePtr> aliases_;
  std::map<std::string, TypePtr> structs_, variants_, enums_;
};

uint32_t load_u32(const uint8_t* p, bool swap) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return swap ? __builtin_bswap32(v) : v;
}

}  // namespace

int EventClass::field_index(std::string_view name) const {
  if (!fields) return -1;
  for (std::size_t i = 0; i < fields->fields.size(); ++i) {
    if (fields->fields[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

const StreamClass* Metadata::stream(uint64_t id) const {
  for (const auto& s : streams) {
    if (s.id == id) return &s;
  }
  return nullptr;
}

std::string Metadata::env_value(std::string_view key) const {
  for (const auto& [k, v] : env) {
    if (k == key) return v;
  }
  return {};
}

Metadata parse_metadata_text(std::string_view tsdl) {
  return Parser(tokenize(tsdl)).parse();
}

Metadata read_metadata(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw CtfError("cannot open " + file.string());
  std::string raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  constexpr uint32_t kMetadataMagic = 0x75D11D57;
  // Packetised metadata: 37-byte headers, each followed by content_size bits.
  constexpr std::size_t kHeaderBytes = 37;
  std::string text;
  if (raw.size() >= 4 &&
      (load_u32(reinterpret_cast<const uint8_t*>(raw.data()), false) == kMetadataMagic ||
       load_u32(reinterpret_cast<const uint8_t*>(raw.data()), true) == kMetadataMagic)) {
    const bool swap =
        load_u32(reinterpret_cast<const uint8_t*>(raw.data()), false) != kMetadataMagic;
    std::size_t off = 0;
    while (off + kHeaderBytes <= raw.size()) {
      const auto* p = reinterpret_cast<const uint8_t*>(raw.data() + off);
      if (load_u32(p, swap) != kMetadataMagic)
        throw CtfError(file.string() + ": bad metadata packet magic at byte " +
                       std::to_string(off));
      const uint32_t content_bits = load_u32(p + 24, swap);
      const uint32_t packet_bits = load_u32(p + 28, swap);
      if (p[32] != 0 || p[33] != 0)
        throw CtfError(file.string() + ": compressed or encrypted metadata is not supported");
      const std::size_t content = content_bits / 8, packet = packet_bits / 8;
      if (content < kHeaderBytes || packet < content || off + packet > raw.size() + 0 ||
          packet == 0) {
        if (off + content <= raw.size() && content >= kHeaderBytes) {
          text.append(raw, off + kHeaderBytes, content - kHeaderBytes);
          break;  // the last packet may be cut short by a crash
        }
        throw CtfError(file.string() + ": corrupt metadata packet at byte " + std::to_string(off));
      }
      text.append(raw, off + kHeaderBytes, content - kHeaderBytes);
      off += packet;
    }
  } else if (raw.starts_with("/* CTF")) {
    text = std::move(raw);
  } else {
    throw CtfError(file.string() +
                   ": not CTF metadata (neither '/* CTF' text nor metadata packets)");
  }
  try {
    return parse_metadata_text(text);
  } catch (const CtfError& e) {
    throw CtfError(file.string() + ": " + e.what());
  }
}

}  // namespace robotperf::tracing::ctf
