#include "api/farm_bus.h"

#include <mutex>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "api/dds.h"
#include "api/farm_samples.h"

namespace enavi::api {
namespace {

using namespace std::chrono_literals;

// Topic names carry the protocol version: binaries of different versions never match.
constexpr const char* kStatusTopic = "enavi_v2_worker_status";
constexpr const char* kAssignmentTopic = "enavi_v2_assignment";
constexpr const char* kResultTopic = "enavi_v2_result";
constexpr const char* kAckTopic = "enavi_v2_result_ack";
constexpr const char* kEventTopic = "enavi_v2_job_event";
constexpr const char* kPolicyTopic = "enavi_v2_policy";
constexpr const char* kCollectTopic = "enavi_v2_collect_assignment";
constexpr const char* kRolloutTopic = "enavi_v2_rollout_result";

// QoS per topic; the reasons are in api/README.md ("Topics and QoS").
dds::Qos StatusQos(std::chrono::milliseconds lease) {
  return dds::Qos().Reliable().TransientLocal().KeepLast(1).Liveliness(lease);
}
dds::Qos AssignmentQos() { return dds::Qos().Reliable().TransientLocal().KeepLast(1); }
dds::Qos ResultQos() { return dds::Qos().Reliable(30s).TransientLocal().KeepLast(1); }
dds::Qos AckQos() { return dds::Qos().Reliable().Volatile().KeepAll(); }
dds::Qos EventQos() { return dds::Qos().Reliable().Volatile().KeepLast(64); }
// Policies: every worker, also one that joins late, needs each running job's policy.
dds::Qos PolicyQos() { return dds::Qos().Reliable(30s).TransientLocal().KeepLast(1); }

// The C structs idlc generates hold `char*`; Cyclone only reads them on write.
char* Str(const std::string& s) { return const_cast<char*>(s.c_str()); }
std::string Str(const char* s) { return s == nullptr ? std::string() : std::string(s); }

template <typename Seq, typename T>
void PointSeq(Seq& seq, const std::vector<T>& v) {
  seq._maximum = seq._length = static_cast<uint32_t>(v.size());
  seq._buffer = const_cast<T*>(v.data());
  seq._release = false;
}

std::vector<double> CopyDoubles(const dds_sequence_double& seq) {
  return std::vector<double>(seq._buffer, seq._buffer + seq._length);
}

std::vector<Vec3> Unflatten(const dds_sequence_double& seq, const char* column) {
  if (seq._length % 3 != 0) {
    throw std::invalid_argument(std::string("result series: ") + column +
                                " length is not a multiple of 3");
  }
  std::vector<Vec3> out(seq._length / 3);
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = {seq._buffer[3 * i], seq._buffer[3 * i + 1], seq._buffer[3 * i + 2]};
  }
  return out;
}

std::vector<double> Flatten(const std::vector<Vec3>& v) {
  std::vector<double> out;
  out.reserve(3 * v.size());
  for (const Vec3& p : v) out.insert(out.end(), p.begin(), p.end());
  return out;
}

// ---- WorkerStatus ----

struct StatusSample {
  enavi_farm_WorkerStatus c{};
  std::vector<char*> boards, clocks, features;
  std::vector<enavi_farm_EpisodeRef> running;
};

void ToSample(const WorkerStatus& s, StatusSample* out) {
  for (const auto& b : s.boards) out->boards.push_back(Str(b));
  for (const auto& c : s.clocks) out->clocks.push_back(Str(c));
  for (const auto& f : s.features) out->features.push_back(Str(f));
  for (const auto& r : s.running) out->running.push_back({Str(r.episode_id), r.attempt});
  enavi_farm_WorkerStatus& c = out->c;
  c.worker_id = Str(s.worker_id);
  c.protocol = s.protocol;
  c.host = Str(s.host);
  c.pid = s.pid;
  c.slots = s.slots;
  c.free_slots = s.free_slots;
  PointSeq(c.boards, out->boards);
  PointSeq(c.clocks, out->clocks);
  c.calibration_id = Str(s.calibration_id);
  c.draining = s.draining;
  c.seq = s.seq;
  PointSeq(c.running, out->running);
  c.unacked_results = s.unacked_results;
  c.version = Str(s.version);
  PointSeq(c.features, out->features);
}

WorkerStatus FromSample(const enavi_farm_WorkerStatus& c) {
  WorkerStatus s;
  s.worker_id = Str(c.worker_id);
  s.protocol = c.protocol;
  s.host = Str(c.host);
  s.pid = c.pid;
  s.slots = c.slots;
  s.free_slots = c.free_slots;
  for (uint32_t i = 0; i < c.boards._length; ++i) s.boards.push_back(Str(c.boards._buffer[i]));
  for (uint32_t i = 0; i < c.clocks._length; ++i) s.clocks.push_back(Str(c.clocks._buffer[i]));
  for (uint32_t i = 0; i < c.features._length; ++i) s.features.push_back(Str(c.features._buffer[i]));
  s.calibration_id = Str(c.calibration_id);
  s.draining = c.draining;
  s.seq = c.seq;
  for (uint32_t i = 0; i < c.running._length; ++i) {
    s.running.push_back({Str(c.running._buffer[i].episode_id), c.running._buffer[i].attempt});
  }
  s.unacked_results = c.unacked_results;
  s.version = Str(c.version);
  return s;
}

// ---- Assignment ----

// The plain and the collection assignment topics carry the same fields; a collection job's adds
// the policy it must fly. A sample owns the spec's JSON its spec_json field points into.
template <class C>
struct SpecSample {
  C c{};
  std::string spec_json;
};
using AssignmentSample = SpecSample<enavi_farm_Assignment>;
using CollectSample = SpecSample<enavi_farm_CollectAssignment>;

template <class C>
void ToCommonFields(const Assignment& a, SpecSample<C>* out) {
  out->spec_json = nlohmann::json(a.spec).dump();
  C& c = out->c;
  c.worker_id = Str(a.worker_id);
  c.episode_id = Str(a.episode_id);
  c.attempt = a.attempt;
  c.job_id = Str(a.job_id);
  c.lease_deadline_ms = a.lease_deadline_ms;
  c.lease_ms = a.lease_ms;
  c.spec_json = Str(out->spec_json);
}

template <class C>
Assignment FromCommonFields(const C& c) {
  Assignment a;
  a.worker_id = Str(c.worker_id);
  a.episode_id = Str(c.episode_id);
  a.attempt = c.attempt;
  a.job_id = Str(c.job_id);
  a.lease_deadline_ms = c.lease_deadline_ms;
  a.lease_ms = c.lease_ms;
  a.spec = nlohmann::json::parse(Str(c.spec_json)).template get<EpisodeSpec>();
  return a;
}

void ToSample(const Assignment& a, AssignmentSample* out) { ToCommonFields(a, out); }

Assignment FromSample(const enavi_farm_Assignment& c) { return FromCommonFields(c); }

void ToSample(const Assignment& a, CollectSample* out) {
  ToCommonFields(a, out);
  out->c.policy_hash = Str(a.policy_hash);
}

Assignment FromSample(const enavi_farm_CollectAssignment& c) {
  Assignment a = FromCommonFields(c);
  a.policy_hash = Str(c.policy_hash);
  if (a.policy_hash.empty()) throw std::invalid_argument("collect assignment: empty policy_hash");
  return a;
}

// ---- Result ----

enavi_farm_ResultStatus ToC(ResultStatus s) {
  switch (s) {
    case ResultStatus::kOk: return enavi_farm_RESULT_OK;
    case ResultStatus::kError: return enavi_farm_RESULT_ERROR;
    case ResultStatus::kRejected: return enavi_farm_RESULT_REJECTED;
  }
  throw std::logic_error("unknown ResultStatus");
}

ResultStatus FromC(enavi_farm_ResultStatus s) {
  switch (s) {
    case enavi_farm_RESULT_OK: return ResultStatus::kOk;
    case enavi_farm_RESULT_ERROR: return ResultStatus::kError;
    case enavi_farm_RESULT_REJECTED: return ResultStatus::kRejected;
  }
  throw std::invalid_argument("result: unknown status " + std::to_string(static_cast<int>(s)));
}

struct ResultSample {
  enavi_farm_EpisodeResult c{};
  std::string result_json;
  std::vector<enavi_farm_EpisodeEvent> events;
  std::vector<double> position, velocity;
};

void ToSample(const ResultMessage& m, ResultSample* out) {
  enavi_farm_EpisodeResult& c = out->c;
  c.episode_id = Str(m.episode_id);
  c.attempt = m.attempt;
  c.worker_id = Str(m.worker_id);
  c.job_id = Str(m.job_id);
  c.status = ToC(m.status);
  c.error = Str(m.error);
  c.wall_time_s = m.wall_time_s;
  if (m.status == ResultStatus::kOk) {
    nlohmann::json summary = ResultSummaryJson(m.result);
    summary["spec"] = m.result.spec;
    out->result_json = summary.dump();
    for (const auto& e : m.result.events) out->events.push_back({e.t, Str(e.kind), Str(e.detail)});
    const TimeSeries& s = m.result.series;
    out->position = Flatten(s.position);
    out->velocity = Flatten(s.velocity);
    PointSeq(c.series.t, s.t);
    PointSeq(c.series.position_xyz, out->position);
    PointSeq(c.series.velocity_xyz, out->velocity);
    PointSeq(c.series.eci, s.eci);
    PointSeq(c.series.f_per, s.f_per);
    PointSeq(c.series.f_col, s.f_col);
    PointSeq(c.series.f_dif, s.f_dif);
    PointSeq(c.series.res, s.res);
    PointSeq(c.series.utilisation, s.utilisation);
    PointSeq(c.series.wind_speed, s.wind_speed);
    PointSeq(c.series.odometry_error, s.odometry_error);
  }
  c.result_json = Str(out->result_json);
  PointSeq(c.events, out->events);
}

ResultMessage FromSample(const enavi_farm_EpisodeResult& c) {
  ResultMessage m;
  m.episode_id = Str(c.episode_id);
  m.attempt = c.attempt;
  m.worker_id = Str(c.worker_id);
  m.job_id = Str(c.job_id);
  m.status = FromC(c.status);
  m.error = Str(c.error);
  m.wall_time_s = c.wall_time_s;
  if (m.status != ResultStatus::kOk) return m;
  m.result = nlohmann::json::parse(Str(c.result_json)).get<EpisodeResult>();
  for (uint32_t i = 0; i < c.events._length; ++i) {
    const auto& e = c.events._buffer[i];
    m.result.events.push_back({e.t, Str(e.kind), Str(e.detail)});
  }
  TimeSeries& s = m.result.series;
  s.t = CopyDoubles(c.series.t);
  s.position = Unflatten(c.series.position_xyz, "position_xyz");
  s.velocity = Unflatten(c.series.velocity_xyz, "velocity_xyz");
  s.eci = CopyDoubles(c.series.eci);
  s.f_per = CopyDoubles(c.series.f_per);
  s.f_col = CopyDoubles(c.series.f_col);
  s.f_dif = CopyDoubles(c.series.f_dif);
  s.res = CopyDoubles(c.series.res);
  s.utilisation = CopyDoubles(c.series.utilisation);
  s.wind_speed = CopyDoubles(c.series.wind_speed);
  s.odometry_error = CopyDoubles(c.series.odometry_error);
  return m;
}

// A collection result: the plain result sample nested, plus policy hash and rollout bytes.
struct RolloutSample {
  enavi_farm_RolloutResult c{};
  ResultSample result;
};

void ToSample(const ResultMessage& m, RolloutSample* out) {
  ToSample(m, &out->result);
  out->c.episode_id = Str(m.episode_id);
  out->c.attempt = m.attempt;
  out->c.result = out->result.c;
  out->c.policy_hash = Str(m.policy_hash);
  out->c.rollout._maximum = out->c.rollout._length = static_cast<uint32_t>(m.rollout.size());
  out->c.rollout._buffer = reinterpret_cast<uint8_t*>(const_cast<char*>(m.rollout.data()));
  out->c.rollout._release = false;
}

ResultMessage FromSample(const enavi_farm_RolloutResult& c) {
  ResultMessage m = FromSample(c.result);
  m.policy_hash = Str(c.policy_hash);
  if (c.rollout._length > kMaxRolloutBytes) {
    throw std::invalid_argument("rollout result: " + std::to_string(c.rollout._length) +
                                " bytes, above the limit");
  }
  m.rollout.assign(reinterpret_cast<const char*>(c.rollout._buffer), c.rollout._length);
  return m;
}

// ---- Ack ----

enavi_farm_AckStatus ToC(AckStatus s) {
  switch (s) {
    case AckStatus::kStored: return enavi_farm_ACK_STORED;
    case AckStatus::kDuplicate: return enavi_farm_ACK_DUPLICATE;
    case AckStatus::kDiscarded: return enavi_farm_ACK_DISCARDED;
    case AckStatus::kUnknown: return enavi_farm_ACK_UNKNOWN;
    case AckStatus::kRecorded: return enavi_farm_ACK_RECORDED;
  }
  throw std::logic_error("unknown AckStatus");
}

AckStatus FromC(enavi_farm_AckStatus s) {
  switch (s) {
    case enavi_farm_ACK_STORED: return AckStatus::kStored;
    case enavi_farm_ACK_DUPLICATE: return AckStatus::kDuplicate;
    case enavi_farm_ACK_DISCARDED: return AckStatus::kDiscarded;
    case enavi_farm_ACK_UNKNOWN: return AckStatus::kUnknown;
    case enavi_farm_ACK_RECORDED: return AckStatus::kRecorded;
  }
  throw std::invalid_argument("ack: unknown status " + std::to_string(static_cast<int>(s)));
}

enavi_farm_ResultAck ToSample(const ResultAck& a) {
  return {Str(a.worker_id), Str(a.episode_id), a.attempt, ToC(a.status), Str(a.detail)};
}

ResultAck FromSample(const enavi_farm_ResultAck& c) {
  return {Str(c.worker_id), Str(c.episode_id), c.attempt, FromC(c.status), Str(c.detail)};
}

enavi_farm_JobEvent ToSample(const JobEvent& e) {
  return {Str(e.job_id), Str(e.kind), Str(e.episode_id), e.done, e.failed, e.total,
          Str(e.message), e.time_ms};
}

JobEvent FromSample(const enavi_farm_JobEvent& c) {
  return {Str(c.job_id), Str(c.kind), Str(c.episode_id), c.done, c.failed, c.total,
          Str(c.message), c.time_ms};
}

}  // namespace

