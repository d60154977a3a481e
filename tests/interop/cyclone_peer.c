/* A second DDS vendor beside hil: Eclipse Cyclone DDS (Debian's libddsc), configured by
 * CYCLONEDDS_URI (idl/profiles/cyclonedds_localhost.xml).
 *
 *   cyclone_peer DOMAIN TF_COUNT
 *
 * Subscribes to hil's standard topics with ROS 2's type names (ros2_types.idl) and the QoS a ROS 2
 * node would use, reads what discovery says of every writer (the DCPSPublication built-in topic:
 * topic, type name, reliability, durability), and publishes TF_COUNT tf2_msgs/TFMessage on rt/tf
 * (child frame "cyclone_frame", one every 100 ms once a reader has matched) for hil to receive.
 * Runs until it has seen at least one message on each topic and sent its messages, or 90 s.
 * Prints one line per discovered hil writer ("writer TOPIC TYPE reliable|best_effort
 * volatile|transient_local"), one per topic ("got TOPIC N first ...") and "sent N". Exit 0 when
 * everything arrived and was sent, 1 otherwise. */
#include <dds/dds.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ros2_types.h"

enum { kWrench, kPose, kTf, kTfStatic, kDiagnostics, kJoints, kSamples, kStatus, kTopics };
static const char* const kNames[kTopics] = {"rt/hil/wrench",    "rt/hil/pose",       "rt/tf",
                                            "rt/tf_static",     "rt/diagnostics",    "rt/hil/joint_states",
                                            "rt/hil/pose_wrench", "rt/hil/device_status"};

static dds_entity_t reader(dds_entity_t p, const dds_topic_descriptor_t* desc, const char* name, int transient_local, int depth) {
  dds_entity_t t = dds_create_topic(p, desc, name, NULL, NULL);
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(q, transient_local ? DDS_DURABILITY_TRANSIENT_LOCAL : DDS_DURABILITY_VOLATILE);
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, depth);
  dds_qset_ignorelocal(q, DDS_IGNORELOCAL_PARTICIPANT);  // not our own rt/tf writer
  dds_entity_t r = dds_create_reader(p, t, q, NULL);
  dds_delete_qos(q);
  if (r < 0) {
    fprintf(stderr, "cyclone_peer: reader on %s: %s\n", name, dds_strretcode(-r));
    exit(2);
  }
  return r;
}

