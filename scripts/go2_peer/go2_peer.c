/* go2_peer: a Cyclone DDS 0.10.x C peer for the GO2's low-level topics, built against the same
 * Cyclone C stack (0.10.2) as unitree_sdk2 and unitree_mujoco, to check that our Python side
 * (cyclonedds 11.0.1) interoperates with it. See scripts/go2_peer/build.sh and
 * tests/test_dds_interop.py.
 *
 * Modes:
 *   echo-state     take LowState_ from rt/lowstate; answer each with a LowCmd_ on rt/lowcmd made
 *                  by the echo rule below (crc left 0). Stops once it has answered the state with
 *                  tick == --count, after a short linger that answers any resend of it.
 *   publish-state  publish the known LowState_ for ticks 1..--count on rt/lowstate (crc set as
 *                  the SDK computes it), each until the LowCmd_ that echoes it comes back on
 *                  rt/lowcmd (lockstep, resent every --period-ms); compare every LowCmd_ with the
 *                  echo of the state it names, and stop at the first that differs.
 *
 * Both sides of a test implement the same two functions, so each checks the other exactly:
 *   known_state(k)  every field of LowState_ a function of the tick k (floats exact in float32);
 *   echo(state)     LowCmd_: head, level_flag, frame_reserve, sn, version, bandwidth copied;
 *                   motor_cmd[i] = {mode, q, dq, tau_est} of motor_state[i], kp =
 *                   imu.quaternion[i % 4], kd = foot_force[i % 4], reserve[0] = lost;
 *                   bms_cmd.off = bms.soc; wireless_remote copied; led[0..3] = temperature_ntc1,
 *                   temperature_ntc2, imu.temperature, bit_flag; fan[j] = fan_frequency[j] & 0xFF;
 *                   gpio = bms.status; reserve = tick; crc = 0.
 * Received messages are compared whole, except crc, which is reported as crc_valid (whether it
 * is the SDK's CRC of the C image): the peer sets it on its states, our side may or may not.
 *
 * QoS as unitree_sdk2's channels: writers reliable (max blocking 100 ms) keep-last 1, readers
 * best-effort keep-last 1. Pin the peer to an interface with CYCLONEDDS_URI.
 *
 * Output: one line per message received, then one summary line
 *   go2_peer summary: mode=... cyclonedds=0.10.2 sent=N received=N ... errors=N
 *   invalid_type_object=N result=ok|incomplete|mismatch|error
 * Exit status: 0 ok, 1 incomplete (timeout), 2 usage or DDS setup error, 3 mismatch or errors
 * logged by Cyclone.
 */
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dds/dds.h"
#include "dds/version.h"
#include "unitree_go.h"

typedef unitree_go_msg_dds__LowState_ LowState;
typedef unitree_go_msg_dds__LowCmd_ LowCmd;

/* The C memory images the SDK's CRC is computed over (sizes of the C++ classes). */
_Static_assert(sizeof(LowCmd) == 812, "LowCmd_ must be 812 bytes as in the C++ SDK");
_Static_assert(sizeof(LowState) == 1180, "LowState_ must be 1180 bytes as in the C++ SDK");

#define POS_STOP_F 2.146e9f
#define VEL_STOP_F 16000.0f

/* ---- Cyclone's log: count errors and type-object complaints, forward everything to stderr. */

static atomic_int logged_errors;
static atomic_int logged_invalid_type;

static void log_sink(void *arg, const dds_log_data_t *data)
{
  (void)arg;
  if (data->priority & (DDS_LC_FATAL | DDS_LC_ERROR))
    atomic_fetch_add(&logged_errors, 1);
  if (strstr(data->message, "invalid type object") != NULL)
    atomic_fetch_add(&logged_invalid_type, 1);
  fwrite(data->message, 1, data->size, stderr);
  if (data->size == 0 || data->message[data->size - 1] != '\n')
    fputc('\n', stderr);
  fflush(stderr);
}

/* ---- CRC-32/MPEG-2 over the little-endian 32-bit words of the C image, excluding crc. */

static uint32_t crc32_words(const void *image, size_t n_words)
{
  uint32_t crc = 0xFFFFFFFFu;
  const unsigned char *bytes = image;
  for (size_t i = 0; i < n_words; i++) {
    uint32_t word;
    memcpy(&word, bytes + 4 * i, 4);
    for (int bit = 0; bit < 32; bit++) {
      uint32_t top = (crc ^ word) & 0x80000000u;
      crc <<= 1;
      if (top)
        crc ^= 0x04C11DB7u;
      word <<= 1;
    }
  }
  return crc;
}

