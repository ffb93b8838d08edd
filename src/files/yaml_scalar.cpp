#include "robotperf/files/yaml_scalar.hpp"

#include <cstdio>
#include <regex>

namespace robotperf::files {

std::string yaml_double_quoted(std::string_view text) {
  std::string out = "\"";
  for (const unsigned char c : text) {
    switch (c) {
      case '\\':
        out += "\\\\";
        break;
      case '"':
        out += "\\\"";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (c < 0x20 || c == 0x7f) {
          char escape[8];
          std::snprintf(escape, sizeof escape, "\\x%02X", c);
          out += escape;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

std::string yaml_scalar(std::string_view text) {
  static const std::regex plain("[A-Za-z][A-Za-z0-9 _./+()-]*");
  static const std::regex reserved("(?:true|false|yes|no|on|off|null|y|n)", std::regex::icase);
  const std::string s(text);
  if (std::regex_match(s, plain) && s.back() != ' ' && !std::regex_match(s, reserved)) return s;
  return yaml_double_quoted(text);
}

}  // namespace robotperf::files
