#include "robotperf/plugin/parameters.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <system_error>

#include "robotperf/plugin/parameter_struct.hpp"

namespace robotperf::plugin {
namespace {

template <class T>
T parse_number(const std::string& text, const char* what) {
  T value{};
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || text.empty()) {
    throw std::invalid_argument("'" + text + "' is not " + what);
  }
  return value;
}

bool parse_bool(const std::string& text) {
  if (text == "true" || text == "True" || text == "1") return true;
  if (text == "false" || text == "False" || text == "0") return false;
  throw std::invalid_argument("'" + text + "' is not true or false");
}

std::string shortest(double value) {
  char buf[64];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, value);
  return std::string(buf, end);
}

}  // namespace

const char* type_name(ParameterType type) {
  switch (type) {
    case ParameterType::kBool:
      return "bool";
    case ParameterType::kInt:
      return "int";
    case ParameterType::kDouble:
      return "double";
    case ParameterType::kString:
      return "string";
  }
  return "?";
}

void check_value(ParameterType type, const std::string& text) {
  switch (type) {
    case ParameterType::kBool:
      parse_bool(text);
      return;
    case ParameterType::kInt:
      parse_number<int64_t>(text, "an integer");
      return;
    case ParameterType::kDouble:
      parse_number<double>(text, "a number");
      return;
    case ParameterType::kString:
      return;
  }
}

void check_value(const ParameterInfo& parameter, const std::string& text) {
  check_value(parameter.type, text);
  const ParameterBounds& b = parameter.bounds;
  if ((!b.minimum && !b.maximum) ||
      (parameter.type != ParameterType::kInt && parameter.type != ParameterType::kDouble))
    return;
  const double value = parameter.type == ParameterType::kInt
                           ? static_cast<double>(parse_number<int64_t>(text, "an integer"))
                           : parse_number<double>(text, "a number");
  // Written so that NaN is outside every range.
  if (!(!b.minimum || value >= *b.minimum) || !(!b.maximum || value <= *b.maximum))
    throw std::invalid_argument(text + " is outside its range, " + bounds_text(b));
}

std::string bounds_text(const ParameterBounds& b) {
  // Whole bounds as integers (100000, not 1e+05).
  auto text = [](double v) {
    return v == std::trunc(v) && std::fabs(v) < 1e15 ? std::to_string(static_cast<int64_t>(v))
                                                     : shortest(v);
  };
  if (b.minimum && b.maximum) return text(*b.minimum) + " to " + text(*b.maximum);
  if (b.minimum) return "at least " + text(*b.minimum);
  if (b.maximum) return "at most " + text(*b.maximum);
  return "";
}

ParameterInfo bool_parameter(std::string name, bool default_value, std::string doc) {
  return {std::move(name), ParameterType::kBool, default_value ? "true" : "false", std::move(doc)};
}

ParameterInfo int_parameter(std::string name, int64_t default_value, std::string doc,
                            ParameterBounds bounds) {
  return {std::move(name), ParameterType::kInt, std::to_string(default_value), std::move(doc),
          bounds};
}

ParameterInfo double_parameter(std::string name, double default_value, std::string doc,
                               ParameterBounds bounds) {
  return {std::move(name), ParameterType::kDouble, shortest(default_value), std::move(doc), bounds};
}

ParameterInfo string_parameter(std::string name, std::string default_value, std::string doc) {
  return {std::move(name), ParameterType::kString, std::move(default_value), std::move(doc)};
}

ParameterInfo computed_parameter(std::string name, ParameterType type, std::string doc) {
  return {std::move(name), type, std::nullopt, std::move(doc)};
}

Parameters::Parameters(std::vector<ParameterInfo> declared,
                       const std::map<std::string, std::string>& values, const std::string& owner)
    : declared_(std::move(declared)), owner_(owner) {
  for (const auto& [name, value] : values) {
    auto it = std::ranges::find(declared_, name, &ParameterInfo::name);
    if (it == declared_.end()) {
      std::string known;
      for (const auto& p : declared_) known += (known.empty() ? "" : ", ") + p.name;
      throw std::invalid_argument(owner + ": unknown parameter '" + name + "' (" +
                                  (known.empty() ? "it takes none" : "known: " + known) + ")");
    }
    try {
      check_value(*it, value);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(owner + ": parameter '" + name + "' (" + type_name(it->type) +
                                  "): " + e.what());
    }
    values_[name] = value;
  }
}

const ParameterInfo& Parameters::declaration(const std::string& name, ParameterType type) const {
  auto it = std::ranges::find(declared_, name, &ParameterInfo::name);
  if (it == declared_.end())
    throw std::logic_error(owner_ + " reads parameter '" + name + "', which it does not declare");
  if (it->type != type) {
    throw std::logic_error(owner_ + " reads parameter '" + name + "' as " + type_name(type) +
                           ", declared " + type_name(it->type));
  }
  return *it;
}

std::optional<std::string> Parameters::text(const std::string& name, ParameterType type) const {
  const ParameterInfo& info = declaration(name, type);
  if (auto it = values_.find(name); it != values_.end()) return it->second;
  return info.default_value;
}

namespace {

template <class T, class Parse>
T read(const std::optional<std::string>& text, const std::string& owner, const std::string& name,
       Parse parse) {
  if (!text) {
    throw std::logic_error(owner + " reads parameter '" + name +
                           "' without a fallback, but it has no default");
  }
  return parse(*text);
}

}  // namespace

bool Parameters::get_bool(const std::string& name) const {
  return read<bool>(text(name, ParameterType::kBool), owner_, name, parse_bool);
}

int64_t Parameters::get_int(const std::string& name) const {
  return read<int64_t>(text(name, ParameterType::kInt), owner_, name,
                       [](const std::string& t) { return parse_number<int64_t>(t, "an integer"); });
}

int Parameters::get_int32(const std::string& name) const {
  const int64_t v = get_int(name);
  detail::check_integer_range(*this, name, v, std::numeric_limits<int>::min(),
                              std::numeric_limits<int>::max(), "a 32-bit integer");
  return static_cast<int>(v);
}

double Parameters::get_double(const std::string& name) const {
  return read<double>(text(name, ParameterType::kDouble), owner_, name,
                      [](const std::string& t) { return parse_number<double>(t, "a number"); });
}

std::string Parameters::get_string(const std::string& name) const {
  return read<std::string>(text(name, ParameterType::kString), owner_, name,
                           [](const std::string& t) { return t; });
}

bool Parameters::get_bool(const std::string& name, bool fallback) const {
  const auto t = text(name, ParameterType::kBool);
  return t ? parse_bool(*t) : fallback;
}

int64_t Parameters::get_int(const std::string& name, int64_t fallback) const {
  const auto t = text(name, ParameterType::kInt);
  return t ? parse_number<int64_t>(*t, "an integer") : fallback;
}

double Parameters::get_double(const std::string& name, double fallback) const {
  const auto t = text(name, ParameterType::kDouble);
  return t ? parse_number<double>(*t, "a number") : fallback;
}

std::string Parameters::get_string(const std::string& name, const std::string& fallback) const {
  const auto t = text(name, ParameterType::kString);
  return t ? *t : fallback;
}

std::map<std::string, std::string> Parameters::effective() const {
  std::map<std::string, std::string> out;
  for (const auto& p : declared_) {
    if (auto it = values_.find(p.name); it != values_.end()) {
      out[p.name] = it->second;
    } else if (p.default_value) {
      out[p.name] = *p.default_value;
    }
  }
  return out;
}

}  // namespace robotperf::plugin