static uint32_t low_cmd_crc(const LowCmd *cmd) { return crc32_words(cmd, sizeof(*cmd) / 4 - 1); }

static uint32_t low_state_crc(const LowState *state)
{
  return crc32_words(state, sizeof(*state) / 4 - 1);
}

/* The test vectors of the facts sheet, checked once at start. */
static int crc_self_test(void)
{
  LowCmd cmd;
  LowState state;
  memset(&cmd, 0, sizeof(cmd));
  memset(&state, 0, sizeof(state));
  int ok = low_cmd_crc(&cmd) == 0x4B5A4880u && low_state_crc(&state) == 0x85F11EA6u;
  cmd.head[0] = 0xFE;
  cmd.head[1] = 0xEF;
  cmd.level_flag = 0xFF;
  for (int i = 0; i < 20; i++) {
    cmd.motor_cmd[i].mode = 0x01;
    cmd.motor_cmd[i].q = POS_STOP_F;
    cmd.motor_cmd[i].dq = VEL_STOP_F;
  }
  return ok && low_cmd_crc(&cmd) == 0x06E577CDu;
}

/* ---- The two shared functions (mirrored in tests/test_dds_interop.py). */

static void known_state(uint32_t k, LowState *s)
{
  memset(s, 0, sizeof(*s));
  s->head[0] = 0xFE;
  s->head[1] = 0xEF;
  s->level_flag = 0xFF;
  s->frame_reserve = (uint8_t)(k & 0xFF);
  s->sn[0] = k;
  s->sn[1] = 1000 + k;
  s->version[0] = 0x0102;
  s->version[1] = 0x0304;
  s->bandwidth = (uint16_t)(0x1200 + (k & 0xFF));
  for (int j = 0; j < 4; j++)
    s->imu_state.quaternion[j] = (float)k + 0.25f * (float)j;
  for (int j = 0; j < 3; j++) {
    s->imu_state.gyroscope[j] = -((float)k + 0.5f * (float)j);
    s->imu_state.accelerometer[j] = 9.75f + (float)j;
    s->imu_state.rpy[j] = 0.125f * (float)j;
  }
  s->imu_state.temperature = (uint8_t)(40 + k % 10);
  for (int i = 0; i < 20; i++) {
    s->motor_state[i].mode = 0x01;
    s->motor_state[i].q = 0.5f * (float)i + 0.0625f * (float)k;
    s->motor_state[i].dq = -0.25f * (float)i;
    s->motor_state[i].ddq = 0.0f;
    s->motor_state[i].tau_est = 0.125f * (float)i;
    s->motor_state[i].q_raw = 0.0f;
    s->motor_state[i].dq_raw = 0.0f;
    s->motor_state[i].ddq_raw = 0.0f;
    s->motor_state[i].temperature = (uint8_t)(30 + i);
    s->motor_state[i].lost = 20 * k + (uint32_t)i;
    s->motor_state[i].reserve[0] = (uint32_t)i;
    s->motor_state[i].reserve[1] = k;
  }
  s->bms_state.version_high = 1;
  s->bms_state.version_low = 2;
  s->bms_state.status = 3;
  s->bms_state.soc = (uint8_t)(k % 101);
  s->bms_state.current = -1500;
  s->bms_state.cycle = 7;
  s->bms_state.bq_ntc[0] = 25;
  s->bms_state.bq_ntc[1] = 26;
  s->bms_state.mcu_ntc[0] = 27;
  s->bms_state.mcu_ntc[1] = 28;
  for (int j = 0; j < 15; j++)
    s->bms_state.cell_vol[j] = (uint16_t)(3700 + j);
  for (int j = 0; j < 4; j++) {
    s->foot_force[j] = (int16_t)(10 * j - 15);
    s->foot_force_est[j] = (int16_t)(-j);
  }
  s->tick = k;
  for (int j = 0; j < 40; j++)
    s->wireless_remote[j] = (uint8_t)((7 * j + k) & 0xFF);
  s->bit_flag = 0x5A;
  s->adc_reel = 0.5f;
  s->temperature_ntc1 = 45;
  s->temperature_ntc2 = 46;
  s->power_v = 28.25f;
  s->power_a = -1.5f;
  for (int j = 0; j < 4; j++)
    s->fan_frequency[j] = (uint16_t)(1000 * j + k);
  s->reserve = 0xDEADBEEFu;
  s->crc = 0;
}

