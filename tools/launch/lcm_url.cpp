#include "launch/lcm_url.hpp"

#include <arpa/inet.h>

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace rover::launch {
namespace {

std::optional<int> ParseInt(const std::string& text) {
  if (text.empty() || text.size() > 9) return std::nullopt;
  for (const char c : text) {
    if (c < '0' || c > '9') return std::nullopt;
  }
  return std::atoi(text.c_str());
}

// /proc/net/route holds addresses as the hex of the 32-bit value in host byte order.
std::optional<std::uint32_t> ParseRouteHex(const std::string& text) {
  if (text.size() != 8) return std::nullopt;
  char* end = nullptr;
  const unsigned long v = std::strtoul(text.c_str(), &end, 16);
  if (end == nullptr || *end != '\0') return std::nullopt;
  return ntohl(static_cast<std::uint32_t>(v));
}

}  // namespace

LcmUrlInfo ParseLcmUrl(const std::string& url) {
  LcmUrlInfo info;
  const std::string scheme = "udpm://";
  if (url.rfind(scheme, 0) != 0) return info;
  info.udpm = true;
  const auto query_at = url.find('?');
  const std::string target = url.substr(scheme.size(), query_at == std::string::npos
                                                           ? std::string::npos
                                                           : query_at - scheme.size());
  const auto colon = target.rfind(':');
  if (!target.empty()) info.group = target.substr(0, colon);
  if (colon != std::string::npos) {
    if (auto port = ParseInt(target.substr(colon + 1))) info.port = *port;
  }
  if (query_at != std::string::npos) {
    std::istringstream query(url.substr(query_at + 1));
    for (std::string pair; std::getline(query, pair, '&');) {
      if (pair.rfind("ttl=", 0) == 0) {
        if (auto ttl = ParseInt(pair.substr(4))) info.ttl = *ttl;
      }
    }
  }
  return info;
}

std::optional<std::string> MulticastRouteInterface(const std::string& group,
                                                   const std::string& route_table) {
  in_addr addr{};
  if (inet_pton(AF_INET, group.c_str(), &addr) != 1) return std::nullopt;
  const std::uint32_t target = ntohl(addr.s_addr);
  std::ifstream in(route_table);
  std::string line;
  std::getline(in, line);  // header
  std::optional<std::string> best;
  int best_bits = -1;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string iface, dest_hex, gateway, flags, refcnt, use, metric, mask_hex;
    if (!(fields >> iface >> dest_hex >> gateway >> flags >> refcnt >> use >> metric >> mask_hex)) continue;
    const auto dest = ParseRouteHex(dest_hex);
    const auto mask = ParseRouteHex(mask_hex);
    if (!dest || !mask || (target & *mask) != (*dest & *mask)) continue;
    int bits = 0;
    for (std::uint32_t m = *mask; m != 0; m <<= 1) ++bits;
    if (bits > best_bits) {
      best_bits = bits;
      best = bits == 0 ? iface + " (default route)" : iface;
    }
  }
  return best;
}

std::string NothingHeardCauses(const std::string& url, const std::string& process) {
  const auto info = ParseLcmUrl(url);
  std::ostringstream os;
  os << "likely causes: ";
  if (info.udpm && info.ttl == 0) {
    os << "ttl=0 in the LCM URL (this one has it: the bus stays on this host; use ttl=1 on every host)";
  } else if (info.udpm) {
    os << "ttl=0 in the LCM URL of the other host (this one has ttl=" << info.ttl << ")";
  } else {
    os << "a bus that is not udpm multicast (" << url << ")";
  }
  os << "; no multicast route (224.0.0.0/4) on the LAN interface of each host (here " << info.group;
  if (const auto dev = MulticastRouteInterface(info.group)) {
    os << " goes out of " << *dev << ")";
  } else {
    os << " has no route)";
  }
  os << "; a different group or port on the other host (this one: " << info.group << ":" << info.port
     << "); or " << process << " not running";
  return os.str();
}

}  // namespace rover::launch
