// A keyless Fast DDS data type whose sample is the whole serialized payload,
// encapsulation header included, as a byte vector. It lets tests and benchmarks
// read and write exactly the bytes on the wire under any DDS type name, with
// no knowledge of the message layout. Not used by the transport itself.
#pragma once

#include <cstdint>
#include <cstring>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <functional>
#include <string>
#include <vector>

namespace robotperf::rmw {

class FastddsRawBytesType final : public eprosima::fastdds::dds::TopicDataType {
 public:
  using Sample = std::vector<uint8_t>;

  explicit FastddsRawBytesType(const std::string& dds_type_name) {
    setName(dds_type_name.c_str());
    m_typeSize = 4096;
    m_isGetKeyDefined = false;
    auto_fill_type_object(false);
    auto_fill_type_information(false);
  }

  bool serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) override {
    const auto& bytes = *static_cast<const Sample*>(data);
    if (bytes.size() > payload->max_size) return false;
    std::memcpy(payload->data, bytes.data(), bytes.size());
    payload->length = static_cast<uint32_t>(bytes.size());
    payload->encapsulation = CDR_LE;
    return true;
  }

  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
    static_cast<Sample*>(data)->assign(payload->data, payload->data + payload->length);
    return true;
  }

  std::function<uint32_t()> getSerializedSizeProvider(void* data) override {
    return [data] { return static_cast<uint32_t>(static_cast<const Sample*>(data)->size()); };
  }

  void* createData() override { return new Sample(); }
  void deleteData(void* data) override { delete static_cast<Sample*>(data); }

  bool getKey(void*, eprosima::fastrtps::rtps::InstanceHandle_t*, bool) override { return false; }
};

}  // namespace robotperf::rmw