// Entities both sides share. Members are declared in creation order: the participant first,
// so it is deleted last (and deletes anything left). Outside the anonymous namespace because
// ServerBus::Impl and WorkerBus::Impl, which have linkage, hold one.
namespace bus_detail {
struct Common {
  Common(const BusOptions& options)
      : participant(dds::Domain::Acquire(options.domain_id, options.config_xml)),
        status_topic(participant, &enavi_farm_WorkerStatus_desc, kStatusTopic,
                     StatusQos(options.liveliness_lease)),
        assignment_topic(participant, &enavi_farm_Assignment_desc, kAssignmentTopic,
                         AssignmentQos()),
        result_topic(participant, &enavi_farm_EpisodeResult_desc, kResultTopic, ResultQos()),
        ack_topic(participant, &enavi_farm_ResultAck_desc, kAckTopic, AckQos()),
        event_topic(participant, &enavi_farm_JobEvent_desc, kEventTopic, EventQos()),
        policy_topic(participant, &enavi_farm_PolicyBlob_desc, kPolicyTopic, PolicyQos()),
        collect_topic(participant, &enavi_farm_CollectAssignment_desc, kCollectTopic,
                      AssignmentQos()),
        rollout_topic(participant, &enavi_farm_RolloutResult_desc, kRolloutTopic, ResultQos()),
        publisher(participant, dds::Qos().Partition(options.partition)),
        subscriber(participant, dds::Qos().Partition(options.partition)),
        guard(participant),
        waitset(participant) {
    waitset.Attach(guard.get(), 0);
  }
  dds::Participant participant;
  dds::Topic status_topic, assignment_topic, result_topic, ack_topic, event_topic;
  dds::Topic policy_topic, collect_topic, rollout_topic;
  dds::Publisher publisher;
  dds::Subscriber subscriber;
  dds::GuardCondition guard;
  dds::WaitSet waitset;
};
}  // namespace bus_detail

