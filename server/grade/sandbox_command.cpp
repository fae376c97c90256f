#include "server/grade/sandbox_command.h"

#include <unistd.h>

#include <algorithm>
#include <initializer_list>
#include <system_error>

namespace farm {
namespace {

namespace fs = std::filesystem;

void add(std::vector<std::string>& args, std::initializer_list<std::string> items) {
  args.insert(args.end(), items);
}

fs::path first_executable(std::initializer_list<const char*> candidates) {
  for (const char* path : candidates) {
    if (access(path, X_OK) == 0) return path;
  }
  return {};
}

std::size_t depth(const fs::path& path) { return static_cast<std::size_t>(std::distance(path.begin(), path.end())); }

// `path` is `folder` or lies under it (lexically: both absolute and normal).
bool within(const fs::path& path, const fs::path& folder) {
  const fs::path p = path.lexically_normal(), f = folder.lexically_normal();
  return std::mismatch(f.begin(), f.end(), p.begin(), p.end()).first == f.end();
}

}  // namespace

SandboxTools find_sandbox_tools() {
  // bwrap runs outside the sandbox; setpriv runs inside, so it must be one /usr holds.
  return {first_executable({"/usr/bin/bwrap", "/bin/bwrap", "/usr/local/bin/bwrap"}),
          first_executable({"/usr/bin/setpriv"})};
}

std::string check_sandbox_run(const SandboxRun& run) {
  if (run.argv.empty() || run.argv.front().empty()) return "no program to run";
  if (!run.workdir.is_absolute()) return "the working folder " + run.workdir.string() + " is not an absolute path";
  for (const SandboxMount& mount : run.mounts) {
    std::error_code ec;
    if (!fs::exists(mount.host, ec)) return "the folder to mount " + mount.host.string() + " does not exist";
    if (!mount.inside.is_absolute() || mount.inside.lexically_normal() == "/") {
      return "cannot mount " + mount.host.string() + " at " + mount.inside.string() + " (not an absolute folder below /)";
    }
  }
  return {};
}

std::vector<std::string> sandbox_command(const SandboxRun& run, const SandboxTools& tools, unsigned uid,
                                         int pid_namespace_fd) {
  std::vector<std::string> args{tools.bwrap.string(), "--pidns", std::to_string(pid_namespace_fd)};
  // Every namespace but the user one (the program gets its own uid from setpriv instead: a user
  // namespace would map it to root outside, whom RLIMIT_NPROC does not bind). bwrap (pid 1 here)
  // dies with the grader; the program gets a session of its own (no TIOCSTI into our terminal).
  add(args, {"--unshare-net", "--unshare-ipc", "--unshare-uts", "--unshare-cgroup-try", "--die-with-parent",
             "--new-session"});
  // Only what setpriv needs to change user; it drops even those before the program starts.
  add(args, {"--cap-drop", "ALL", "--cap-add", "CAP_SETUID", "--cap-add", "CAP_SETGID", "--cap-add", "CAP_SETPCAP"});

  // The system, read-only: /usr and /etc, and /bin, /lib... as they are here (symlinks into
  // /usr on a merged-/usr Debian 12, folders elsewhere). Nothing else of the host.
  add(args, {"--ro-bind", "/usr", "/usr"});
  for (const char* dir : {"/bin", "/sbin", "/lib", "/lib32", "/lib64", "/libx32"}) {
    std::error_code ec;
    const fs::file_status status = fs::symlink_status(dir, ec);
    if (ec || !fs::exists(status)) continue;
    if (fs::is_symlink(status)) {
      add(args, {"--symlink", fs::read_symlink(dir, ec).string(), dir});
    } else {
      add(args, {"--ro-bind", dir, dir});
    }
  }
  add(args, {"--ro-bind", "/etc", "/etc", "--dev", "/dev", "--proc", "/proc"});
  // A fresh /tmp, as large as its work folders may grow: tmpfs is memory, and no rlimit counts it.
  add(args, {"--perms", "1777", "--size", std::to_string(run.limits.work_folder_mib << 20), "--tmpfs", "/tmp"});

  std::vector<const SandboxMount*> mounts;
  for (const SandboxMount& mount : run.mounts) mounts.push_back(&mount);
  std::stable_sort(mounts.begin(), mounts.end(), [](const SandboxMount* a, const SandboxMount* b) {
    return depth(a->inside.lexically_normal()) < depth(b->inside.lexically_normal());
  });  // a folder before what is mounted inside it
  for (const SandboxMount* mount : mounts) {
    add(args, {mount->writable ? "--bind" : "--ro-bind", mount->host.string(), mount->inside.string()});
  }
  const bool workdir_mounted = std::any_of(mounts.begin(), mounts.end(), [&](const SandboxMount* mount) {
    return within(run.workdir, mount->inside);
  });
  if (!workdir_mounted) add(args, {"--dir", run.workdir.string()});

  // Nothing of the grader's environment: a minimal one, and the run's own.
  add(args, {"--chdir", run.workdir.string(), "--clearenv", "--setenv", "PATH", "/usr/bin:/bin", "--setenv", "HOME",
             run.workdir.string(), "--setenv", "LANG", "C.UTF-8"});
  for (const auto& [name, value] : run.environment) add(args, {"--setenv", name, value});

  const std::string id = std::to_string(uid);
  add(args, {"--", tools.setpriv.string(), "--reuid=" + id, "--regid=" + id, "--clear-groups", "--inh-caps=-all",
             "--bounding-set=-all", "--no-new-privs", "--"});
  args.insert(args.end(), run.argv.begin(), run.argv.end());
  return args;
}

}  // namespace farm
