#pragma once
// A real PostgreSQL server for one test (issue #18's store tests): Debian's `postgresql` package,
// a cluster made by initdb in a temporary folder, listening on 127.0.0.1 at a port of its own
// and on a Unix socket in that folder, stopped (fast shutdown) and removed with the object.
//
// initdb and postgres refuse to run as root, and CI runs as root: there the cluster belongs to
// the package's `postgres` user and both programs run as it (setpriv, no shell); elsewhere they
// run as the caller. The cluster trusts local connections (nothing else can reach it) and holds
// one database, `farm`, owned by the superuser `farm`. fsync is off: a test's data outlives no
// crash of the machine.
#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace farm {
class ChildProcess;
}

namespace farm::test {

// Where the server runs: this host's loopback by default; or a host of a NetworkLab (its
// programs run under `prefix`, `ip netns exec NS`, and it listens on that host's `address`).
struct PostgresPlacement {
  std::vector<std::string> prefix;
  std::string address = "127.0.0.1";
};

class PostgresServer {
 public:
  // Starts it; `problem()` says why when it did not come up within `timeout`.
  explicit PostgresServer(std::chrono::seconds timeout = std::chrono::seconds(60), PostgresPlacement placement = {});
  ~PostgresServer();
  PostgresServer(const PostgresServer&) = delete;
  PostgresServer& operator=(const PostgresServer&) = delete;

  const std::string& problem() const { return problem_; }
  // postgresql://farm@ADDRESS:PORT/farm, what `--store` takes.
  std::string url() const;
  int port() const { return port_; }
  const std::filesystem::path& data_dir() const { return data_; }
  // The server's own log so far (its stderr), for failure messages.
  std::string log() const;

  // Stops the server (fast shutdown) and waits for it; start() brings it back on the same data
  // and port (a store that goes away mid-job and comes back). Both false, with problem() set,
  // when that does not happen within the constructor's timeout.
  bool stop();
  bool start();

 private:
  std::vector<std::string> as_owner(std::vector<std::string> argv) const;

  std::chrono::seconds timeout_;
  PostgresPlacement placement_;
  std::filesystem::path root_, data_, socket_dir_;
  std::filesystem::path bin_;  // /usr/lib/postgresql/<version>/bin
  int port_ = 0;
  bool as_postgres_user_ = false;
  std::string problem_;
  std::unique_ptr<ChildProcess> server_;
};

}  // namespace farm::test
