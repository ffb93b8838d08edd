#include "robotperf/msgs/type_support.hpp"

#include <stdexcept>

namespace robotperf::msgs {

std::string dds_type_name(std::string_view ros_type) {
  // <pkg>/msg/<Type>  ->  <pkg>::msg::dds_::<Type>_
  const auto first = ros_type.find('/');
  const auto last = ros_type.rfind('/');
  if (first == std::string_view::npos || first == last) {
    throw std::invalid_argument("ROS type name must look like pkg/msg/Type: " +
                                std::string(ros_type));
  }
  std::string out(ros_type.substr(0, first));
  out += "::";
  out += ros_type.substr(first + 1, last - first - 1);
  out += "::dds_::";
  out += ros_type.substr(last + 1);
  out += '_';
  return out;
}

std::string ros_type_name(std::string_view dds_type) {
  // <pkg>::<kind>::dds_::<Type>_  ->  <pkg>/<kind>/<Type>
  const auto dds = dds_type.find("::dds_::");
  const auto first = dds_type.find("::");
  if (dds == std::string_view::npos || first == dds || !dds_type.ends_with('_')) {
    return std::string(dds_type);
  }
  std::string out(dds_type.substr(0, first));
  out += '/';
  out += dds_type.substr(first + 2, dds - first - 2);
  out += '/';
  const std::string_view type = dds_type.substr(dds + 8);
  out += type.substr(0, type.size() - 1);
  return out;
}

}  // namespace robotperf::msgs
