#pragma once
// Several hosts on one machine, for a test of a farm spread over a network (issue #18): each host
// a network namespace of its own with its loopback and one link, eth0, at 10.77.0.N/24, cabled by
// a veth pair to a bridge that lives in a namespace of its own too. Nothing is added to the
// machine's own network: the hosts reach each other and nothing else, and deleting the
// namespaces takes their links and the bridge with them. The destructor deletes them (killing
// anything still running in them), and a lab left behind by a test process that died (its pid
// gone) is deleted, its servers killed, by the next one.
//
// Needs root (CAP_SYS_ADMIN and CAP_NET_ADMIN) and iproute2's `ip`; problem() says why not.
// Processes on a host run under on(host, argv): `ip netns exec NAMESPACE argv...`, which execs
// argv in place, so the child's pid is the program's own (a signal reaches it).
#include <string>
#include <vector>

namespace farm::test {

class NetworkLab {
 public:
  explicit NetworkLab(const std::vector<std::string>& hosts);
  ~NetworkLab();
  NetworkLab(const NetworkLab&) = delete;
  NetworkLab& operator=(const NetworkLab&) = delete;

  const std::string& problem() const { return problem_; }
  // The host's address on the lab's network, "10.77.0.N".
  std::string address(const std::string& host) const;
  // `argv` run on the host.
  std::vector<std::string> on(const std::string& host, const std::vector<std::string>& argv) const;
  // Takes the host's link down or brings it back up (a cable pulled and plugged in again);
  // false, with problem() set, when `ip` refused.
  bool set_link(const std::string& host, bool up);

 private:
  std::string namespace_of(const std::string& host) const;
  bool ip(const std::vector<std::string>& args);  // `ip args...`; false and problem_ set on failure

  std::string prefix_;  // "flPID-": this lab's namespaces
  std::vector<std::string> hosts_;
  std::vector<std::string> made_;  // namespaces made, deleted in the destructor
  std::string problem_;
};

}  // namespace farm::test
