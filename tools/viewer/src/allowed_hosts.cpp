// The Host names the viewer answers (allowed_hosts.h).
#include "whiskeye/viewer/allowed_hosts.h"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>

namespace whiskeye::viewer {

namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

std::string numeric(const sockaddr* a) {
  char text[INET6_ADDRSTRLEN] = "";
  if (a->sa_family == AF_INET) {
    ::inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(a)->sin_addr, text, sizeof text);
  } else if (a->sa_family == AF_INET6) {
    ::inet_ntop(AF_INET6, &reinterpret_cast<const sockaddr_in6*>(a)->sin6_addr, text, sizeof text);
  }
  return text;
}

// The host part of a Host header, lower case, an IPv6 address without its brackets.
std::string host_part(std::string_view host) {
  if (!host.empty() && host.front() == '[') {
    const auto close = host.find(']');
    return close == std::string_view::npos ? std::string() : lower(host.substr(1, close - 1));
  }
  const auto colon = host.find(':');
  if (colon != std::string_view::npos && host.find(':', colon + 1) == std::string_view::npos) host = host.substr(0, colon);
  if (!host.empty() && host.back() == '.') host.remove_suffix(1);  // "localhost." is localhost
  return lower(host);
}

}  // namespace

std::vector<std::string> interface_addresses(bool ipv6) {
  std::vector<std::string> out;
  ifaddrs* list = nullptr;
  if (::getifaddrs(&list) == 0) {
    for (const ifaddrs* i = list; i != nullptr; i = i->ifa_next) {
      if (i->ifa_addr == nullptr || (i->ifa_flags & IFF_UP) == 0) continue;
      if (i->ifa_addr->sa_family == AF_INET || (ipv6 && i->ifa_addr->sa_family == AF_INET6)) {
        out.push_back(numeric(i->ifa_addr));
      }
    }
    ::freeifaddrs(list);
    return out;
  }
  // getifaddrs needs a netlink socket, which the unit's RestrictAddressFamilies= does not allow: the
  // IPv4 addresses through an AF_INET socket instead.
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return out;
  ifreq reqs[64];
  ifconf conf{};
  conf.ifc_len = sizeof reqs;
  conf.ifc_req = reqs;
  if (::ioctl(fd, SIOCGIFCONF, &conf) == 0) {
    for (std::size_t i = 0; i < static_cast<std::size_t>(conf.ifc_len) / sizeof(ifreq); ++i) out.push_back(numeric(&reqs[i].ifr_addr));
  }
  ::close(fd);
  return out;
}

AllowedHosts::AllowedHosts(const sockaddr_storage& bound, const std::string& listen_host,
                           const std::vector<std::string>& extra, const std::vector<std::string>& interfaces,
                           const std::string& host_name) {
  const auto* a = reinterpret_cast<const sockaddr*>(&bound);
  bool loopback = false;
  if (a->sa_family == AF_INET) {
    const auto* in = reinterpret_cast<const sockaddr_in*>(a);
    port_ = ntohs(in->sin_port);
    wildcard_ = in->sin_addr.s_addr == htonl(INADDR_ANY);
    loopback = (ntohl(in->sin_addr.s_addr) >> 24) == 127;
  } else if (a->sa_family == AF_INET6) {
    const auto* in6 = reinterpret_cast<const sockaddr_in6*>(a);
    port_ = ntohs(in6->sin6_port);
    wildcard_ = IN6_IS_ADDR_UNSPECIFIED(&in6->sin6_addr);
    loopback = IN6_IS_ADDR_LOOPBACK(&in6->sin6_addr);
  }
  if (wildcard_) {
    served_ = interfaces;
    std::stable_partition(served_.begin(), served_.end(), [](const std::string& s) { return s == "127.0.0.1" || s == "::1"; });
    names_.insert("localhost");
    if (!host_name.empty()) {
      names_.insert(lower(host_name));
      // Its mDNS name on the robot's network.
      if (host_name.find('.') == std::string::npos) names_.insert(lower(host_name) + ".local");
    }
  } else {
    served_.push_back(numeric(a));
    if (loopback) names_.insert("localhost");
  }
  for (const auto& s : served_) names_.insert(lower(s));
  // A name given to --listen ("localhost", the robot's name) is one it serves on.
  if (!wildcard_ && !listen_host.empty()) {
    names_.insert(host_part(listen_host.find(':') == std::string::npos ? listen_host : "[" + listen_host + "]"));
  }
  for (const auto& e : extra) names_.insert(host_part(e));
  names_.erase("");
}

bool AllowedHosts::allows(std::string_view host) const { return names_.count(host_part(host)) > 0; }

std::vector<std::string> AllowedHosts::urls() const {
  std::vector<std::string> out;
  for (const auto& s : served_) {
    const bool v6 = s.find(':') != std::string::npos;
    out.push_back("http://" + (v6 ? "[" + s + "]" : s) + ":" + std::to_string(port_) + "/");
  }
  return out;
}

}  // namespace whiskeye::viewer
