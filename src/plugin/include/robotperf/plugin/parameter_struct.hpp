// Typed parameters: a kernel, dataset generator or evaluator declares a struct of its settings
// once, member by member, and reads the whole struct back. Each parameter's type follows from its
// member's type and its default is given in that type, so that the name, the type and the member
// are written in one place: no parameter is read back by name, and a type mismatch does not
// compile. The declarations and checks of parameters.hpp stay underneath: given values are still
// checked against the declarations (and their bounds) when Parameters is built.
//
//   struct RelaySettings { std::string type; double delay_ms; int64_t drop_every; };
//   const plugin::ParameterStruct<RelaySettings> kRelayParameters{
//       plugin::field(&RelaySettings::type, "type", "sensor_msgs/msg/Image", "ROS type"),
//       plugin::field(&RelaySettings::delay_ms, "delay_ms", 0, "hold, ms", {.minimum = 0}),
//       plugin::field(&RelaySettings::drop_every, "drop_every", 0, "drop every k-th")};
//   KernelInfo{..., .parameters = kRelayParameters.declarations()};
//   const RelaySettings s = kRelayParameters.read(config.parameters);
#pragma once

#include <concepts>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "robotperf/plugin/parameters.hpp"

namespace robotperf::plugin {

// The member types a parameter is read into: bool, any integer (declared int; a value beyond the
// member's range is refused when read), float or double (declared double) and std::string.
template <class T>
concept ParameterValue = std::same_as<T, bool> || std::integral<T> || std::floating_point<T> ||
    std::same_as<T, std::string>;

// One member of a settings struct S and the parameter it is read from.
template <class S>
struct ParameterField {
  ParameterInfo declaration;
  // Fills the member of `settings` from `parameters`.
  std::function<void(const Parameters& parameters, S& settings)> read;
  // The member's address within `settings`: how ParameterStruct::given() finds its parameter.
  std::function<const void*(const S& settings)> member;
};

namespace detail {

// Throws std::invalid_argument naming the parameter when `value` lies outside min to max, the
// range of the member it is read into, described as `type` ("a 32-bit integer"). Inline, as all
// of this header is, so that a plug-in reading typed parameters needs no symbol of the plug-in
// library that the untyped access did not already need.
inline void check_integer_range(const Parameters& parameters, const std::string& name,
                                int64_t value, int64_t min, int64_t max, const std::string& type) {
  if (value < min || value > max) {
    throw std::invalid_argument(parameters.owner() + ": parameter '" + name + "' is " +
                                std::to_string(value) + ", beyond " + type);
  }
}

// "a 16-bit unsigned integer".
template <std::integral T>
std::string integer_type_text() {
  constexpr int bits = std::numeric_limits<T>::digits + std::is_signed_v<T>;
  return std::string(bits == 8 ? "an " : "a ") + std::to_string(bits) + "-bit " +
         (std::is_signed_v<T> ? "" : "unsigned ") + "integer";
}

template <ParameterValue T>
T read_value(const Parameters& parameters, const std::string& name) {
  if constexpr (std::same_as<T, bool>) {
    return parameters.get_bool(name);
  } else if constexpr (std::integral<T>) {
    const int64_t value = parameters.get_int(name);
    // The range of T as far as an int64_t reaches (a uint64_t's top half is beyond it).
    constexpr int64_t min = std::is_signed_v<T> ? int64_t{std::numeric_limits<T>::min()} : 0;
    constexpr int64_t max = std::numeric_limits<T>::max() > uint64_t{INT64_MAX}
                                ? INT64_MAX
                                : static_cast<int64_t>(std::numeric_limits<T>::max());
    check_integer_range(parameters, name, value, min, max, integer_type_text<T>());
    return static_cast<T>(value);
  } else if constexpr (std::floating_point<T>) {
    return static_cast<T>(parameters.get_double(name));
  } else {
    return parameters.get_string(name);
  }
}

template <ParameterValue T>
constexpr ParameterType parameter_type() {
  if constexpr (std::same_as<T, bool>) return ParameterType::kBool;
  if constexpr (std::integral<T>) return ParameterType::kInt;
  if constexpr (std::floating_point<T>) return ParameterType::kDouble;
  return ParameterType::kString;
}

template <ParameterValue T>
ParameterInfo declaration(std::string name, const T& default_value, std::string doc,
                          ParameterBounds bounds) {
  if constexpr (std::same_as<T, bool>) {
    return bool_parameter(std::move(name), default_value, std::move(doc));
  } else if constexpr (std::integral<T>) {
    if (std::cmp_greater(default_value, INT64_MAX))
      throw std::logic_error("parameter '" + name + "': its default is beyond an int parameter");
    return int_parameter(std::move(name), static_cast<int64_t>(default_value), std::move(doc),
                         bounds);
  } else if constexpr (std::floating_point<T>) {
    return double_parameter(std::move(name), default_value, std::move(doc), bounds);
  } else {
    return string_parameter(std::move(name), default_value, std::move(doc));
  }
}

// Bounds are checked on numbers only: on another type they are a mistake of the declaration.
template <ParameterValue T>
void check_bounds_apply(const std::string& name, const ParameterBounds& bounds) {
  constexpr bool number = std::integral<T> && !std::same_as<T, bool>;
  if (!number && !std::floating_point<T> && (bounds.minimum || bounds.maximum))
    throw std::logic_error("parameter '" + name + "': bounds on a parameter that is not a number");
}

template <class S, class M>
std::function<const void*(const S&)> member_address(M S::*member) {
  return [member](const S& settings) -> const void* { return &(settings.*member); };
}

}  // namespace detail

// A parameter with a default, read into `member`; a number may have the range its given values
// must lie in.
template <class S, ParameterValue M>
ParameterField<S> field(M S::*member, std::string name, std::type_identity_t<M> default_value,
                        std::string doc, ParameterBounds bounds = {}) {
  detail::check_bounds_apply<M>(name, bounds);
  ParameterInfo info = detail::declaration<M>(name, default_value, std::move(doc), bounds);
  return {std::move(info),
          [member, name](const Parameters& p, S& s) { s.*member = detail::read_value<M>(p, name); },
          detail::member_address(member)};
}

// A parameter whose default the code computes from other parameters or the workload (the doc says
// how): declared without a default, read as the value given or std::nullopt.
template <class S, ParameterValue T>
ParameterField<S> field(std::optional<T> S::*member, std::string name, std::string doc,
                        ParameterBounds bounds = {}) {
  detail::check_bounds_apply<T>(name, bounds);
  ParameterInfo info{name, detail::parameter_type<T>(), std::nullopt, std::move(doc), bounds};
  return {std::move(info),
          [member, name](const Parameters& p, S& s) {
            s.*member =
                p.has(name) ? std::optional<T>(detail::read_value<T>(p, name)) : std::nullopt;
          },
          detail::member_address(member)};
}

template <class S>
class ParameterStruct;

// The parameters of a struct that is a member of S (settings several kernels share), declared
// and read in its place.
template <class S, class Inner>
std::vector<ParameterField<S>> nested(Inner S::*member, const ParameterStruct<Inner>& inner) {
  std::vector<ParameterField<S>> out;
  for (const ParameterField<Inner>& f : inner.fields()) {
    out.push_back({f.declaration,
                   [member, read = f.read](const Parameters& p, S& s) { read(p, s.*member); },
                   [member, address = f.member](const S& s) { return address(s.*member); }});
  }
  return out;
}

// The parameters of settings struct S, in the order declared: what KernelInfo, DatasetInfo and
// EvaluatorInfo list, and how S is read back from the Parameters built from that list.
template <class S>
class ParameterStruct {
 public:
  // Each part is a field() or the fields of a nested() struct.
  template <class... Parts>
  explicit ParameterStruct(Parts... parts) {
    (add(std::move(parts)), ...);
  }