int main(int argc, char** argv) {
  if (argc != 3) {
    fprintf(stderr, "usage: cyclone_peer DOMAIN TF_COUNT\n");
    return 2;
  }
  const int domain = atoi(argv[1]), tf_count = atoi(argv[2]);
  dds_entity_t p = dds_create_participant((dds_domainid_t)domain, NULL, NULL);
  if (p < 0) {
    fprintf(stderr, "cyclone_peer: participant: %s\n", dds_strretcode(-p));
    return 2;
  }
  dds_instance_handle_t self = 0;
  dds_get_instance_handle(p, &self);
  dds_entity_t pubs = dds_create_reader(p, DDS_BUILTIN_TOPIC_DCPSPUBLICATION, NULL, NULL);
  dds_entity_t r[kTopics];
  r[kWrench] = reader(p, &geometry_msgs_msg_dds__WrenchStamped__desc, kNames[kWrench], 0, 1000);
  r[kPose] = reader(p, &geometry_msgs_msg_dds__PoseStamped__desc, kNames[kPose], 0, 1000);
  r[kTf] = reader(p, &tf2_msgs_msg_dds__TFMessage__desc, kNames[kTf], 0, 100);
  r[kTfStatic] = reader(p, &tf2_msgs_msg_dds__TFMessage__desc, kNames[kTfStatic], 1, 1);  // tf2's static listener
  r[kDiagnostics] = reader(p, &diagnostic_msgs_msg_dds__DiagnosticArray__desc, kNames[kDiagnostics], 0, 10);
  r[kJoints] = reader(p, &sensor_msgs_msg_dds__JointState__desc, kNames[kJoints], 0, 1000);
  r[kSamples] = reader(p, &hil_msgs_msg_dds__PoseWrenchSample__desc, kNames[kSamples], 0, 1000);
  r[kStatus] = reader(p, &hil_msgs_msg_dds__DeviceStatus__desc, kNames[kStatus], 1, 10);

  // The publisher into hil: tf2's TransformBroadcaster QoS.
  dds_entity_t tf_topic = dds_find_topic(DDS_FIND_SCOPE_PARTICIPANT, p, "rt/tf", NULL, DDS_SECS(1));
  dds_qos_t* wq = dds_create_qos();
  dds_qset_reliability(wq, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(wq, DDS_HISTORY_KEEP_LAST, 100);
  dds_qset_ignorelocal(wq, DDS_IGNORELOCAL_PARTICIPANT);  // matched by hil's reader, not by ours
  dds_entity_t w = dds_create_writer(p, tf_topic, wq, NULL);
  dds_delete_qos(wq);
  if (w < 0) {
    fprintf(stderr, "cyclone_peer: writer on rt/tf: %s\n", dds_strretcode(-w));
    return 2;
  }

  int got[kTopics] = {0}, sent = 0, ok = 0;
  char first[kTopics][256] = {{0}};
  for (int tick = 0; tick < 900 && !ok; ++tick) {
    void* s[16] = {NULL};
    dds_sample_info_t info[16];
    int n;
    while ((n = dds_take(pubs, s, info, 16, 16)) > 0) {
      for (int i = 0; i < n; ++i) {
        const dds_builtintopic_endpoint_t* e = s[i];
        if (!info[i].valid_data || strncmp(e->topic_name, "rt/", 3) != 0) continue;
        dds_reliability_kind_t rel = DDS_RELIABILITY_BEST_EFFORT;
        dds_duration_t block;
        dds_durability_kind_t dur = DDS_DURABILITY_VOLATILE;
        dds_qget_reliability(e->qos, &rel, &block);
        dds_qget_durability(e->qos, &dur);
        if (e->participant_instance_handle == self) continue; /* our own writer */
        printf("writer %s %s %s %s\n", e->topic_name, e->type_name, rel == DDS_RELIABILITY_RELIABLE ? "reliable" : "best_effort",
               dur == DDS_DURABILITY_TRANSIENT_LOCAL ? "transient_local" : "volatile");
      }
      dds_return_loan(pubs, s, n);
    }
    for (int k = 0; k < kTopics; ++k) {
      while ((n = dds_take(r[k], s, info, 16, 16)) > 0) {
        for (int i = 0; i < n; ++i) {
          if (!info[i].valid_data) continue;
          if (got[k]++ > 0) continue;
          if (k == kWrench) {
            const geometry_msgs_msg_dds__WrenchStamped_* m = s[i];
            snprintf(first[k], sizeof first[k], "frame %s stamp %d.%09u fz %.17g", m->header.frame_id, m->header.stamp.sec,
                     m->header.stamp.nanosec, m->wrench.force.z);
          } else if (k == kPose) {
            const geometry_msgs_msg_dds__PoseStamped_* m = s[i];
            snprintf(first[k], sizeof first[k], "frame %s stamp %d.%09u qw %.17g", m->header.frame_id, m->header.stamp.sec,
                     m->header.stamp.nanosec, m->pose.orientation.w);
          } else if (k == kTf || k == kTfStatic) {
            const tf2_msgs_msg_dds__TFMessage_* m = s[i];
            const geometry_msgs_msg_dds__TransformStamped_* t = m->transforms._length ? &m->transforms._buffer[0] : NULL;
            snprintf(first[k], sizeof first[k], "transforms %u first %s -> %s", m->transforms._length, t ? t->header.frame_id : "-",
                     t ? t->child_frame_id : "-");
          } else if (k == kJoints) {
            const sensor_msgs_msg_dds__JointState_* m = s[i];
            snprintf(first[k], sizeof first[k], "names %u first %s positions %u", m->name._length, m->name._length ? m->name._buffer[0] : "-",
                     m->position._length);
          } else if (k == kSamples) {
            const hil_msgs_msg_dds__PoseWrenchSample_* m = s[i];
            snprintf(first[k], sizeof first[k], "index %llu fz %.17g pz %.17g", (unsigned long long)m->sample_index, m->wrench_fp.force.z,
                     m->pose_world_ee.position.z);
          } else if (k == kStatus) {
            const hil_msgs_msg_dds__DeviceStatus_* m = s[i];
            snprintf(first[k], sizeof first[k], "device %s state %u", m->device, (unsigned)m->state);
          } else {
            const diagnostic_msgs_msg_dds__DiagnosticArray_* m = s[i];
            snprintf(first[k], sizeof first[k], "status %u first %s", m->status._length,
                     m->status._length ? m->status._buffer[0].name : "-");
          }
        }
        dds_return_loan(r[k], s, n);
      }
    }
    dds_publication_matched_status_t st;
    if (sent < tf_count && dds_get_publication_matched_status(w, &st) == DDS_RETCODE_OK && st.current_count > 0) {
      geometry_msgs_msg_dds__TransformStamped_ t;
      memset(&t, 0, sizeof t);
      t.header.frame_id = "world";
      t.child_frame_id = "cyclone_frame";
      t.header.stamp.sec = 1767225600 + sent;
      t.transform.translation.x = 0.25 * sent;
      t.transform.rotation.w = 1.0;
      tf2_msgs_msg_dds__TFMessage_ m;
      m.transforms._maximum = m.transforms._length = 1;
      m.transforms._buffer = &t;
      m.transforms._release = false;
      if (dds_write(w, &m) == DDS_RETCODE_OK) ++sent;
    }
    ok = sent == tf_count;
    for (int k = 0; k < kTopics; ++k) ok = ok && got[k] > 0;
    dds_sleepfor(DDS_MSECS(100));
  }
  for (int k = 0; k < kTopics; ++k) printf("got %s %d %s\n", kNames[k], got[k], first[k]);
  printf("sent %d\n", sent);
  fflush(stdout);
  dds_sleepfor(DDS_MSECS(500));  // the last messages reach their reader before the writer goes
  dds_delete(p);
  return ok ? 0 : 1;
}
