#include "api/dds.h"

#include <map>
#include <mutex>

namespace enavi::api::dds {

DdsError::DdsError(const std::string& what, dds_return_t code)
    : std::runtime_error(what), code_(code) {}

dds_return_t Check(dds_return_t rc, const char* what) {
  if (rc < 0) throw DdsError(std::string(what) + ": " + dds_strretcode(rc), rc);
  return rc;
}

dds_duration_t ToDuration(std::chrono::nanoseconds d) {
  if (d == std::chrono::nanoseconds::max()) return DDS_INFINITY;
  return static_cast<dds_duration_t>(d.count());
}

Entity& Entity::operator=(Entity&& other) noexcept {
  if (this != &other) {
    Reset();
    handle_ = std::exchange(other.handle_, 0);
  }
  return *this;
}

void Entity::Reset() {
  if (handle_ > 0) dds_delete(handle_);
  handle_ = 0;
}

// ---- Qos ----

Qos::Qos() : qos_(dds_create_qos()) {
  if (qos_ == nullptr) throw std::bad_alloc();
}
Qos::~Qos() { dds_delete_qos(qos_); }
Qos::Qos(const Qos& other) : Qos() { dds_copy_qos(qos_, other.qos_); }
Qos& Qos::operator=(const Qos& other) {
  if (this != &other) {
    dds_reset_qos(qos_);
    dds_copy_qos(qos_, other.qos_);
  }
  return *this;
}

Qos& Qos::Reliable(std::chrono::milliseconds max_blocking) {
  dds_qset_reliability(qos_, DDS_RELIABILITY_RELIABLE, ToDuration(max_blocking));
  return *this;
}
Qos& Qos::BestEffort() {
  dds_qset_reliability(qos_, DDS_RELIABILITY_BEST_EFFORT, 0);
  return *this;
}
Qos& Qos::Volatile() {
  dds_qset_durability(qos_, DDS_DURABILITY_VOLATILE);
  return *this;
}
Qos& Qos::TransientLocal() {
  dds_qset_durability(qos_, DDS_DURABILITY_TRANSIENT_LOCAL);
  return *this;
}
Qos& Qos::KeepLast(int depth) {
  dds_qset_history(qos_, DDS_HISTORY_KEEP_LAST, depth);
  return *this;
}
Qos& Qos::KeepAll() {
  dds_qset_history(qos_, DDS_HISTORY_KEEP_ALL, DDS_LENGTH_UNLIMITED);
  return *this;
}
Qos& Qos::Liveliness(std::chrono::milliseconds lease) {
  dds_qset_liveliness(qos_, DDS_LIVELINESS_AUTOMATIC, ToDuration(lease));
  return *this;
}
Qos& Qos::Partition(const std::string& name) {
  dds_qset_partition1(qos_, name.c_str());
  return *this;
}
Qos& Qos::NoAutoDispose() {
  dds_qset_writer_data_lifecycle(qos_, false);
  return *this;
}

// ---- Domain ----

namespace {
// Process-wide registry: Cyclone refuses a second dds_create_domain for an id that exists.
struct DomainRegistry {
  std::mutex mutex;
  std::map<std::uint32_t, std::weak_ptr<Domain>> domains;
};
DomainRegistry& Registry() {
  static DomainRegistry* registry = new DomainRegistry();  // never destroyed: used at exit
  return *registry;
}
}  // namespace

std::shared_ptr<Domain> Domain::Acquire(std::uint32_t domain_id, const std::string& config_xml) {
  if (domain_id > 232) {
    throw DdsError("DDS domain id " + std::to_string(domain_id) + " out of range [0, 232]",
                   DDS_RETCODE_BAD_PARAMETER);
  }
  DomainRegistry& registry = Registry();
  std::lock_guard lock(registry.mutex);
  if (auto existing = registry.domains[domain_id].lock()) return existing;
  dds_entity_t handle = 0;
  if (!config_xml.empty()) {
    handle = Check(dds_create_domain(domain_id, config_xml.c_str()), "dds_create_domain");
  }
  std::shared_ptr<Domain> domain(new Domain(domain_id, handle));
  registry.domains[domain_id] = domain;
  return domain;
}

Domain::~Domain() {
  if (handle_ > 0) dds_delete(handle_);
}

// ---- entities ----

Participant::Participant(std::shared_ptr<Domain> domain)
    : domain_(std::move(domain)),
      entity_(Check(dds_create_participant(domain_->id(), nullptr, nullptr),
                    "dds_create_participant")) {}

Topic::Topic(const Participant& participant, const dds_topic_descriptor_t* descriptor,
             const std::string& name, const Qos& qos)
    : entity_(Check(dds_create_topic(participant.get(), descriptor, name.c_str(), qos.get(),
                                     nullptr),
                    ("dds_create_topic(" + name + ")").c_str())) {}

Publisher::Publisher(const Participant& participant, const Qos& qos)
    : entity_(Check(dds_create_publisher(participant.get(), qos.get(), nullptr),
                    "dds_create_publisher")) {}

Subscriber::Subscriber(const Participant& participant, const Qos& qos)
    : entity_(Check(dds_create_subscriber(participant.get(), qos.get(), nullptr),
                    "dds_create_subscriber")) {}

GuardCondition::GuardCondition(const Participant& participant)
    : entity_(Check(dds_create_guardcondition(participant.get()), "dds_create_guardcondition")) {}

void GuardCondition::Trigger() {
  Check(dds_set_guardcondition(entity_.get(), true), "dds_set_guardcondition");
}

bool GuardCondition::TakeTriggered() {
  bool triggered = false;
  Check(dds_take_guardcondition(entity_.get(), &triggered), "dds_take_guardcondition");
  return triggered;
}

ReadCondition::ReadCondition(dds_entity_t reader)
    : entity_(Check(dds_create_readcondition(reader, DDS_ANY_STATE), "dds_create_readcondition")) {}

WaitSet::WaitSet(const Participant& participant)
    : entity_(Check(dds_create_waitset(participant.get()), "dds_create_waitset")) {}

void WaitSet::Attach(dds_entity_t condition, dds_attach_t token) {
  Check(dds_waitset_attach(entity_.get(), condition, token), "dds_waitset_attach");
}

std::vector<dds_attach_t> WaitSet::Wait(std::chrono::nanoseconds timeout) {
  dds_attach_t triggered[16];
  const dds_return_t n =
      Check(dds_waitset_wait(entity_.get(), triggered, 16, ToDuration(timeout)),
            "dds_waitset_wait");
  return std::vector<dds_attach_t>(triggered, triggered + std::min<dds_return_t>(n, 16));
}

std::size_t MatchedCount(dds_entity_t entity, bool writer_side) {
  if (writer_side) {
    dds_publication_matched_status_t status;
    Check(dds_get_publication_matched_status(entity, &status), "dds_get_publication_matched_status");
    return status.current_count;
  }
  dds_subscription_matched_status_t status;
  Check(dds_get_subscription_matched_status(entity, &status), "dds_get_subscription_matched_status");
  return status.current_count;
}

}  // namespace enavi::api::dds