namespace {

// Spool files are JSON: rollout bytes go in as hex (spool files are local and short-lived).
std::string HexEncode(const std::string& bytes) {
  static const char* kDigits = "0123456789abcdef";
  std::string out(2 * bytes.size(), '0');
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    const auto b = static_cast<unsigned char>(bytes[i]);
    out[2 * i] = kDigits[b >> 4];
    out[2 * i + 1] = kDigits[b & 15];
  }
  return out;
}

std::string HexDecode(const std::string& hex) {
  auto nibble = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    throw std::invalid_argument("rollout_hex: not a hex digit");
  };
  if (hex.size() % 2 != 0) throw std::invalid_argument("rollout_hex: odd length");
  std::string out(hex.size() / 2, '\0');
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = static_cast<char>(nibble(hex[2 * i]) << 4 | nibble(hex[2 * i + 1]));
  }
  return out;
}

}  // namespace

ResultMessage ResultFromSample(const enavi_farm_EpisodeResult& c) { return FromSample(c); }
ResultMessage ResultFromSample(const enavi_farm_RolloutResult& c) { return FromSample(c); }

namespace {

// Converts one sample, recording a conversion failure instead of throwing it out of Take().
template <typename F>
void Convert(std::vector<std::string>* bad, const char* topic, F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    bad->push_back(std::string(topic) + ": " + e.what());
  }
}

}  // namespace

