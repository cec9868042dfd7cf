#pragma once
// A small RAII layer over the Cyclone DDS C API. Only api/ includes this header: the rest of the
// code talks to the farm through api/farm_bus.h, which keeps DDS types out of its interface.
//
// Handles: dds_entity_t > 0 is a valid entity, < 0 an error code (dds_strretcode). Every wrapper
// owns its entity and deletes it on destruction; deleting a participant deletes its children, so
// declare the participant before the entities created from it (members die in reverse order).

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <dds/dds.h>

namespace enavi::api::dds {

/// A DDS call failed; `code()` is the dds_return_t, the message names the call.
class DdsError : public std::runtime_error {
 public:
  DdsError(const std::string& what, dds_return_t code);
  dds_return_t code() const { return code_; }

 private:
  dds_return_t code_;
};

/// Returns `rc` when it is >= 0 and throws DdsError("<what>: <dds_strretcode>") otherwise.
dds_return_t Check(dds_return_t rc, const char* what);

/// dds_duration_t from a std::chrono duration (infinite durations map to DDS_INFINITY).
dds_duration_t ToDuration(std::chrono::nanoseconds d);

/// Move-only owner of one entity; deletes it on destruction (errors ignored: a parent may
/// already have deleted it).
class Entity {
 public:
  Entity() = default;
  explicit Entity(dds_entity_t handle) : handle_(handle) {}
  ~Entity() { Reset(); }
  Entity(Entity&& other) noexcept : handle_(std::exchange(other.handle_, 0)) {}
  Entity& operator=(Entity&& other) noexcept;
  Entity(const Entity&) = delete;
  Entity& operator=(const Entity&) = delete;

  dds_entity_t get() const { return handle_; }
  explicit operator bool() const { return handle_ > 0; }
  void Reset();

 private:
  dds_entity_t handle_ = 0;
};

/// QoS builder (owns a dds_qos_t).
class Qos {
 public:
  Qos();
  ~Qos();
  Qos(const Qos& other);
  Qos& operator=(const Qos& other);

  Qos& Reliable(std::chrono::milliseconds max_blocking = std::chrono::seconds(10));
  Qos& BestEffort();
  Qos& Volatile();
  Qos& TransientLocal();
  Qos& KeepLast(int depth);
  Qos& KeepAll();
  /// AUTOMATIC liveliness: the participant asserts it; lost when the process stops.
  Qos& Liveliness(std::chrono::milliseconds lease);
  Qos& Partition(const std::string& name);
  /// Writers: do not dispose an instance when it is unregistered (we unregister to free memory).
  Qos& NoAutoDispose();
  const dds_qos_t* get() const { return qos_; }

 private:
  dds_qos_t* qos_;
};

/// A domain created with an explicit Cyclone XML configuration. Process-wide and shared: creating
/// the same domain id twice in one process returns the first (its configuration wins), and the
/// domain is deleted when the last user goes away.
class Domain {
 public:
  /// @param config_xml Cyclone configuration; empty: Cyclone's own (CYCLONEDDS_URI or defaults).
  static std::shared_ptr<Domain> Acquire(std::uint32_t domain_id, const std::string& config_xml);
  ~Domain();
  std::uint32_t id() const { return id_; }

 private:
  Domain(std::uint32_t id, dds_entity_t handle) : id_(id), handle_(handle) {}
  std::uint32_t id_;
  dds_entity_t handle_;  // 0 when Cyclone's implicit domain is used
};

class Participant {
 public:
  Participant(std::shared_ptr<Domain> domain);
  dds_entity_t get() const { return entity_.get(); }

 private:
  std::shared_ptr<Domain> domain_;  // outlives the participant entity (declared first)
  Entity entity_;
};

class Topic {
 public:
  Topic(const Participant& participant, const dds_topic_descriptor_t* descriptor,
        const std::string& name, const Qos& qos);
  dds_entity_t get() const { return entity_.get(); }

 private:
  Entity entity_;
};

/// Publisher or subscriber bound to one partition.
class Publisher {
 public:
  Publisher(const Participant& participant, const Qos& qos);
  dds_entity_t get() const { return entity_.get(); }

 private:
  Entity entity_;
};

class Subscriber {
 public:
  Subscriber(const Participant& participant, const Qos& qos);
  dds_entity_t get() const { return entity_.get(); }