static void echo(const LowState *s, LowCmd *c)
{
  memset(c, 0, sizeof(*c));
  memcpy(c->head, s->head, sizeof(c->head));
  c->level_flag = s->level_flag;
  c->frame_reserve = s->frame_reserve;
  memcpy(c->sn, s->sn, sizeof(c->sn));
  memcpy(c->version, s->version, sizeof(c->version));
  c->bandwidth = s->bandwidth;
  for (int i = 0; i < 20; i++) {
    c->motor_cmd[i].mode = s->motor_state[i].mode;
    c->motor_cmd[i].q = s->motor_state[i].q;
    c->motor_cmd[i].dq = s->motor_state[i].dq;
    c->motor_cmd[i].tau = s->motor_state[i].tau_est;
    c->motor_cmd[i].kp = s->imu_state.quaternion[i % 4];
    c->motor_cmd[i].kd = (float)s->foot_force[i % 4];
    c->motor_cmd[i].reserve[0] = s->motor_state[i].lost;
  }
  c->bms_cmd.off = s->bms_state.soc;
  memcpy(c->wireless_remote, s->wireless_remote, sizeof(c->wireless_remote));
  c->led[0] = s->temperature_ntc1;
  c->led[1] = s->temperature_ntc2;
  c->led[2] = s->imu_state.temperature;
  c->led[3] = s->bit_flag;
  for (int j = 0; j < 2; j++)
    c->fan[j] = (uint8_t)(s->fan_frequency[j] & 0xFF);
  c->gpio = s->bms_state.status;
  c->reserve = s->tick;
  c->crc = 0;
}

/* ---- DDS plumbing. */

struct peer {
  dds_entity_t participant, state_topic, cmd_topic;
  dds_entity_t state_reader, state_writer, cmd_reader, cmd_writer;
  dds_entity_t waitset;
};

static dds_entity_t make_writer(dds_entity_t participant, dds_entity_t topic)
{
  dds_qos_t *qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
  dds_entity_t writer = dds_create_writer(participant, topic, qos, NULL);
  dds_delete_qos(qos);
  return writer;
}

static dds_entity_t make_reader(dds_entity_t participant, dds_entity_t topic)
{
  dds_qos_t *qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
  dds_entity_t reader = dds_create_reader(participant, topic, qos, NULL);
  dds_delete_qos(qos);
  return reader;
}

static int open_peer(struct peer *p, dds_domainid_t domain, int publish_state)
{
  memset(p, 0, sizeof(*p));
  p->participant = dds_create_participant(domain, NULL, NULL);
  if (p->participant < 0) {
    fprintf(stderr, "go2_peer: dds_create_participant: %s\n", dds_strretcode(-p->participant));
    return -1;
  }
  p->state_topic = dds_create_topic(p->participant, &unitree_go_msg_dds__LowState__desc,
                                    "rt/lowstate", NULL, NULL);
  p->cmd_topic = dds_create_topic(p->participant, &unitree_go_msg_dds__LowCmd__desc,
                                  "rt/lowcmd", NULL, NULL);
  if (p->state_topic < 0 || p->cmd_topic < 0) {
    fprintf(stderr, "go2_peer: dds_create_topic failed\n");
    return -1;
  }
  dds_entity_t reader;
  if (publish_state) {
    p->state_writer = make_writer(p->participant, p->state_topic);
    reader = p->cmd_reader = make_reader(p->participant, p->cmd_topic);
    if (p->state_writer < 0)
      reader = -1;
  } else {
    reader = p->state_reader = make_reader(p->participant, p->state_topic);
    p->cmd_writer = make_writer(p->participant, p->cmd_topic);
    if (p->cmd_writer < 0)
      reader = -1;
  }
  if (reader < 0) {
    fprintf(stderr, "go2_peer: creating the reader or writer failed\n");
    return -1;
  }
  p->waitset = dds_create_waitset(p->participant);
  dds_entity_t cond = dds_create_readcondition(reader, DDS_ANY_STATE);
  if (p->waitset < 0 || cond < 0 || dds_waitset_attach(p->waitset, cond, 0) < 0) {
    fprintf(stderr, "go2_peer: waitset setup failed\n");
    return -1;
  }
  return 0;
}

/* Wait for data on the peer's reader until `until` (absolute dds_time_t). */
static void wait_data(const struct peer *p, dds_time_t until)
{
  dds_duration_t left = until - dds_time();
  if (left > 0)
    (void)dds_waitset_wait(p->waitset, NULL, 0, left);
}

/* Take one sample into caller memory zeroed first, so the whole image, padding included,
 * compares with memcmp. Returns 1 for a valid sample, 2 for a sample without data (a writer
 * gone), 0 for none, <0 on error. */