const char* ToString(ResultStatus s) {
  switch (s) {
    case ResultStatus::kOk: return "ok";
    case ResultStatus::kError: return "error";
    case ResultStatus::kRejected: return "rejected";
  }
  return "?";
}

const char* ToString(AckStatus s) {
  switch (s) {
    case AckStatus::kStored: return "stored";
    case AckStatus::kDuplicate: return "duplicate";
    case AckStatus::kDiscarded: return "discarded";
    case AckStatus::kUnknown: return "unknown";
    case AckStatus::kRecorded: return "recorded";
  }
  return "?";
}

nlohmann::json ToJson(const ResultMessage& m) {
  nlohmann::json j = {{"episode_id", m.episode_id}, {"attempt", m.attempt},
                      {"worker_id", m.worker_id},   {"job_id", m.job_id},
                      {"status", ToString(m.status)}, {"error", m.error},
                      {"wall_time_s", m.wall_time_s}};
  if (m.status == ResultStatus::kOk) j["result"] = m.result;
  if (!m.policy_hash.empty()) j["policy_hash"] = m.policy_hash;
  if (!m.rollout.empty()) j["rollout_hex"] = HexEncode(m.rollout);
  return j;
}

ResultMessage ResultMessageFromJson(const nlohmann::json& j) {
  ResultMessage m;
  m.episode_id = j.at("episode_id").get<std::string>();
  m.attempt = j.at("attempt").get<int>();
  m.worker_id = j.at("worker_id").get<std::string>();
  m.job_id = j.at("job_id").get<std::string>();
  const std::string status = j.at("status").get<std::string>();
  if (status == "ok") {
    m.status = ResultStatus::kOk;
  } else if (status == "error") {
    m.status = ResultStatus::kError;
  } else if (status == "rejected") {
    m.status = ResultStatus::kRejected;
  } else {
    throw std::invalid_argument("status: unknown value '" + status + "'");
  }
  m.error = j.value("error", std::string());
  m.wall_time_s = j.value("wall_time_s", 0.0);
  if (m.status == ResultStatus::kOk) j.at("result").get_to(m.result);
  m.policy_hash = j.value("policy_hash", std::string());
  if (j.contains("rollout_hex")) m.rollout = HexDecode(j.at("rollout_hex").get<std::string>());
  return m;
}