 private:
  Entity entity_;
};

/// Writer of the IDL-generated C type `T`.
template <typename T>
class Writer {
 public:
  Writer(const Publisher& publisher, const Topic& topic, const Qos& qos)
      : entity_(Check(dds_create_writer(publisher.get(), topic.get(), qos.get(), nullptr),
                      "dds_create_writer")) {}
  void Write(const T& sample) { Check(dds_write(entity_.get(), &sample), "dds_write"); }
  /// Drops the instance from the writer's history (after its data was acknowledged).
  void Unregister(const T& key_sample) {
    Check(dds_unregister_instance(entity_.get(), &key_sample), "dds_unregister_instance");
  }
  void Dispose(const T& key_sample) {
    Check(dds_dispose(entity_.get(), &key_sample), "dds_dispose");
  }
  /// Number of matched readers.
  std::size_t MatchedReaders() const;
  dds_entity_t get() const { return entity_.get(); }

 private:
  Entity entity_;
};

/// Sample metadata the farm uses.
struct SampleInfo {
  bool valid_data = false;
  bool alive = true;      ///< false: instance disposed or without writers
  bool disposed = false;  ///< the writer disposed the instance (a deliberate end)
  dds_instance_handle_t instance = 0;
};

/// Reader of the IDL-generated C type `T`; Take() loans the samples and returns them after the
/// visitor has copied what it needs.
template <typename T>
class Reader {
 public:
  Reader(const Subscriber& subscriber, const Topic& topic, const Qos& qos)
      : entity_(Check(dds_create_reader(subscriber.get(), topic.get(), qos.get(), nullptr),
                      "dds_create_reader")) {}

  /// Takes up to `max` samples; calls visit(const T&, const SampleInfo&) for each. Returns the
  /// number taken.
  template <typename Visit>
  std::size_t Take(std::size_t max, Visit&& visit);

  std::size_t MatchedWriters() const;
  dds_entity_t get() const { return entity_.get(); }

 private:
  Entity entity_;
};

/// A condition the application triggers (used to wake a waitset from another thread).
class GuardCondition {
 public:
  explicit GuardCondition(const Participant& participant);
  void Trigger();
  /// Reads and resets the trigger.
  bool TakeTriggered();
  dds_entity_t get() const { return entity_.get(); }

 private:
  Entity entity_;
};

/// Triggers while the reader holds samples in any state (data or instance-state changes).
class ReadCondition {
 public:
  explicit ReadCondition(dds_entity_t reader);
  dds_entity_t get() const { return entity_.get(); }

 private:
  Entity entity_;
};

class WaitSet {
 public:
  explicit WaitSet(const Participant& participant);
  void Attach(dds_entity_t condition, dds_attach_t token);
  /// Blocks until an attached condition triggers or `timeout` passes; returns the tokens of the
  /// triggered conditions (empty on timeout).
  std::vector<dds_attach_t> Wait(std::chrono::nanoseconds timeout);

 private:
  Entity entity_;
};

// ---- template implementations ----

std::size_t MatchedCount(dds_entity_t entity, bool writer_side);

template <typename T>
std::size_t Writer<T>::MatchedReaders() const {
  return MatchedCount(entity_.get(), /*writer_side=*/true);
}

template <typename T>
std::size_t Reader<T>::MatchedWriters() const {
  return MatchedCount(entity_.get(), /*writer_side=*/false);
}

template <typename T>
template <typename Visit>
std::size_t Reader<T>::Take(std::size_t max, Visit&& visit) {
  constexpr std::size_t kChunk = 64;
  std::size_t total = 0;
  while (total < max) {
    void* samples[kChunk] = {nullptr};
    dds_sample_info_t infos[kChunk];
    const std::size_t want = std::min(kChunk, max - total);
    const dds_return_t n = Check(
        dds_take(entity_.get(), samples, infos, want, static_cast<uint32_t>(want)), "dds_take");
    if (n == 0) break;
    // Return the loan even when the visitor throws.
    struct LoanGuard {
      dds_entity_t reader;
      void** buffer;
      dds_return_t count;
      ~LoanGuard() { dds_return_loan(reader, buffer, count); }
    } guard{entity_.get(), samples, n};
    for (dds_return_t i = 0; i < n; ++i) {
      SampleInfo info;
      info.valid_data = infos[i].valid_data;
      info.alive = infos[i].instance_state == DDS_IST_ALIVE;
      info.disposed = infos[i].instance_state == DDS_IST_NOT_ALIVE_DISPOSED;
      info.instance = infos[i].instance_handle;
      visit(*static_cast<const T*>(samples[i]), info);
    }
    total += static_cast<std::size_t>(n);
    if (static_cast<std::size_t>(n) < want) break;
  }
  return total;
}

}  // namespace enavi::api::dds
