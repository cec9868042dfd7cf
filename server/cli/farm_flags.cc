#include "server/cli/farm_flags.h"

#include <signal.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "api/dds_config.h"

namespace enavi::cli {

void AddBusFlags(CLI::App* app, BusFlags* f) {
  app->add_option("--domain", f->domain, "DDS domain id shared by server and workers")
      ->check(CLI::Range(0, 232))
      ->envname("ENAVI_DOMAIN")
      ->capture_default_str();
  app->add_option("--partition", f->partition, "DDS partition: farms in one domain stay apart")
      ->envname("ENAVI_PARTITION")
      ->capture_default_str();
  app->add_option("--peers", f->peers,
                  "hosts to discover over unicast (comma-separated); no multicast needed")
      ->delimiter(',');
  app->add_option("--interface", f->interface, "network interface (name or address) to use");
  app->add_option("--dds-config", f->dds_config, "Cyclone DDS XML configuration file")
      ->check(CLI::ExistingFile);
  app->add_flag("--loopback", f->loopback, "this host only: loopback interface, no network");
}

api::BusOptions ResolveBus(const BusFlags& f) {
  api::BusOptions bus;
  bus.domain_id = static_cast<std::uint32_t>(f.domain);
  if (f.partition.empty() || f.partition.find_first_of("*?[]\\") != std::string::npos) {
    throw std::invalid_argument("--partition: '" + f.partition +
                                "' must be non-empty and free of wildcards (* ? [ ] \\)");
  }
  bus.partition = f.partition;
  const bool network_flags = !f.peers.empty() || !f.interface.empty();
  if (!f.dds_config.empty()) {
    if (network_flags || f.loopback) {
      throw std::invalid_argument("--dds-config: cannot be combined with --peers/--interface/--loopback");
    }
    std::ifstream in(f.dds_config);
    std::ostringstream text;
    text << in.rdbuf();
    if (!in) throw std::invalid_argument("--dds-config: cannot read '" + f.dds_config + "'");
    bus.config_xml = text.str();
  } else if (f.loopback) {
    if (network_flags) throw std::invalid_argument("--loopback: cannot be combined with --peers/--interface");
    api::DdsNetwork net;
    net.loopback = true;
    bus.config_xml = api::CycloneConfigXml(net);
  } else if (network_flags) {
    api::DdsNetwork net;
    net.peers = f.peers;
    net.interface = f.interface;
    bus.config_xml = api::CycloneConfigXml(net);
  } else if (const char* uri = std::getenv("CYCLONEDDS_URI"); uri != nullptr && *uri != '\0') {
    bus.config_xml.clear();  // Cyclone reads CYCLONEDDS_URI itself
  } else {
    api::DdsNetwork net;
    net.loopback = true;
    bus.config_xml = api::CycloneConfigXml(net);
  }
  return bus;
}

void SetupLogging(bool verbose) {
  auto logger = spdlog::stderr_color_mt("enavi");
  logger->set_pattern("[%H:%M:%S.%e] [%^%l%$] %v");
  logger->set_level(verbose ? spdlog::level::debug : spdlog::level::info);
  spdlog::set_default_logger(logger);
}

namespace {
sigset_t StopSet() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  return set;
}
}  // namespace

StopSignals::StopSignals() {
  const sigset_t set = StopSet();
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

StopSignals::~StopSignals() {
  done_ = true;
  if (watcher_.joinable()) watcher_.join();
}

int StopSignals::Wait() {
  const sigset_t set = StopSet();
  int sig = 0;
  while (sigwait(&set, &sig) != 0) {
  }
  return sig;
}

void StopSignals::Watch(std::function<void(int)> on_signal) {
  watcher_ = std::thread([this, on_signal = std::move(on_signal)] {
    const sigset_t set = StopSet();
    const timespec slice{0, 200'000'000};
    int count = 0;
    while (!done_) {
      if (sigtimedwait(&set, nullptr, &slice) > 0) on_signal(++count);
    }
  });
}

void RequireEpisodeUnlessEpisodeCmd(const CLI::App& root, const std::string& episode_cmd) {
  if (!episode_cmd.empty()) return;
  for (const CLI::App* sub : root.get_subcommands([](const CLI::App*) { return true; })) {
    if (sub->get_name() == "episode") return;
  }
  throw std::runtime_error(
      "this enavi build has no `episode` subcommand, the default episode command "
      "(`enavi episode --spec-file S --result-file R`); pass --episode-cmd PROGRAM");
}

std::pair<std::string, int> ParseHostPort(const std::string& text, const std::string& flag) {
  const std::size_t colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == text.size()) {
    throw std::invalid_argument(flag + ": '" + text + "' is not HOST:PORT");
  }
  std::string host = text.substr(0, colon);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  int port = -1;
  try {
    std::size_t used = 0;
    port = std::stoi(text.substr(colon + 1), &used);
    if (used != text.size() - colon - 1) port = -1;
  } catch (const std::exception&) {
  }
  if (port < 0 || port > 65535) {
    throw std::invalid_argument(flag + ": '" + text + "': port must be 0..65535");
  }
  return {host, port};
}

}  // namespace enavi::cli
