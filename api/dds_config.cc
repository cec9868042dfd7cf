#include "api/dds_config.h"

#include <cctype>
#include <sstream>
#include <stdexcept>

namespace enavi::api {
namespace {

// Host names, IPv4/IPv6 addresses, interface names and an optional :port.
void CheckToken(const std::string& value, const char* field) {
  if (value.empty()) throw std::invalid_argument(std::string(field) + ": empty value");
  for (char ch : value) {
    const bool ok = std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' || ch == '-' ||
                    ch == '_' || ch == ':' || ch == '[' || ch == ']' || ch == '%';
    if (!ok) {
      throw std::invalid_argument(std::string(field) + ": '" + value +
                                  "' is not a host name, address or interface name");
    }
  }
}

bool LooksLikeAddress(const std::string& s) {
  return !s.empty() && (std::isdigit(static_cast<unsigned char>(s[0])) ||
                        s.find(':') != std::string::npos);
}

}  // namespace

std::string CycloneConfigXml(const DdsNetwork& network) {
  if (network.max_participants_per_host < 1 || network.max_participants_per_host > 120) {
    throw std::invalid_argument("max_participants_per_host: " +
                                std::to_string(network.max_participants_per_host) +
                                " outside [1, 120]");
  }
  std::vector<std::string> peers = network.peers;
  std::string interface = network.interface;
  if (network.loopback) {
    interface = "127.0.0.1";
    peers = {"127.0.0.1"};
  } else {
    // Participants on this host find each other through the local host entry.
    peers.push_back("localhost");
  }
  for (const auto& p : peers) CheckToken(p, "peers");
  if (!interface.empty()) CheckToken(interface, "interface");

  std::ostringstream x;
  x << "<CycloneDDS xmlns=\"https://cdds.io/config\"><Domain Id=\"any\">";
  x << "<General>";
  if (!interface.empty()) {
    x << "<Interfaces><NetworkInterface "
      << (LooksLikeAddress(interface) ? "address" : "name") << "=\"" << interface
      << "\"/></Interfaces>";
  }
  x << "<AllowMulticast>false</AllowMulticast>";
  x << "</General>";
  x << "<Discovery>";
  x << "<ParticipantIndex>auto</ParticipantIndex>";
  x << "<MaxAutoParticipantIndex>" << network.max_participants_per_host - 1
    << "</MaxAutoParticipantIndex>";
  x << "<Peers>";
  for (const auto& p : peers) x << "<Peer address=\"" << p << "\"/>";
  x << "</Peers>";
  // A dead or unreachable peer stays matched until its participant lease ends (Cyclone's
  // default: 10 s); reliable writers keep every sample it has not acknowledged until then.
  x << "<LeaseDuration>" << kParticipantLeaseS << "s</LeaseDuration>";
  x << "</Discovery>";
  // Those unacknowledged samples count against the writer's history-cache high-water mark, and a
  // writer above it blocks in dds_write (Cyclone's default: adaptive, from 30 kB up to 500 kB).
  // On lossy links a killed worker then froze the server's loop (and a killed server every
  // worker's) for the whole lease: no heartbeats handled, healthy workers declared gone, their
  // leases re-queued. A fixed, generous mark keeps writes from blocking while a lost peer ages out.
  x << "<Internal><Watermarks><WhcHigh>" << kWhcHighBytes / 1024
    << "kB</WhcHigh><WhcAdaptive>false</WhcAdaptive></Watermarks></Internal>";
  if (!network.trace_file.empty()) {
    if (network.trace_file.find_first_of("<>&\"'") != std::string::npos) {
      throw std::invalid_argument("trace_file: '" + network.trace_file +
                                  "' holds a character not allowed in the XML configuration");
    }
    x << "<Tracing><Verbosity>config</Verbosity><OutputFile>" << network.trace_file
      << "</OutputFile></Tracing>";
  }
  x << "</Domain></CycloneDDS>";
  return x.str();
}

}  // namespace enavi::api
