#include "tests/support/postgres_server.h"

#include <arpa/inet.h>
#include <fmt/format.h>
#include <netinet/in.h>
#include <pwd.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <optional>
#include <system_error>
#include <vector>

#include "server/common/child_process.h"

namespace farm::test {

namespace fs = std::filesystem;

namespace {

// Debian installs each major version's server programs under /usr/lib/postgresql/<major>/bin:
// the newest there.
fs::path server_programs() {
  fs::path best;
  int best_version = -1;
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator("/usr/lib/postgresql", ec)) {
    const std::string name = e.path().filename().string();
    if (name.empty() || name.find_first_not_of("0123456789") != std::string::npos) continue;
    if (!fs::exists(e.path() / "bin" / "initdb") || !fs::exists(e.path() / "bin" / "postgres")) continue;
    if (const int v = std::atoi(name.c_str()); v > best_version) {
      best_version = v;
      best = e.path() / "bin";
    }
  }
  return best;
}

// A port nobody listens on now (the kernel's pick for a socket bound to port 0).
int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return 0;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t size = sizeof a;
  int port = 0;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &size) == 0) {
    port = ntohs(a.sin_port);
  }
  ::close(fd);
  return port;
}

// Runs `argv` to its end: its exit code (nullopt past `timeout`) and what it said.
std::optional<int> run(const std::vector<std::string>& argv, std::chrono::seconds timeout, std::string& said) {
  ChildProcess child(argv);
  const std::optional<int> code = child.wait_exit(timeout);
  said = child.output_to_end(std::chrono::seconds(2));
  return code;
}

}  // namespace

PostgresServer::PostgresServer(std::chrono::seconds timeout, PostgresPlacement placement)
    : timeout_(timeout), placement_(std::move(placement)) {
  bin_ = server_programs();
  if (bin_.empty()) {
    problem_ = "no PostgreSQL server programs under /usr/lib/postgresql/<version>/bin (Debian's postgresql "
               "package; deploy/install-deps.sh installs it)";
    return;
  }
  as_postgres_user_ = ::geteuid() == 0;
  std::string pattern = (fs::temp_directory_path() / "farm-pg-XXXXXX").string();
  if (!::mkdtemp(pattern.data())) {
    problem_ = "cannot make a temporary folder for the cluster";
    return;
  }
  root_ = pattern;
  data_ = root_ / "data";
  socket_dir_ = root_ / "socket";
  fs::create_directories(socket_dir_);
  if (as_postgres_user_) {
    const passwd* user = ::getpwnam("postgres");
    if (!user) {
      problem_ = "running as root, and there is no 'postgres' user to run the server as (Debian's postgresql package makes it)";
      return;
    }
    for (const fs::path& p : {root_, socket_dir_}) {
      if (::chown(p.c_str(), user->pw_uid, user->pw_gid) != 0) {
        problem_ = fmt::format("cannot give {} to the postgres user", p.string());
        return;
      }
    }
  }
  std::string said;
  const std::optional<int> made = run(as_owner({(bin_ / "initdb").string(), "--pgdata", data_.string(), "--username",
                                                "farm", "--auth", "trust", "--encoding", "UTF8", "--locale", "C",
                                                "--no-sync"}),
                                      timeout_, said);
  if (made != 0) {
    problem_ = "initdb failed: " + said;
    return;
  }
  if (placement_.address != "127.0.0.1") {
    // Clients on the other hosts of its network (a NetworkLab's) are trusted too.
    std::ofstream hba(data_ / "pg_hba.conf", std::ios::app);
    hba << "host all all samenet trust\n";
    if (!hba.flush()) {
      problem_ = "cannot add the network to pg_hba.conf";
      return;
    }
  }
  port_ = free_port();
  if (port_ == 0) {
    problem_ = "no free port on 127.0.0.1";
    return;
  }
  if (!start()) return;
  const std::optional<int> created = run({(bin_ / "createdb").string(), "--host", socket_dir_.string(), "--port",
                                          std::to_string(port_), "--username", "farm", "farm"},
                                         timeout_, said);
  if (created != 0) problem_ = "createdb failed: " + said;
}

PostgresServer::~PostgresServer() {
  if (server_) stop();
  std::error_code ignored;
  if (!root_.empty()) fs::remove_all(root_, ignored);
}

std::vector<std::string> PostgresServer::as_owner(std::vector<std::string> argv) const {
  std::vector<std::string> wrapped = placement_.prefix;
  if (as_postgres_user_) {
    wrapped.insert(wrapped.end(), {"/usr/bin/setpriv", "--reuid=postgres", "--regid=postgres", "--init-groups", "--"});
  }
  wrapped.insert(wrapped.end(), argv.begin(), argv.end());
  return wrapped;
}

std::string PostgresServer::url() const {
  return fmt::format("postgresql://farm@{}:{}/farm", placement_.address, port_);
}

std::string PostgresServer::log() const { return server_ ? server_->output() : std::string(); }

bool PostgresServer::start() {
  if (server_) return true;
  server_ = std::make_unique<ChildProcess>(as_owner(
      {(bin_ / "postgres").string(), "-D", data_.string(), "-k", socket_dir_.string(), "-p", std::to_string(port_),
       "-c", "listen_addresses=" + placement_.address, "-c", "fsync=off", "-c", "max_connections=200"}));
  if (!server_->wait_for_line("database system is ready to accept connections", timeout_)) {
    problem_ = "the PostgreSQL server did not come up: " + server_->output();
    server_.reset();
    return false;
  }
  return true;
}

bool PostgresServer::stop() {
  if (!server_) return true;
  server_->send_signal(SIGINT);  // fast shutdown: clients cut off, the data consistent
  const std::optional<int> code = server_->wait_exit(timeout_);
  if (!code) problem_ = "the PostgreSQL server did not stop: " + server_->output();
  server_.reset();  // killed if still running
  return code.has_value();
}

}  // namespace farm::test
