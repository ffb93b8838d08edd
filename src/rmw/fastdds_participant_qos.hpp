// Private to the rmw library (and its tests and benchmarks): the participant
// configuration of the Fast DDS transport, so that a plain Fast DDS baseline
// can run under exactly the same settings.
#pragma once

#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

namespace robotperf::rmw {

// Fast DDS's defaults (after any XML profile the user points Fast DDS at),
// named "robotperf", with a shared-memory segment large enough for
// multi-megabyte messages when the profile keeps the built-in transports.
eprosima::fastdds::dds::DomainParticipantQos fastdds_participant_qos();

}  // namespace robotperf::rmw
