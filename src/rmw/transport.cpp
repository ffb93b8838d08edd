#include "robotperf/rmw/transport.hpp"

#include <time.h>

#include <cctype>
#include <cstdlib>
#include <stdexcept>

#include "fastdds_transport.hpp"
#include "intra_transport.hpp"

namespace robotperf::rmw {

QoS QoS::from_profile_name(const std::string& name) {
  if (name == "default") return ros_default();
  if (name == "sensor_data") return sensor_data();
  throw std::invalid_argument("unknown QoS profile '" + name + "' (choose default or sensor_data)");
}

std::unique_ptr<Transport> make_transport(const std::string& name,
                                          const TransportOptions& options) {
  if (name == "intra") return make_intra_transport();
  if (name == "fastdds") return make_fastdds_transport(options);
  throw std::invalid_argument("unknown transport '" + name + "' (choose intra or fastdds)");
}

int domain_id_from_environment() {
  const char* value = std::getenv("ROS_DOMAIN_ID");
  if (value == nullptr || *value == '\0') return 0;
  char* end = nullptr;
  const long id = std::strtol(value, &end, 10);
  // 232 is the largest domain whose RTPS ports still fit in 16 bits.
  if (*end != '\0' || id < 0 || id > 232) {
    throw std::invalid_argument(std::string("ROS_DOMAIN_ID='") + value +
                                "' is not a domain id between 0 and 232");
  }
  return static_cast<int>(id);
}

int64_t steady_now_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

int64_t wall_now_ns() {
  timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

std::string dds_topic_name(const std::string& ros_topic) {
  auto bad = [&](const char* why) {
    return std::invalid_argument("invalid topic name '" + ros_topic + "': " + why);
  };
  if (ros_topic.empty() || ros_topic[0] != '/') throw bad("must be absolute (start with '/')");
  if (ros_topic.size() > 1 && ros_topic.back() == '/') throw bad("must not end with '/'");
  char prev = 0;
  for (char c : ros_topic) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '/')) {
      throw bad("only letters, digits, '_' and '/' are allowed");
    }
    if (c == '/' && prev == '/') throw bad("must not contain '//'");
    if (std::isdigit(static_cast<unsigned char>(c)) && prev == '/') {
      throw bad("a name token must not start with a digit");
    }
    prev = c;
  }
  return "rt" + ros_topic;
}

}  // namespace robotperf::rmw
