#pragma once
// Cyclone DDS configuration for the farm: one private loopback farm on a host, or many hosts
// that find each other through a peer list (no multicast assumed). docs/farm.md shows the XML.

#include <cstddef>
#include <string>
#include <vector>

namespace enavi::api {

struct DdsNetwork {
  /// Single host, nothing leaves it: interface 127.0.0.1, discovery to 127.0.0.1 only.
  bool loopback = false;
  /// Hosts (name or address, optionally host:port) to send discovery to. Unicast only: each
  /// worker needs the server here (and the server may list workers); the local host is added.
  std::vector<std::string> peers;
  /// Network interface (name like eth0 or an address); empty: Cyclone picks one.
  std::string interface;
  /// Participants one host may run in one domain (server + workers + clients); each takes a
  /// participant index and a pair of UDP ports.
  int max_participants_per_host = 60;
  /// Optional Cyclone trace file (Tracing/OutputFile with verbosity "config"); empty: none.
  std::string trace_file;
};

/// Participant lease: how long a silent peer (killed, or cut off) stays matched. Just above the
/// farm's 4 s writer liveliness (BusOptions::liveliness_lease), which detects lost workers first.
inline constexpr int kParticipantLeaseS = 5;
/// Writer history-cache high-water mark: room for every sample a lost peer leaves
/// unacknowledged during its lease (thousands of results, assignments and acks), so no write
/// blocks on it.
inline constexpr std::size_t kWhcHighBytes = std::size_t{16} << 20;

/// Cyclone DDS XML for `network`. Throws std::invalid_argument naming the field when a peer or
/// interface holds characters that cannot appear in a host name or address.
std::string CycloneConfigXml(const DdsNetwork& network);

}  // namespace enavi::api
