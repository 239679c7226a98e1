// What an LCM udpm URL says about reaching other hosts, and where this host routes its
// multicast: for the launcher's warnings and the operator's "nothing answered" message.
// LCM 1.3.1's udpm URL: udpm://GROUP:PORT?ttl=N&recv_buf_size=B (defaults 239.255.76.67,
// 7667, ttl 0). ttl=0 keeps every packet on this host; ttl=1 reaches the LAN segment.
#pragma once

#include <optional>
#include <string>

namespace rover::launch {

struct LcmUrlInfo {
  bool udpm = false;                 // the udpm provider (else: fields are defaults)
  std::string group = "239.255.76.67";
  int port = 7667;
  int ttl = 0;
};

// Parses `url`; a malformed number leaves the default (LCM itself reports the error).
LcmUrlInfo ParseLcmUrl(const std::string& url);

// The interface this host's routing table sends `group` out of (longest matching prefix
// of /proc/net/route), with " (default route)" when only the default route covers it;
// nullopt when no route does (multicast cannot leave or loop back then).
std::optional<std::string> MulticastRouteInterface(const std::string& group,
                                                   const std::string& route_table = "/proc/net/route");

// One sentence naming why a bus heard nothing from another host's processes: ttl=0 in
// the URL, no multicast route on the LAN interface, a different port on the other
// host, or the process not running; what this host has for each is filled in.
std::string NothingHeardCauses(const std::string& url, const std::string& process);

}  // namespace rover::launch