static int take_one(dds_entity_t reader, void *sample, size_t size)
{
  memset(sample, 0, size);
  void *buf[1] = {sample};
  dds_sample_info_t info;
  dds_return_t n = dds_take(reader, buf, &info, 1, 1);
  if (n < 0)
    return (int)n;
  return n == 1 && info.valid_data ? 1 : (n == 1 ? 2 : 0);
}

struct options {
  int publish_state;
  dds_domainid_t domain;
  uint32_t count;
  double timeout_s;
  int period_ms;
};

static int summary(const struct options *o, int sent, int received, int resent, int matched,
                   int mismatches, int crc_valid, int complete)
{
  int errors = atomic_load(&logged_errors);
  int invalid = atomic_load(&logged_invalid_type);
  const char *result = (errors > 0 || invalid > 0) ? "error"
                       : mismatches > 0             ? "mismatch"
                       : complete                   ? "ok"
                                                    : "incomplete";
  printf("go2_peer summary: mode=%s cyclonedds=%s domain=%u count=%u sent=%d received=%d "
         "resent=%d matched=%d mismatches=%d crc_valid=%d errors=%d invalid_type_object=%d "
         "result=%s\n",
         o->publish_state ? "publish-state" : "echo-state", DDS_VERSION, (unsigned)o->domain,
         (unsigned)o->count, sent, received, resent, matched, mismatches, crc_valid, errors,
         invalid, result);
  fflush(stdout);
  if (strcmp(result, "error") == 0 || strcmp(result, "mismatch") == 0)
    return 3;
  return complete ? 0 : 1;
}

static int run_echo_state(const struct options *o, struct peer *p)
{
  const dds_time_t deadline = dds_time() + (dds_duration_t)(o->timeout_s * 1e9);
  const dds_duration_t linger = DDS_MSECS(300);
  dds_time_t until = deadline;
  int sent = 0, received = 0, matched = 0, mismatches = 0, crc_valid = 0, complete = 0;
  LowState state, expected;
  LowCmd cmd;
  while (dds_time() < until) {
    wait_data(p, until);
    int rc;
    while ((rc = take_one(p->state_reader, &state, sizeof(state))) > 0) {
      if (rc != 1)
        continue;
      received++;
      known_state(state.tick, &expected);
      expected.crc = state.crc; /* the sender may or may not have set it */
      int same = memcmp(&state, &expected, sizeof(state)) == 0;
      int crc_ok = state.crc == low_state_crc(&state);
      matched += same;
      mismatches += !same;
      crc_valid += crc_ok;
      printf("got LowState_ tick=%u imu.quaternion[0]=%.9g motor_state[0].q=%.9g crc=%08X "
             "crc_valid=%d matches_known=%d\n",
             (unsigned)state.tick, (double)state.imu_state.quaternion[0],
             (double)state.motor_state[0].q, (unsigned)state.crc, crc_ok, same);
      echo(&state, &cmd);
      dds_return_t wr = dds_write(p->cmd_writer, &cmd);
      if (wr < 0)
        fprintf(stderr, "go2_peer: dds_write(rt/lowcmd): %s\n", dds_strretcode(-wr));
      else
        sent++;
      if (state.tick == o->count && !complete) {
        complete = 1;
        until = dds_time() + linger < deadline ? dds_time() + linger : deadline;
      }
    }
    if (rc < 0) {
      fprintf(stderr, "go2_peer: dds_take(rt/lowstate): %s\n", dds_strretcode(-rc));
      break;
    }
  }
  return summary(o, sent, received, 0, matched, mismatches, crc_valid, complete);
}

static int wait_matched(const struct peer *p, dds_time_t deadline)
{
  dds_publication_matched_status_t pub;
  dds_subscription_matched_status_t sub;
  while (dds_time() < deadline) {
    if (dds_get_publication_matched_status(p->state_writer, &pub) == 0 &&
        dds_get_subscription_matched_status(p->cmd_reader, &sub) == 0 &&
        pub.current_count > 0 && sub.current_count > 0)
      return 1;
    dds_sleepfor(DDS_MSECS(5));
  }
  return 0;
}

