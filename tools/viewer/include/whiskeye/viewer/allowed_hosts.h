// Which Host headers the viewer answers: the names and addresses it serves on, and those the operator
// adds (--allow-host). A page on any other name is a DNS rebinding (a site whose name the attacker
// points at 127.0.0.1 or the robot's address, so the browser lets it read the answers): refused.
#pragma once

#include <sys/socket.h>

#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace whiskeye::viewer {

// The addresses of this host's interfaces (IPv4 and, where the socket is IPv6, IPv6), numeric.
std::vector<std::string> interface_addresses(bool ipv6);

class AllowedHosts {
 public:
  // `bound`: the listening socket's address. A wildcard address (0.0.0.0, ::) serves on every
  // interface: their addresses, "localhost" and this host's name; a loopback one: itself and
  // "localhost"; any other: itself. `listen_host`: the host as given to --listen (a name is allowed).
  // `extra`: --allow-host names or addresses. `interfaces`: interface_addresses() (a parameter for tests).
  AllowedHosts(const sockaddr_storage& bound, const std::string& listen_host, const std::vector<std::string>& extra,
               const std::vector<std::string>& interfaces, const std::string& host_name);

  // `host` is a Host header's value: a name, an IPv4 address or a bracketed IPv6 address, with or
  // without a port (the port is not checked: an ssh tunnel may forward any local port).
  bool allows(std::string_view host) const;

  // The URLs it serves on, to print: http://ADDR:PORT/ for each address (a wildcard: every interface's).
  std::vector<std::string> urls() const;

  bool wildcard() const { return wildcard_; }

 private:
  std::set<std::string> names_;      // lower case, IPv6 without brackets
  std::vector<std::string> served_;  // the addresses of urls(), in order
  int port_ = 0;
  bool wildcard_ = false;
};

}  // namespace whiskeye::viewer
