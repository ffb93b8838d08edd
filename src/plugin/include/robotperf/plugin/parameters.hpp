// Parameters of kernels, dataset generators and evaluators: declared with a type, a default and
// a one-line doc, given as text in graph.yaml or benchmark.yaml, checked when they are read in.
// Kernels, generators and evaluators declare and read them as a struct (parameter_struct.hpp);
// the declarations below and the reads by name of Parameters are that struct's storage, and the
// untyped access for a plug-in that reads a parameter whose name is data.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace robotperf::plugin {

enum class ParameterType { kBool, kInt, kDouble, kString };

// "bool", "int", "double", "string".
const char* type_name(ParameterType type);

// The closed range an int or double parameter's value must lie in; an absent end is open.
// Checked where the value is given, so that a value out of range is refused before any run
// (a sweep checks every value before its first).
struct ParameterBounds {
  std::optional<double> minimum{};
  std::optional<double> maximum{};
};

struct ParameterInfo {
  std::string name{};
  ParameterType type = ParameterType::kString;
  // The value when none is given, as text; absent when the code computes it from other
  // parameters or the workload (the doc then says how).
  std::optional<std::string> default_value{};
  std::string doc{};  // one line
  ParameterBounds bounds{};
};

// Declarations with their default in the declared type.
ParameterInfo bool_parameter(std::string name, bool default_value, std::string doc);
ParameterInfo int_parameter(std::string name, int64_t default_value, std::string doc,
                            ParameterBounds bounds = {});
ParameterInfo double_parameter(std::string name, double default_value, std::string doc,
                               ParameterBounds bounds = {});
ParameterInfo string_parameter(std::string name, std::string default_value, std::string doc);
// A parameter whose default depends on something else: read it with a fallback.
ParameterInfo computed_parameter(std::string name, ParameterType type, std::string doc);

// The parameters given to one kernel, generator or evaluator, checked against its declarations.
class Parameters {
 public:
  Parameters() = default;
  // Throws std::invalid_argument naming `owner` and the parameter when a name is not declared
  // (listing those that are), a value does not convert to its declared type or lies outside its
  // bounds.
  Parameters(std::vector<ParameterInfo> declared, const std::map<std::string, std::string>& values,
             const std::string& owner);

  // Whether the value was given (rather than defaulted).
  bool has(const std::string& name) const { return values_.contains(name); }

  // The value given, else the declared default. Reading a parameter that was not declared, in
  // another type than declared, or without a default through these is a bug of the caller: it
  // throws std::logic_error.
  bool get_bool(const std::string& name) const;
  int64_t get_int(const std::string& name) const;
  double get_double(const std::string& name) const;
  std::string get_string(const std::string& name) const;
  // An integer parameter read into an int: a value beyond int's range throws
  // std::invalid_argument naming it (a cast would wrap 4294967303 to 7).
  int get_int32(const std::string& name) const;

  // For parameters declared with computed_parameter(): the value given, else `fallback`.
  bool get_bool(const std::string& name, bool fallback) const;
  int64_t get_int(const std::string& name, int64_t fallback) const;
  double get_double(const std::string& name, double fallback) const;
  std::string get_string(const std::string& name, const std::string& fallback) const;

  const std::vector<ParameterInfo>& declared() const { return declared_; }
  // Whose parameters these are ("node 'resize'"), as errors name it.
  const std::string& owner() const { return owner_; }
  // The values given, as text.
  const std::map<std::string, std::string>& values() const { return values_; }
  // Every declared parameter with the value it takes: given, else its default; parameters
  // without a static default appear only when given.
  std::map<std::string, std::string> effective() const;

 private:
  const ParameterInfo& declaration(const std::string& name, ParameterType type) const;
  std::optional<std::string> text(const std::string& name, ParameterType type) const;

  std::vector<ParameterInfo> declared_;
  std::map<std::string, std::string> values_;
  std::string owner_;
};

// Converts `text` as a value of `type` would be read; throws std::invalid_argument saying why
// not. Used to check values and defaults before anything runs.
void check_value(ParameterType type, const std::string& text);
// Also checks that the value lies within the parameter's bounds.
void check_value(const ParameterInfo& parameter, const std::string& text);

// "1 to 268435456", "at least 1", "at most 0.5"; empty without bounds.
std::string bounds_text(const ParameterBounds& bounds);

}  // namespace robotperf::plugin
