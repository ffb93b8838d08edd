// sensor_msgs/Image as a plain Fast DDS program carries it: a TopicDataType whose (de)serialization
// is Fast CDR's own, field by field, as Fast DDS's code generator (fastddsgen) and ROS 2's
// rmw_fastrtps type support write it. The bench's typed baseline; robotperf's transport uses its
// own CDR code instead.
#pragma once

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastcdr/exceptions/Exception.h>

#include <cstdint>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <functional>

#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::bench {

class FastCdrImageType final : public eprosima::fastdds::dds::TopicDataType {
 public:
  using Sample = msgs::Image;

  FastCdrImageType() {
    setName("sensor_msgs::msg::dds_::Image_");
    m_typeSize = 4096;
    m_isGetKeyDefined = false;
    auto_fill_type_object(false);
    auto_fill_type_information(false);
  }

  bool serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) override {
    const auto& image = *static_cast<const Sample*>(data);
    eprosima::fastcdr::FastBuffer buffer(reinterpret_cast<char*>(payload->data), payload->max_size);
    eprosima::fastcdr::Cdr cdr(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN,
                               eprosima::fastcdr::Cdr::DDS_CDR);
    payload->encapsulation =
        cdr.endianness() == eprosima::fastcdr::Cdr::BIG_ENDIANNESS ? CDR_BE : CDR_LE;
    try {
      cdr.serialize_encapsulation();
      cdr << image.header.stamp.sec << image.header.stamp.nanosec << image.header.frame_id
          << image.height << image.width << image.encoding << image.is_bigendian << image.step
          << image.data;
    } catch (const eprosima::fastcdr::exception::Exception&) {
      return false;
    }
    payload->length = static_cast<uint32_t>(cdr.getSerializedDataLength());
    return true;
  }

  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
    auto& image = *static_cast<Sample*>(data);
    eprosima::fastcdr::FastBuffer buffer(reinterpret_cast<char*>(payload->data), payload->length);
    eprosima::fastcdr::Cdr cdr(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN,
                               eprosima::fastcdr::Cdr::DDS_CDR);
    try {
      cdr.read_encapsulation();
      cdr >> image.header.stamp.sec >> image.header.stamp.nanosec >> image.header.frame_id >>
          image.height >> image.width >> image.encoding >> image.is_bigendian >> image.step >>
          image.data;
    } catch (const eprosima::fastcdr::exception::Exception&) {
      return false;
    }
    return true;
  }

  // The generated code's getCdrSerializedSize: each field at its alignment, after the header.
  std::function<uint32_t()> getSerializedSizeProvider(void* data) override {
    return [data] {
      const auto& image = *static_cast<const Sample*>(data);
      using eprosima::fastcdr::Cdr;
      std::size_t at = 0;
      auto field = [&at](std::size_t size, std::size_t align) {
        at += Cdr::alignment(at, align) + size;
      };
      auto string = [&](const std::string& s) {
        field(4, 4);  // its length, then its characters and a NUL
        at += s.size() + 1;
      };
      field(4, 4);  // stamp.sec
      field(4, 4);  // stamp.nanosec
      string(image.header.frame_id);
      field(4, 4);  // height
      field(4, 4);  // width
      string(image.encoding);
      field(1, 1);  // is_bigendian
      field(4, 4);  // step
      field(4, 4);  // data's length
      at += image.data.size();
      return static_cast<uint32_t>(4 + at);  // and the encapsulation header
    };
  }

  void* createData() override { return new Sample(); }
  void deleteData(void* data) override { delete static_cast<Sample*>(data); }

  bool getKey(void*, eprosima::fastrtps::rtps::InstanceHandle_t*, bool) override { return false; }
};

}  // namespace robotperf::bench
