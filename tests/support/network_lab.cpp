#include "tests/support/network_lab.h"

#include <fmt/format.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <sstream>

#include "tests/support/run_command.h"

namespace farm::test {

namespace {

constexpr const char* kLabPrefix = "fl";

// iproute2's `ip`, by its full path (processes are started without a shell or PATH search).
std::string ip_program() {
  for (const char* p : {"/usr/sbin/ip", "/sbin/ip", "/usr/bin/ip", "/bin/ip"}) {
    if (::access(p, X_OK) == 0) return p;
  }
  return "ip";
}

std::string quoted(const std::vector<std::string>& argv) {
  std::string line;
  for (const std::string& a : argv) line += fmt::format("{}{}", line.empty() ? "" : " ", shell_quote(a));
  return line;
}

// Deletes a namespace, killing what still runs in it first (a lab whose test process was killed
// leaves its servers running: nothing else stops them).
void delete_namespace(const std::string& name) {
  const std::string ns = shell_quote(name);
  run_command(fmt::format("{0} netns pids {1} 2>/dev/null | xargs -r kill -9; {0} netns delete {1} 2>&1", ip_program(), ns));
}

// Labs of test processes that are gone: namespaces "flPID-..." whose PID no longer runs.
void delete_abandoned_labs() {
  const CommandResult list = run_command(ip_program() + " netns list 2>/dev/null");
  std::istringstream lines(list.output);
  for (std::string line; std::getline(lines, line);) {
    const std::string name = line.substr(0, line.find(' '));
    if (!name.starts_with(kLabPrefix)) continue;
    const std::size_t dash = name.find('-');
    if (dash == std::string::npos || dash == 2) continue;
    const std::string pid = name.substr(2, dash - 2);
    if (pid.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t owner = static_cast<pid_t>(std::stol(pid));
    if (::kill(owner, 0) == 0 || errno != ESRCH) continue;
    delete_namespace(name);
  }
}

}  // namespace

NetworkLab::NetworkLab(const std::vector<std::string>& hosts)
    : prefix_(fmt::format("{}{}-", kLabPrefix, ::getpid())), hosts_(hosts) {
  if (::geteuid() != 0) {
    problem_ = "network namespaces need root";
    return;
  }
  if (::access(ip_program().c_str(), X_OK) != 0) {
    problem_ = "no `ip` (iproute2; deploy/install-deps.sh installs it)";
    return;
  }
  if (hosts.size() > 200) {
    problem_ = "at most 200 hosts";
    return;
  }
  delete_abandoned_labs();
  const std::string sw = prefix_ + "switch";
  if (!ip({"netns", "add", sw})) return;
  made_.push_back(sw);
  if (!ip({"-n", sw, "link", "add", "br0", "type", "bridge"}) || !ip({"-n", sw, "link", "set", "br0", "up"})) return;
  for (std::size_t i = 0; i < hosts.size(); ++i) {
    const std::string ns = namespace_of(hosts[i]);
    if (!ip({"netns", "add", ns})) return;
    made_.push_back(ns);
    // The pair is made in the switch's namespace (names there are ours alone), one end moved to
    // the host and named eth0 there.
    const std::string port = fmt::format("p{}", i), peer = fmt::format("h{}", i);
    if (!ip({"-n", sw, "link", "add", port, "type", "veth", "peer", "name", peer}) ||
        !ip({"-n", sw, "link", "set", peer, "netns", ns}) ||
        !ip({"-n", sw, "link", "set", port, "master", "br0"}) || !ip({"-n", sw, "link", "set", port, "up"}) ||
        !ip({"-n", ns, "link", "set", peer, "name", "eth0"}) ||
        !ip({"-n", ns, "addr", "add", address(hosts[i]) + "/24", "dev", "eth0"}) ||
        !ip({"-n", ns, "link", "set", "eth0", "up"}) || !ip({"-n", ns, "link", "set", "lo", "up"})) {
      return;
    }
  }
}

NetworkLab::~NetworkLab() {
  // Hosts first, the switch last. The test has stopped its processes; any left are killed.
  for (auto it = made_.rbegin(); it != made_.rend(); ++it) delete_namespace(*it);
}

std::string NetworkLab::namespace_of(const std::string& host) const { return prefix_ + host; }

std::string NetworkLab::address(const std::string& host) const {
  const auto it = std::find(hosts_.begin(), hosts_.end(), host);
  if (it == hosts_.end()) throw std::invalid_argument("NetworkLab: no host '" + host + "'");
  return fmt::format("10.77.0.{}", (it - hosts_.begin()) + 1);
}

std::vector<std::string> NetworkLab::on(const std::string& host, const std::vector<std::string>& argv) const {
  address(host);  // a host of this lab
  std::vector<std::string> out{ip_program(), "netns", "exec", namespace_of(host)};
  out.insert(out.end(), argv.begin(), argv.end());
  return out;
}

bool NetworkLab::set_link(const std::string& host, bool up) {
  address(host);
  return ip({"-n", namespace_of(host), "link", "set", "eth0", up ? "up" : "down"});
}

bool NetworkLab::ip(const std::vector<std::string>& args) {
  std::vector<std::string> argv{ip_program()};
  argv.insert(argv.end(), args.begin(), args.end());
  const CommandResult r = run_command(quoted(argv) + " 2>&1");
  if (r.exit_code == 0) return true;
  problem_ = fmt::format("{}: exit {}: {}", quoted(argv), r.exit_code, r.output);
  return false;
}

}  // namespace farm::test