// ---------------------------------------------------------------- ServerBus

struct ServerBus::Impl {
  explicit Impl(const BusOptions& options)
      : common(options),
        status_reader(common.subscriber, common.status_topic, StatusQos(options.liveliness_lease)),
        result_reader(common.subscriber, common.result_topic, dds::Qos(ResultQos()).KeepAll()),
        assignment_writer(common.publisher, common.assignment_topic,
                          dds::Qos(AssignmentQos()).NoAutoDispose()),
        ack_writer(common.publisher, common.ack_topic, AckQos()),
        event_writer(common.publisher, common.event_topic, EventQos()),
        rollout_reader(common.subscriber, common.rollout_topic, dds::Qos(ResultQos()).KeepAll()),
        collect_writer(common.publisher, common.collect_topic,
                       dds::Qos(AssignmentQos()).NoAutoDispose()),
        policy_writer(common.publisher, common.policy_topic, dds::Qos(PolicyQos()).NoAutoDispose()),
        status_cond(status_reader.get()),
        result_cond(result_reader.get()),
        rollout_cond(rollout_reader.get()) {
    common.waitset.Attach(status_cond.get(), 1);
    common.waitset.Attach(result_cond.get(), 2);
    common.waitset.Attach(rollout_cond.get(), 3);
  }
  bus_detail::Common common;
  dds::Reader<enavi_farm_WorkerStatus> status_reader;
  dds::Reader<enavi_farm_EpisodeResult> result_reader;
  dds::Writer<enavi_farm_Assignment> assignment_writer;
  dds::Writer<enavi_farm_ResultAck> ack_writer;
  dds::Writer<enavi_farm_JobEvent> event_writer;
  dds::Reader<enavi_farm_RolloutResult> rollout_reader;
  dds::Writer<enavi_farm_CollectAssignment> collect_writer;
  dds::Writer<enavi_farm_PolicyBlob> policy_writer;
  dds::ReadCondition status_cond, result_cond, rollout_cond;
};