  std::vector<ParameterInfo> declarations() const {
    std::vector<ParameterInfo> out;
    for (const auto& f : fields_) out.push_back(f.declaration);
    return out;
  }

  // Every member read: the value given, else the declared default (std::nullopt for a computed
  // one); members without a field keep their initializers. `parameters` must have been built
  // from declarations(); an integer beyond its member's range throws std::invalid_argument
  // naming it.
  S read(const Parameters& parameters) const {
    S settings{};
    for (const auto& f : fields_) f.read(parameters, settings);
    return settings;
  }

  // Whether the parameter of `member`, a member of `settings` as read() returned it (a nested
  // one too), was given rather than defaulted.
  template <class M>
  bool given(const Parameters& parameters, const S& settings, const M& member) const {
    for (const auto& f : fields_) {
      if (f.member(settings) == static_cast<const void*>(&member))
        return parameters.has(f.declaration.name);
    }
    throw std::logic_error("given(): the member asked about is not one of the settings'");
  }

  const std::vector<ParameterField<S>>& fields() const { return fields_; }

 private:
  void add(ParameterField<S> f) { fields_.push_back(std::move(f)); }
  void add(std::vector<ParameterField<S>> fs) {
    for (auto& f : fs) fields_.push_back(std::move(f));
  }

  std::vector<ParameterField<S>> fields_;
};

}  // namespace robotperf::plugin
