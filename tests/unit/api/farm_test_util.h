#pragma once
// Helpers for tests that talk over the farm's DDS bus: every test gets a private loopback
// configuration, a domain derived from its process id and a partition of its own, so tests run
// concurrently (ctest -j) without hearing each other.

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "api/dds_config.h"
#include "api/farm_bus.h"

namespace enavi::testing {

inline api::BusOptions TestBus() {
  static std::atomic<int> counter{0};
  api::BusOptions bus;
  bus.domain_id = 120 + static_cast<std::uint32_t>(getpid()) % 100;
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  bus.partition = "test-" + std::to_string(getpid()) + "-" +
                  (info ? std::string(info->name()) : std::string("x")) + "-" +
                  std::to_string(counter++);
  api::DdsNetwork net;
  net.loopback = true;
  bus.config_xml = api::CycloneConfigXml(net);
  return bus;
}

/// Polls `condition` until it holds or `timeout` passes (a wait, not a timing assertion).
inline bool WaitFor(const std::function<bool()>& condition,
                    std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return condition();
}

}  // namespace enavi::testing