ServerBus::ServerBus(const BusOptions& options) : impl_(std::make_unique<Impl>(options)) {}
ServerBus::~ServerBus() = default;

ServerBus::Inbox ServerBus::Wait(std::chrono::milliseconds timeout, std::size_t max_results) {
  impl_->common.waitset.Wait(timeout);
  impl_->common.guard.TakeTriggered();
  Inbox inbox;
  impl_->status_reader.Take(SIZE_MAX, [&](const enavi_farm_WorkerStatus& c,
                                          const dds::SampleInfo& info) {
    // A status that arrives together with its instance's end (dispose, no writers) is the
    // worker's last word: report it gone, not alive.
    if (!info.alive) {
      (info.disposed ? inbox.workers_left : inbox.workers_gone).push_back(Str(c.worker_id));
    } else if (info.valid_data) {
      Convert(&inbox.bad_samples, kStatusTopic,
              [&] { inbox.statuses.push_back(FromSample(c)); });
    }
  });
  impl_->result_reader.Take(max_results, [&](const enavi_farm_EpisodeResult& c,
                                             const dds::SampleInfo& info) {
    if (!info.valid_data) return;  // instance unregistered by the worker after our ack
    Convert(&inbox.bad_samples, kResultTopic, [&] { inbox.results.push_back(FromSample(c)); });
  });
  const std::size_t taken = inbox.results.size();
  impl_->rollout_reader.Take(max_results > taken ? max_results - taken : 1,
                             [&](const enavi_farm_RolloutResult& c, const dds::SampleInfo& info) {
    if (!info.valid_data) return;
    Convert(&inbox.bad_samples, kRolloutTopic, [&] { inbox.results.push_back(FromSample(c)); });
  });
  return inbox;
}