static int run_publish_state(const struct options *o, struct peer *p)
{
  const dds_time_t deadline = dds_time() + (dds_duration_t)(o->timeout_s * 1e9);
  int sent = 0, received = 0, resent = 0, matched = 0, crc_valid = 0;
  uint32_t k = 1;
  LowState state;
  LowCmd cmd, expected;
  if (!wait_matched(p, deadline)) {
    fprintf(stderr, "go2_peer: no reader of rt/lowstate and writer of rt/lowcmd matched\n");
    return summary(o, 0, 0, 0, 0, 0, 0, 0);
  }
  while (k <= o->count && dds_time() < deadline) {
    known_state(k, &state);
    state.crc = low_state_crc(&state);
    dds_return_t wr = dds_write(p->state_writer, &state);
    if (wr < 0)
      fprintf(stderr, "go2_peer: dds_write(rt/lowstate): %s\n", dds_strretcode(-wr));
    else
      sent++;
    dds_time_t until = dds_time() + DDS_MSECS(o->period_ms);
    if (until > deadline)
      until = deadline;
    int answered = 0;
    while (!answered && dds_time() < until) {
      wait_data(p, until);
      int rc;
      while ((rc = take_one(p->cmd_reader, &cmd, sizeof(cmd))) > 0) {
        if (rc != 1)
          continue;
        received++;
        LowState named;
        known_state(cmd.reserve, &named);
        echo(&named, &expected);
        expected.crc = cmd.crc; /* the sender may or may not have set it */
        int same = memcmp(&cmd, &expected, sizeof(cmd)) == 0;
        int crc_ok = cmd.crc == low_cmd_crc(&cmd);
        crc_valid += crc_ok;
        printf("got LowCmd_ reserve=%u head=%02X%02X level_flag=%02X motor_cmd[0].q=%.9g "
               "motor_cmd[0].kp=%.9g crc=%08X crc_valid=%d matches_echo=%d\n",
               (unsigned)cmd.reserve, cmd.head[0], cmd.head[1], cmd.level_flag,
               (double)cmd.motor_cmd[0].q, (double)cmd.motor_cmd[0].kp, (unsigned)cmd.crc,
               crc_ok, same);
        if (!same) {
          /* Definite: stop now rather than resend until the timeout. */
          return summary(o, sent, received, resent, matched, 1, crc_valid, 0);
        }
        if (cmd.reserve == k) {
          matched++;
          answered = 1;
        }
      }
      if (rc < 0) {
        fprintf(stderr, "go2_peer: dds_take(rt/lowcmd): %s\n", dds_strretcode(-rc));
        return summary(o, sent, received, resent, matched, 0, crc_valid, 0);
      }
    }
    if (answered)
      k++;
    else
      resent++;
  }
  return summary(o, sent, received, resent, matched, 0, crc_valid, matched == (int)o->count);
}

static int usage(const char *argv0)
{
  fprintf(stderr,
          "usage: %s echo-state|publish-state [--domain ID] [--count N] [--timeout S] "
          "[--period-ms MS]\n"
          "       %s crc-self-test\n",
          argv0, argv0);
  return 2;
}

int main(int argc, char **argv)
{
  struct options o = {0, 1, 10, 10.0, 50};
  if (argc < 2)
    return usage(argv[0]);
  if (strcmp(argv[1], "crc-self-test") == 0) {
    int ok = crc_self_test();
    printf("go2_peer crc-self-test: %s\n", ok ? "ok" : "FAILED");
    return ok ? 0 : 3;
  }
  if (strcmp(argv[1], "publish-state") == 0)
    o.publish_state = 1;
  else if (strcmp(argv[1], "echo-state") != 0)
    return usage(argv[0]);
  for (int i = 2; i + 1 < argc; i += 2) {
    if (strcmp(argv[i], "--domain") == 0)
      o.domain = (dds_domainid_t)strtoul(argv[i + 1], NULL, 10);
    else if (strcmp(argv[i], "--count") == 0)
      o.count = (uint32_t)strtoul(argv[i + 1], NULL, 10);
    else if (strcmp(argv[i], "--timeout") == 0)
      o.timeout_s = strtod(argv[i + 1], NULL);
    else if (strcmp(argv[i], "--period-ms") == 0)
      o.period_ms = atoi(argv[i + 1]);
    else
      return usage(argv[0]);
  }
  if ((argc - 2) % 2 != 0 || o.count == 0 || o.timeout_s <= 0 || o.period_ms <= 0)
    return usage(argv[0]);
  if (!crc_self_test()) {
    fprintf(stderr, "go2_peer: the CRC does not reproduce the SDK's test vectors\n");
    return 2;
  }
  dds_set_log_sink(log_sink, NULL);

  struct peer p;
  if (open_peer(&p, o.domain, o.publish_state) != 0)
    return 2;
  printf("go2_peer: mode=%s cyclonedds=%s domain=%u count=%u ready\n",
         o.publish_state ? "publish-state" : "echo-state", DDS_VERSION, (unsigned)o.domain,
         (unsigned)o.count);
  fflush(stdout);
  int status = o.publish_state ? run_publish_state(&o, &p) : run_echo_state(&o, &p);
  dds_delete(p.participant);
  return status;
}
