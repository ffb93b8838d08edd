/* A ROS 2-style image node that is not robotperf: written in C against Cyclone DDS's C API, with
 * its message types compiled by Cyclone's IDL compiler (ros2_types.idl), as a node of another
 * team would be. It behaves as rmw_cyclonedds makes a ROS 2 node behave on the wire: topics
 * rt/<name>, ROS 2's default QoS (reliable, volatile, keep last 10), "enclave=/;" in its
 * participant's USER_DATA, its type's hash in each endpoint's USER_DATA, and its node announced on
 * ros_discovery_info. It republishes each sensor_msgs/Image it receives.
 *
 *   foreign_image_node DOMAIN IN_TOPIC OUT_TOPIC MODE [NODE_NAME]
 *
 * MODE: copy (the message as received, header included), restamp (header.stamp set to the time
 * of republishing, as a node that makes a new header would), drop (never republish), or
 * exit-after=N (copy N, then exit with status 7). Runs until SIGINT or SIGTERM. */
#include <dds/dds.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "ros2_types.h"

/* sensor_msgs/msg/Image's REP 2011 hash, as rosidl generates it into a node's type support. */
#define IMAGE_TYPE_HASH "RIHS01_d31d41a9a4c4bc8eae9be757b0beed306564f7526c88ea6a4588fb9582527d47"

static volatile sig_atomic_t stop_requested = 0;
static void on_signal(int sig) {
  (void)sig;
  stop_requested = 1;
}

static void fail(const char* what, dds_return_t rc) {
  fprintf(stderr, "foreign_image_node: %s: %s\n", what, dds_strretcode(rc));
  exit(2);
}

static dds_entity_t check(dds_entity_t e, const char* what) {
  if (e < 0) fail(what, e);
  return e;
}

static void gid_of(dds_entity_t entity, rmw_dds_common_msg_dds__Gid_* gid) {
  dds_guid_t guid;
  if (dds_get_guid(entity, &guid) != DDS_RETCODE_OK) fail("dds_get_guid", DDS_RETCODE_ERROR);
  memcpy(gid->data, guid.v, sizeof gid->data);
}

int main(int argc, char** argv) {
  if (argc < 5) {
    fprintf(stderr, "usage: foreign_image_node DOMAIN IN_TOPIC OUT_TOPIC MODE [NODE_NAME]\n");
    return 2;
  }
  const dds_domainid_t domain = (dds_domainid_t)atoi(argv[1]);
  const char* mode = argv[4];
  const char* node_name = argc > 5 ? argv[5] : "foreign_image_node";
  const int restamp = strcmp(mode, "restamp") == 0;
  const int drop = strcmp(mode, "drop") == 0;
  long exit_after = -1;
  if (strncmp(mode, "exit-after=", 11) == 0) exit_after = atol(mode + 11);
  if (!restamp && !drop && exit_after < 0 && strcmp(mode, "copy") != 0) {
    fprintf(stderr, "foreign_image_node: unknown mode '%s'\n", mode);
    return 2;
  }
  char in_topic[256], out_topic[256];
  snprintf(in_topic, sizeof in_topic, "rt%s", argv[2]);
  snprintf(out_topic, sizeof out_topic, "rt%s", argv[3]);
  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);

  dds_qos_t* qos = dds_create_qos();
  dds_qset_userdata(qos, "enclave=/;", strlen("enclave=/;"));
  const dds_entity_t participant = check(dds_create_participant(domain, qos, NULL), "participant");
  dds_delete_qos(qos);

  qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 10);
  const char* user_data = "typehash=" IMAGE_TYPE_HASH ";";
  dds_qset_userdata(qos, user_data, strlen(user_data));
  const dds_entity_t in =
      check(dds_create_topic(participant, &sensor_msgs_msg_dds__Image__desc, in_topic, NULL, NULL),
            "topic in");
  const dds_entity_t out =
      check(dds_create_topic(participant, &sensor_msgs_msg_dds__Image__desc, out_topic, NULL, NULL),
            "topic out");
  const dds_entity_t reader = check(dds_create_reader(participant, in, qos, NULL), "reader");
  const dds_entity_t writer = check(dds_create_writer(participant, out, qos, NULL), "writer");
  dds_delete_qos(qos);

  /* The node on ros_discovery_info: reliable, transient local, keep last 1, as rmw_dds_common. */
  qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
  const dds_entity_t discovery_topic =
      check(dds_create_topic(participant, &rmw_dds_common_msg_dds__ParticipantEntitiesInfo__desc,
                             "ros_discovery_info", NULL, NULL),
            "ros_discovery_info topic");
  const dds_entity_t discovery =
      check(dds_create_writer(participant, discovery_topic, qos, NULL), "ros_discovery_info");
  dds_delete_qos(qos);
  rmw_dds_common_msg_dds__Gid_ reader_gid, writer_gid;
  gid_of(reader, &reader_gid);
  gid_of(writer, &writer_gid);
  rmw_dds_common_msg_dds__NodeEntitiesInfo_ node;
  memset(&node, 0, sizeof node);
  snprintf(node.node_namespace, sizeof node.node_namespace, "/");
  snprintf(node.node_name, sizeof node.node_name, "%s", node_name);
  node.reader_gid_seq._length = node.reader_gid_seq._maximum = 1;
  node.reader_gid_seq._buffer = &reader_gid;
  node.writer_gid_seq._length = node.writer_gid_seq._maximum = 1;
  node.writer_gid_seq._buffer = &writer_gid;
  rmw_dds_common_msg_dds__ParticipantEntitiesInfo_ info;
  memset(&info, 0, sizeof info);
  gid_of(participant, &info.gid);
  info.node_entities_info_seq._length = info.node_entities_info_seq._maximum = 1;
  info.node_entities_info_seq._buffer = &node;
  dds_return_t rc = dds_write(discovery, &info);
  if (rc != DDS_RETCODE_OK) fail("ros_discovery_info write", rc);

  const dds_entity_t waitset = check(dds_create_waitset(participant), "waitset");
  const dds_entity_t readable = check(dds_create_readcondition(reader, DDS_ANY_STATE), "condition");
  dds_waitset_attach(waitset, readable, 0);
  fprintf(stderr, "foreign_image_node: %s -> %s (%s)\n", argv[2], argv[3], mode);
  long republished = 0;
  while (!stop_requested) {
    dds_waitset_wait(waitset, NULL, 0, DDS_MSECS(100));
    void* samples[1] = {NULL};
    dds_sample_info_t sample_info;
    while (dds_take(reader, samples, &sample_info, 1, 1) == 1) {
      if (sample_info.valid_data && !drop) {
        sensor_msgs_msg_dds__Image_ image = *(const sensor_msgs_msg_dds__Image_*)samples[0];
        if (restamp) {
          struct timespec now;
          clock_gettime(CLOCK_REALTIME, &now);
          image.header.stamp.sec = (int32_t)now.tv_sec;
          image.header.stamp.nanosec = (uint32_t)now.tv_nsec;
        }
        rc = dds_write(writer, &image);
        if (rc != DDS_RETCODE_OK) fail("write", rc);
        ++republished;
      }
      dds_return_loan(reader, samples, 1);
      samples[0] = NULL;
      if (exit_after >= 0 && republished >= exit_after) {
        fprintf(stderr, "foreign_image_node: exiting after %ld images\n", republished);
        dds_delete(participant);
        return 7;
      }
    }
  }
  fprintf(stderr, "foreign_image_node: stopped after %ld images\n", republished);
  dds_delete(participant);
  return 0;
}