void ServerBus::Wake() { impl_->common.guard.Trigger(); }

void ServerBus::Publish(const Assignment& assignment) {
  if (!assignment.policy_hash.empty()) {
    CollectSample sample;
    ToSample(assignment, &sample);
    return impl_->collect_writer.Write(sample.c);
  }
  AssignmentSample sample;
  ToSample(assignment, &sample);
  impl_->assignment_writer.Write(sample.c);
}

void ServerBus::Retire(const Assignment& assignment) {
  // By key: the instance is on one of the two assignment topics.
  AssignmentSample plain;
  ToSample(assignment, &plain);
  CollectSample collect;
  ToSample(assignment, &collect);
  try {
    impl_->assignment_writer.Unregister(plain.c);
  } catch (const dds::DdsError&) {
    impl_->collect_writer.Unregister(collect.c);
  }
}

void ServerBus::Publish(const PolicyBlob& policy) {
  const enavi_farm_PolicyBlob sample{Str(policy.hash), Str(policy.json)};
  impl_->policy_writer.Write(sample);
}

void ServerBus::Retire(const PolicyBlob& policy) {
  const enavi_farm_PolicyBlob sample{Str(policy.hash), Str(std::string())};
  impl_->policy_writer.Unregister(sample);
}

void ServerBus::Publish(const ResultAck& ack) {
  const enavi_farm_ResultAck sample = ToSample(ack);
  impl_->ack_writer.Write(sample);
}

void ServerBus::Publish(const JobEvent& event) {
  const enavi_farm_JobEvent sample = ToSample(event);
  impl_->event_writer.Write(sample);
}

std::size_t ServerBus::MatchedWorkers() const { return impl_->status_reader.MatchedWriters(); }

// ---------------------------------------------------------------- WorkerBus

struct WorkerBus::Impl {
  Impl(const BusOptions& options, std::string id)
      : worker_id(std::move(id)),
        common(options),
        assignment_reader(common.subscriber, common.assignment_topic, AssignmentQos()),
        ack_reader(common.subscriber, common.ack_topic, AckQos()),
        event_reader(common.subscriber, common.event_topic, EventQos()),
        // No auto-dispose: only an explicit DisposeStatus() is a graceful leave; a writer that
        // merely disappears is a worker gone.
        status_writer(common.publisher, common.status_topic,
                      StatusQos(options.liveliness_lease).NoAutoDispose()),
        result_writer(common.publisher, common.result_topic, dds::Qos(ResultQos()).NoAutoDispose()),
        collect_reader(common.subscriber, common.collect_topic, AssignmentQos()),
        policy_reader(common.subscriber, common.policy_topic, PolicyQos()),
        rollout_writer(common.publisher, common.rollout_topic,
                       dds::Qos(ResultQos()).NoAutoDispose()),
        assignment_cond(assignment_reader.get()),
        ack_cond(ack_reader.get()),
        event_cond(event_reader.get()),
        collect_cond(collect_reader.get()),
        policy_cond(policy_reader.get()) {
    common.waitset.Attach(assignment_cond.get(), 1);
    common.waitset.Attach(ack_cond.get(), 2);
    common.waitset.Attach(event_cond.get(), 3);
    common.waitset.Attach(collect_cond.get(), 4);
    common.waitset.Attach(policy_cond.get(), 5);
  }
  std::string worker_id;
  bus_detail::Common common;
  dds::Reader<enavi_farm_Assignment> assignment_reader;
  dds::Reader<enavi_farm_ResultAck> ack_reader;
  dds::Reader<enavi_farm_JobEvent> event_reader;
  dds::Writer<enavi_farm_WorkerStatus> status_writer;
  dds::Writer<enavi_farm_EpisodeResult> result_writer;
  dds::Reader<enavi_farm_CollectAssignment> collect_reader;
  dds::Reader<enavi_farm_PolicyBlob> policy_reader;
  dds::Writer<enavi_farm_RolloutResult> rollout_writer;
  dds::ReadCondition assignment_cond, ack_cond, event_cond, collect_cond, policy_cond;
};

