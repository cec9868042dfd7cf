#pragma once
// Routes Cyclone DDS's log into the test: any warning or error it prints while a guard lives is a
// test failure (a misconfiguration Cyclone only complains about must not pass silently).

#include <mutex>
#include <string>
#include <vector>

#include <dds/dds.h>
#include <gtest/gtest.h>

namespace enavi::testing {

class CycloneLogGuard {
 public:
  CycloneLogGuard() { dds_set_log_sink(&Sink, this); }
  ~CycloneLogGuard() {
    dds_set_log_sink(nullptr, nullptr);
    std::lock_guard lock(mutex_);
    for (const auto& m : messages_) ADD_FAILURE() << "Cyclone DDS logged: " << m;
  }
  CycloneLogGuard(const CycloneLogGuard&) = delete;
  CycloneLogGuard& operator=(const CycloneLogGuard&) = delete;

 private:
  static void Sink(void* self, const dds_log_data_t* data) {
    if ((data->priority & (DDS_LC_FATAL | DDS_LC_ERROR | DDS_LC_WARNING)) == 0) return;
    auto* guard = static_cast<CycloneLogGuard*>(self);
    std::lock_guard lock(guard->mutex_);
    guard->messages_.emplace_back(data->message, data->size);
  }
  std::mutex mutex_;
  std::vector<std::string> messages_;
};

}  // namespace enavi::testing