WorkerBus::WorkerBus(const BusOptions& options, std::string worker_id)
    : impl_(std::make_unique<Impl>(options, std::move(worker_id))) {}
WorkerBus::~WorkerBus() = default;

WorkerBus::Inbox WorkerBus::Wait(std::chrono::milliseconds timeout) {
  impl_->common.waitset.Wait(timeout);
  impl_->common.guard.TakeTriggered();
  Inbox inbox;
  const std::string& me = impl_->worker_id;
  impl_->assignment_reader.Take(SIZE_MAX, [&](const enavi_farm_Assignment& c,
                                              const dds::SampleInfo& info) {
    if (!info.valid_data || Str(c.worker_id) != me) return;
    Convert(&inbox.bad_samples, kAssignmentTopic,
            [&] { inbox.assignments.push_back(FromSample(c)); });
  });
  impl_->collect_reader.Take(SIZE_MAX, [&](const enavi_farm_CollectAssignment& c,
                                           const dds::SampleInfo& info) {
    if (!info.valid_data || Str(c.worker_id) != me) return;
    Convert(&inbox.bad_samples, kCollectTopic,
            [&] { inbox.assignments.push_back(FromSample(c)); });
  });
  impl_->policy_reader.Take(SIZE_MAX, [&](const enavi_farm_PolicyBlob& c,
                                          const dds::SampleInfo& info) {
    if (!info.valid_data) return;
    inbox.policies.push_back({Str(c.hash), Str(c.policy_json)});
  });
  impl_->ack_reader.Take(SIZE_MAX, [&](const enavi_farm_ResultAck& c, const dds::SampleInfo& info) {
    if (!info.valid_data || Str(c.worker_id) != me) return;
    Convert(&inbox.bad_samples, kAckTopic, [&] { inbox.acks.push_back(FromSample(c)); });
  });
  impl_->event_reader.Take(SIZE_MAX, [&](const enavi_farm_JobEvent& c, const dds::SampleInfo& info) {
    if (!info.valid_data) return;
    inbox.events.push_back(FromSample(c));
  });
  return inbox;
}

void WorkerBus::Wake() { impl_->common.guard.Trigger(); }

void WorkerBus::Publish(const WorkerStatus& status) {
  StatusSample sample;
  ToSample(status, &sample);
  impl_->status_writer.Write(sample.c);
}

void WorkerBus::DisposeStatus() {
  WorkerStatus key;
  key.worker_id = impl_->worker_id;
  StatusSample sample;
  ToSample(key, &sample);
  impl_->status_writer.Dispose(sample.c);
}

void WorkerBus::Publish(const ResultMessage& result) {
  if (!result.rollout.empty()) {
    if (result.rollout.size() > kMaxRolloutBytes) {
      throw std::invalid_argument("rollout of " + std::to_string(result.rollout.size()) +
                                  " bytes is above the bus limit");
    }
    RolloutSample sample;
    ToSample(result, &sample);
    return impl_->rollout_writer.Write(sample.c);
  }
  ResultSample sample;
  ToSample(result, &sample);
  impl_->result_writer.Write(sample.c);
}

void WorkerBus::Retire(const ResultMessage& result) {
  // Only the key matters; the other fields are left empty but valid.
  ResultMessage key;
  key.episode_id = result.episode_id;
  key.attempt = result.attempt;
  key.status = ResultStatus::kRejected;
  if (!result.rollout.empty()) {
    RolloutSample sample;
    ToSample(key, &sample);
    return impl_->rollout_writer.Unregister(sample.c);
  }
  ResultSample sample;
  ToSample(key, &sample);
  impl_->result_writer.Unregister(sample.c);
}

std::size_t WorkerBus::MatchedServers() const { return impl_->assignment_reader.MatchedWriters(); }

const std::string& WorkerBus::worker_id() const { return impl_->worker_id; }

}  // namespace enavi::api
