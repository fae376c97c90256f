#!/usr/bin/env python3
"""Deploy.compose: deploy/compose.yaml hangs together, Compose tools read it, and its farm runs.

1. The file as parsed: every secret and named volume a service uses is declared (and every
   declared one used); the schedulers share one store URL, naming the postgres service and its
   port, one env_file and one data volume at their --data-dir; each service publishes only ports
   it listens on, the dashboard among them, with no host port twice; the worker names no
   container_name and no host port (so --scale works) and registers with every scheduler at the
   port it listens on; every service has a healthcheck, the farm's asking `farm health` on the
   service's own port; depends_on conditions wait on services that have one; every
   /run/secrets/NAME a command names is a secret of that service; every flag is one
   `farm <command> --help` lists.
2. The tools: deploy/compose/make-secrets.sh makes the secrets (into a copy of deploy/); then
   `docker-compose config` (Debian's docker-compose, when installed) must accept the file, and
   podman-compose (Debian's 1.0.3 has no `config`) must turn it into `podman run` commands, which
   a stand-in for podman records, with every secret mounted from a file that exists.
3. The farm it describes, run here as processes (when FARM_BINARY and PostgreSQL's server
   programs are present): PostgreSQL with the password from the secrets (scram over TCP), each
   service's command line with its secrets, volumes, env_file and ports mapped onto this machine
   (service:port to 127.0.0.1:free port; a named volume to one folder for all who mount it; each
   worker its own /tmp), two schedulers and two workers (--scale worker=2); every healthcheck
   passes; a job submitted to scheduler-b with the admin token renders bit-identical to `farm
   render`, is SUCCEEDED on scheduler-a (one store) and fetched from it identical (one data
   volume); the dashboard on scheduler-a's published port shows the job and both workers;
   SIGTERM stops every farm process with exit 0.
Prints every problem and exits 1 if there is any; parts whose tools are missing are skipped with
a note.
"""
import glob
import json
import os
import pwd
import re
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request

import yaml

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "lib"))
from command_line import flag_values  # noqa: E402

SOURCE = os.environ.get("FARM_SOURCE_DIR") or sys.exit("run through ctest, which sets FARM_SOURCE_DIR")
FARM = os.environ.get("FARM_BINARY", "")
HAVE_FARM = bool(FARM) and os.access(FARM, os.X_OK)
DEPLOY = os.path.join(SOURCE, "deploy")
COMPOSE = os.path.join(DEPLOY, "compose.yaml")
problems = []


def problem(text):
    problems.append(text)


def finish():
    if problems:
        print(f"FAIL: {len(problems)} problem(s):")
        for line in problems:
            print("  " + line)
        sys.exit(1)
    print("PASS")
    sys.exit(0)


def interpolate(text, env=None):
    """Compose's ${VAR:-default} and ${VAR}, from `env` (default: none set)."""
    env = env or {}
    return re.sub(r"\$\{(\w+)(?::?-([^}]*))?\}", lambda m: env.get(m.group(1)) or (m.group(2) or ""), text)


with open(COMPOSE) as f:
    compose = yaml.safe_load(f)
services = compose.get("services", {})


def command_of(service):
    command = service.get("command", [])
    if isinstance(command, str):
        command = shlex.split(command)
    return [interpolate(str(word)) for word in command]


def port_of(address):
    return int(address.rsplit(":", 1)[1])


def secrets_of(service):
    return [s if isinstance(s, str) else s["source"] for s in service.get("secrets", [])]


def volume_mounts(service):
    """[(source, target)] of the service's volumes (short syntax or long)."""
    mounts = []
    for v in service.get("volumes", []):
        if isinstance(v, str):
            parts = v.split(":")
            mounts.append((parts[0], parts[1] if len(parts) > 1 else parts[0]))
        else:
            mounts.append((v.get("source"), v["target"]))
    return mounts


def env_files(service):
    files = service.get("env_file", [])
    return [files] if isinstance(files, str) else list(files)


def published(service):
    """[(host ip, host port, container port)]."""
    out = []
    for p in service.get("ports", []):
        text = str(p).split("/")[0]
        parts = text.split(":")
        if len(parts) == 3:
            out.append((parts[0], int(parts[1]), int(parts[2])))
        elif len(parts) == 2:
            out.append(("0.0.0.0", int(parts[0]), int(parts[1])))
        else:
            out.append(("0.0.0.0", None, int(parts[0])))
    return out


help_cache = {}


def farm_flags(command):
    if not HAVE_FARM:
        return None
    if command not in help_cache:
        out = subprocess.run([FARM, command, "--help"], capture_output=True, text=True, timeout=60)
        help_cache[command] = set(re.findall(r"^\s+(?:-\w,)?(--[\w-]+)", out.stdout, re.M)) if out.returncode == 0 else set()
    return help_cache[command]


# ---------------------------------------------------------------- 1. the file as parsed

farm_services = {name: s for name, s in services.items() if command_of(s) and command_of(s)[0] in ("scheduler", "worker")}
schedulers = {n: s for n, s in farm_services.items() if command_of(s)[0] == "scheduler"}
workers = {n: s for n, s in farm_services.items() if command_of(s)[0] == "worker"}
stores = {n: s for n, s in services.items() if "postgres" in s.get("image", "")}
if len(schedulers) < 2:
    problem(f"two schedulers expected, found {sorted(schedulers)}")
if len(workers) != 1:
    problem(f"one worker service (scaled with --scale) expected, found {sorted(workers)}")
if len(stores) != 1:
    problem(f"one PostgreSQL service expected, found {sorted(stores)}")

declared_secrets = compose.get("secrets", {}) or {}
declared_volumes = compose.get("volumes", {}) or {}
used_secrets, used_volumes = set(), set()
for name, s in services.items():
    for secret in secrets_of(s):
        used_secrets.add(secret)
        if secret not in declared_secrets:
            problem(f"{name}: secret {secret} is not declared")
    for source, target in volume_mounts(s):
        if source and not source.startswith(("/", ".", "~")):
            used_volumes.add(source)
            if source not in declared_volumes:
                problem(f"{name}: volume {source} is not declared")
    for word in command_of(s):
        for secret in re.findall(r"/run/secrets/([\w.-]+)", word):
            if secret not in secrets_of(s):
                problem(f"{name}: its command reads /run/secrets/{secret}, which is not among its secrets")
    for key, value in (s.get("environment") or {}).items():
        for secret in re.findall(r"/run/secrets/([\w.-]+)", str(value)):
            if secret not in secrets_of(s):
                problem(f"{name}: {key} names /run/secrets/{secret}, which is not among its secrets")
for secret, spec in declared_secrets.items():
    if secret not in used_secrets:
        problem(f"secret {secret} is declared but no service uses it")
    if not (spec or {}).get("file"):
        problem(f"secret {secret} names no file (Compose without Swarm reads secrets from files)")
for volume in declared_volumes:
    if volume not in used_volumes:
        problem(f"volume {volume} is declared but no service mounts it")

# The schedulers: one store, one env_file, one data volume.
store_urls = {n: tuple(flag_values(command_of(s), "--store")) for n, s in schedulers.items()}
if len(set(store_urls.values())) != 1 or not all(store_urls.values()):
    problem(f"the schedulers' --store differ or are missing: {store_urls}")
for url in set(u for urls in store_urls.values() for u in urls):
    m = re.match(r"postgres(?:ql)?://(?:[^@/]*@)?([^:/]+):?(\d*)/", url)
    if not m or m.group(1) not in stores or int(m.group(2) or 5432) != 5432:
        problem(f"--store {url} is not the postgres service on its port 5432")
    elif ":" in url.split("://", 1)[1].split("@")[0]:
        problem(f"--store {url} holds a password; it belongs in the env_file (PGPASSWORD)")
if len({tuple(env_files(s)) for s in schedulers.values()}) != 1 or not all(env_files(s) for s in schedulers.values()):
    problem("the schedulers should read the same env_file (the store's password)")
data_volumes = {}
for n, s in schedulers.items():
    data_dirs = flag_values(command_of(s), "--data-dir")
    sources = [src for src, target in volume_mounts(s) if data_dirs and target == data_dirs[0]]
    data_volumes[n] = sources[0] if sources else None
if len(set(data_volumes.values())) != 1 or None in data_volumes.values():
    problem(f"the schedulers' --data-dir should be one shared volume: {data_volumes}")

# Ports: published ports are ones the service listens on; the dashboard is published; no host
# port twice.
listening = {}
for n, s in farm_services.items():
    argv = command_of(s)
    ports = {port_of(a) for a in flag_values(argv, "--listen")}
    http = {port_of(a) for a in flag_values(argv, "--http")}
    listening[n] = ports | http
    for address in flag_values(argv, "--listen") + flag_values(argv, "--http"):
        if address.rsplit(":", 1)[0] not in ("0.0.0.0", "[::]", "::"):
            problem(f"{n}: {address} does not listen on the container's network")
for n in stores:
    listening[n] = {5432}
host_ports = {}
dashboard_published = False
for n, s in services.items():
    for ip, host_port, container_port in published(s):
        if container_port not in listening.get(n, set()):
            problem(f"{n}: publishes container port {container_port}, which it does not listen on")
        if host_port is not None:
            if host_port in host_ports:
                problem(f"host port {host_port} is published by {host_ports[host_port]} and {n}")
            host_ports[host_port] = n
        if n in schedulers and container_port in {port_of(a) for a in flag_values(command_of(s), "--http")}:
            dashboard_published = True
if not dashboard_published:
    problem("no scheduler publishes its dashboard (--http) port")

for n, s in workers.items():
    if "container_name" in s:
        problem(f"{n}: container_name stops --scale {n}=N")
    if s.get("ports"):
        problem(f"{n}: a host port stops --scale {n}=N")
    named = set()
    for value in flag_values(command_of(s), "--scheduler"):
        for address in value.split(","):
            host, port = address.rsplit(":", 1)
            named.add(host)
            target = schedulers.get(host)
            if target is None:
                problem(f"{n}: --scheduler {address} is no scheduler service")
            elif int(port) not in {port_of(a) for a in flag_values(command_of(target), "--listen")}:
                problem(f"{n}: --scheduler {address}: {host} does not listen on {port}")
    if named != set(schedulers):
        problem(f"{n}: registers with {sorted(named)}, not every scheduler {sorted(schedulers)}")

for n, s in services.items():
    test = (s.get("healthcheck") or {}).get("test")
    if not test:
        problem(f"{n}: no healthcheck")
        continue
    if n in farm_services:
        words = test[1:] if isinstance(test, list) else shlex.split(test)
        own = {port_of(a) for a in flag_values(command_of(s), "--listen")}
        asked = [w for w in words if re.match(r"^(localhost|127\.0\.0\.1):\d+$", w)]
        if words[:2] != ["farm", "health"] or not asked or port_of(asked[0]) not in own:
            problem(f"{n}: the healthcheck should be `farm health` on its own port {sorted(own)}: {test}")
    for dependency, condition in (s.get("depends_on") or {}).items() if isinstance(s.get("depends_on"), dict) else []:
        if dependency not in services:
            problem(f"{n}: depends on {dependency}, which is no service")
        elif condition.get("condition") == "service_healthy" and not services[dependency].get("healthcheck"):
            problem(f"{n}: waits for {dependency} to be healthy, which has no healthcheck")
for n in schedulers:
    if (services[n].get("depends_on") or {}).get(next(iter(stores), ""), {}).get("condition") != "service_healthy":
        problem(f"{n}: should wait for the store to be healthy")
for n in workers:
    for scheduler in schedulers:
        if (services[n].get("depends_on") or {}).get(scheduler, {}).get("condition") != "service_healthy":
            problem(f"{n}: should wait for {scheduler} to be healthy")

for n, s in farm_services.items():
    argv = command_of(s)
    known = farm_flags(argv[0])
    if known is not None:
        for word in argv[1:]:
            if word.startswith("--") and word.split("=", 1)[0] not in known:
                problem(f"{n}: `farm {argv[0]}` has no flag {word.split('=', 1)[0]}")
    if "renderfarm" not in interpolate(s.get("image", "")):
        problem(f"{n}: image {s.get('image')} is not the farm's")
print(f"compose.yaml: {len(services)} services ({', '.join(sorted(services))}), "
      f"{len(declared_volumes)} volumes, {len(declared_secrets)} secrets, host ports {sorted(host_ports)}")

if not HAVE_FARM:
    print("note: no FARM_BINARY: make-secrets.sh, the Compose tools and the farm itself are not run")
    finish()

# ---------------------------------------------------------------- 2. the tools

tmp = tempfile.mkdtemp(prefix="farm-compose-test.")
processes = []


def cleanup():
    for process, name in processes:
        if process.poll() is None:
            # PostgreSQL's fast shutdown is SIGINT (SIGTERM waits for its clients to leave).
            process.send_signal(signal.SIGINT if name == "postgres" else signal.SIGTERM)
    deadline = time.time() + 20
    for process, _ in processes:
        try:
            process.wait(max(0.1, deadline - time.time()))
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
    shutil.rmtree(tmp, ignore_errors=True)


try:
    copy = os.path.join(tmp, "deploy")
    os.makedirs(copy)
    shutil.copy(COMPOSE, copy)
    shutil.copytree(os.path.join(DEPLOY, "compose"), os.path.join(copy, "compose"),
                    ignore=shutil.ignore_patterns("secrets"))
    secrets_dir = os.path.join(copy, "compose", "secrets")
    made = subprocess.run(["sh", os.path.join(copy, "compose", "make-secrets.sh"), secrets_dir],
                          env=dict(os.environ, FARM=FARM), capture_output=True, text=True, timeout=120)
    if made.returncode != 0:
        problem(f"make-secrets.sh failed: {made.stderr.strip()}")
        raise SystemExit
    again = subprocess.run(["sh", os.path.join(copy, "compose", "make-secrets.sh"), secrets_dir],
                           env=dict(os.environ, FARM=FARM), capture_output=True, text=True, timeout=120)
    if again.returncode == 0:
        problem("make-secrets.sh replaced existing secrets without --force")
    for secret, spec in declared_secrets.items():
        if not os.path.isfile(os.path.join(copy, spec["file"])):
            problem(f"secret {secret}: make-secrets.sh made no {spec['file']}")
    for s in schedulers.values():
        for env_file in env_files(s):
            if not os.path.isfile(os.path.join(copy, env_file)):
                problem(f"env_file {env_file}: make-secrets.sh made no such file")

    if shutil.which("docker-compose"):
        out = subprocess.run(["docker-compose", "-f", os.path.join(copy, "compose.yaml"), "config"],
                             capture_output=True, text=True, timeout=120)
        if out.returncode != 0:
            problem(f"docker-compose config refused the file: {out.stderr.strip()}")
        else:
            config = yaml.safe_load(out.stdout)
            if set(config["services"]) != set(services):
                problem(f"docker-compose config sees services {sorted(config['services'])}")
            for n in schedulers:
                if "PGPASSWORD" not in (config["services"][n].get("environment") or {}):
                    problem(f"docker-compose config: {n} gets no PGPASSWORD from its env_file")
            for secret, spec in config.get("secrets", {}).items():
                if not os.path.isfile(spec["file"]):
                    problem(f"docker-compose config: secret {secret} resolves to {spec['file']}, which does not exist")
            print(f"docker-compose config: accepted ({subprocess.run(['docker-compose', 'version', '--short'], capture_output=True, text=True).stdout.strip()})")
    else:
        print("note: docker-compose is not installed: `docker-compose config` is skipped")

    if shutil.which("podman-compose"):
        # podman-compose runs podman for everything; this stand-in records the commands instead.
        record = os.path.join(tmp, "podman-calls")
        stand_in = os.path.join(tmp, "podman")
        with open(stand_in, "w") as f:
            f.write(f"#!/bin/sh\nprintf '%s\\0' \"$@\" >>{record}\nprintf '\\n' >>{record}\n"
                    "case \"$1\" in --version|version) echo 'podman version 4.3.1';; esac\nexit 0\n")
        os.chmod(stand_in, 0o755)
        out = subprocess.run(["podman-compose", "--podman-path", stand_in, "-f", os.path.join(copy, "compose.yaml"),
                              "-p", "farmtest", "up", "-d"], capture_output=True, text=True, timeout=120, cwd=tmp)
        calls = [[w for w in line.split("\0") if w] for line in open(record).read().split("\n") if line] if os.path.exists(record) else []
        runs = {}
        for call in calls:
            if call and call[0] == "run":
                service = next((w.split("=", 1)[1] for w in call if w.startswith("com.docker.compose.service=")), None)
                runs[service] = call
        if out.returncode != 0 or set(runs) != set(services):
            problem(f"podman-compose up ran {sorted(runs)} (exit {out.returncode}): {out.stdout[-2000:]} {out.stderr[-2000:]}")
        for service, call in runs.items():
            for i, word in enumerate(call):
                if word == "--volume" and ":/run/secrets/" in call[i + 1]:
                    source = call[i + 1].split(":")[0]
                    if not os.path.isfile(os.path.join(copy, source)):
                        problem(f"podman-compose: {service} mounts secret {source}, which does not exist")
            if service in workers and "-p" in call:
                problem(f"podman-compose: {service} publishes a host port")
        print(f"podman-compose up (podman recorded, not run): {len(runs)} containers, secrets mounted from files that exist")
    else:
        print("note: podman-compose is not installed: its reading of the file is skipped")

    # ------------------------------------------------------------ 3. the farm, as processes

    pg_bin = sorted(glob.glob("/usr/lib/postgresql/*/bin/initdb"))
    try:
        postgres_user = pwd.getpwnam("postgres") if os.geteuid() == 0 else None
    except KeyError:
        postgres_user = None
    if not pg_bin:
        print("note: no PostgreSQL server programs (/usr/lib/postgresql/*/bin): the farm is not run")
        raise SystemExit
    if os.geteuid() == 0 and postgres_user is None:
        print("note: root without a postgres user to run PostgreSQL as: the farm is not run")
        raise SystemExit
    pg = os.path.dirname(pg_bin[-1])

    def free_port():
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            return s.getsockname()[1]

    def as_postgres(argv):
        if os.geteuid() == 0:
            return ["setpriv", "--reuid=postgres", "--regid=postgres", "--init-groups", "--"] + argv
        return argv

    def start(name, argv, env=None, cwd=None):
        log = open(os.path.join(tmp, f"{name}.log"), "w")
        process = subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT, env=env, cwd=cwd or tmp)
        processes.append((process, name))
        return process

    def log_of(name):
        with open(os.path.join(tmp, f"{name}.log")) as f:
            return f.read()

    def wait_for(name, process, text, count=1, seconds=90):
        deadline = time.time() + seconds
        while time.time() < deadline:
            if log_of(name).count(text) >= count:
                return True
            if process.poll() is not None:
                break
            time.sleep(0.2)
        problem(f"{name} did not say '{text}' (x{count}); its log:\n{log_of(name)[-3000:]}")
        raise SystemExit

    # PostgreSQL as the postgres service would be: user farm, database farm, the password from
    # the secret, password authentication over TCP.
    os.chmod(tmp, 0o755)
    pg_root = os.path.join(tmp, "postgres")
    os.makedirs(os.path.join(pg_root, "socket"))
    password_file = os.path.join(secrets_dir, "postgres-password")
    shutil.copy(password_file, os.path.join(pg_root, "pwfile"))
    if os.geteuid() == 0:
        for path in (pg_root, os.path.join(pg_root, "socket"), os.path.join(pg_root, "pwfile")):
            os.chown(path, postgres_user.pw_uid, postgres_user.pw_gid)
    pg_env = {k: v for k, v in services[next(iter(stores))].get("environment", {}).items()}
    pg_user = pg_env.get("POSTGRES_USER", "postgres")
    out = subprocess.run(as_postgres([f"{pg}/initdb", "--pgdata", f"{pg_root}/data", "--username", pg_user,
                                      "--pwfile", f"{pg_root}/pwfile", "--auth-local", "trust",
                                      "--auth-host", "scram-sha-256", "--encoding", "UTF8", "--locale", "C",
                                      "--no-sync"]), capture_output=True, text=True, timeout=120)
    if out.returncode != 0:
        problem(f"initdb failed: {out.stdout} {out.stderr}")
        raise SystemExit
    pg_port = free_port()
    postgres = start("postgres", as_postgres([f"{pg}/postgres", "-D", f"{pg_root}/data", "-k", f"{pg_root}/socket",
                                              "-p", str(pg_port), "-c", "listen_addresses=127.0.0.1", "-c", "fsync=off"]))
    wait_for("postgres", postgres, "database system is ready to accept connections")
    out = subprocess.run(as_postgres([f"{pg}/createdb", "--host", f"{pg_root}/socket", "--port", str(pg_port),
                                      "--username", pg_user, pg_env.get("POSTGRES_DB", pg_user)]),
                         capture_output=True, text=True, timeout=60)
    if out.returncode != 0:
        problem(f"createdb failed: {out.stderr}")
        raise SystemExit

    # Every container port a service listens on, published on this machine at a free port.
    host_port = {}
    for n in list(schedulers) + list(workers):
        for port in listening[n]:
            host_port[(n, port)] = None  # workers get theirs per replica
    for n in schedulers:
        for port in listening[n]:
            host_port[(n, port)] = free_port()
    host_port[(next(iter(stores)), 5432)] = pg_port
    volumes_dir = os.path.join(tmp, "volumes")

    def mapped(service_name, argv, own_ports):
        """The service's command line with its container's names and paths as this machine's."""
        s = services[service_name]
        out = []
        for word in argv:
            for secret in secrets_of(s):
                word = word.replace(f"/run/secrets/{secret}", os.path.join(copy, declared_secrets[secret]["file"]))
            for source, target in volume_mounts(s):
                if source in declared_volumes:
                    word = re.sub(rf"(^|=){re.escape(target)}(?=/|$)", rf"\g<1>{volumes_dir}/{source}", word)
            # Addresses: the service's own listening ones, then other services'.
            word = re.sub(r"(0\.0\.0\.0|\[::\]):(\d+)", lambda m: f"127.0.0.1:{own_ports[int(m.group(2))]}", word)
            word = re.sub(r"([a-z][\w-]*):(\d+)(?=[/,]|$)",
                          lambda m: f"127.0.0.1:{host_port[(m.group(1), int(m.group(2)))]}"
                          if (m.group(1), int(m.group(2))) in host_port else m.group(0), word)
            out.append(word)
        return out

    def env_for(service_name, extra=None):
        env = dict(os.environ)
        for env_file in env_files(services[service_name]):
            for line in open(os.path.join(copy, env_file)):
                line = line.strip()
                if line and not line.startswith("#"):
                    key, value = line.split("=", 1)
                    env[key] = value
        env.update(extra or {})
        return env

    for source in declared_volumes:
        os.makedirs(os.path.join(volumes_dir, source), exist_ok=True)
    started = {}
    for n in schedulers:
        own = {port: host_port[(n, port)] for port in listening[n]}
        argv = mapped(n, command_of(services[n]), own)
        started[n] = (start(n, [FARM] + argv, env_for(n)), own)
        wait_for(n, started[n][0], "scheduler listening on")
    replicas = 2  # docker compose up --scale worker=2
    for n in workers:
        for replica in range(1, replicas + 1):
            name = f"{n}-{replica}"
            own = {port: free_port() for port in listening[n]}
            private_tmp = os.path.join(tmp, f"{name}-tmp")  # each container's own /tmp
            os.makedirs(private_tmp)
            argv = mapped(n, command_of(services[n]), own)
            started[name] = (start(name, [FARM] + argv, env_for(n, {"TMPDIR": private_tmp})), own)
        for replica in range(1, replicas + 1):
            name = f"{n}-{replica}"
            wait_for(name, started[name][0], "registered with the scheduler", count=len(schedulers))
    print(f"the farm as processes: PostgreSQL, {', '.join(started)}; each worker registered with "
          f"{len(schedulers)} schedulers")

    # The healthchecks, as Compose would run them in each container.
    before = len(problems)
    for name, (process, own) in started.items():
        service = name.rsplit("-", 1)[0] if name not in services else name
        test = services[service]["healthcheck"]["test"]
        words = test[1:] if isinstance(test, list) else shlex.split(test)
        words = [re.sub(r"^(localhost|127\.0\.0\.1):(\d+)$", lambda m: f"127.0.0.1:{own.get(int(m.group(2)), 1)}", w)
                 for w in words]  # a port the service does not listen on is asked at port 1, where nothing answers
        out = subprocess.run([FARM] + words[1:], capture_output=True, text=True, timeout=60)
        if out.returncode != 0:
            problem(f"{name}: its healthcheck {words} failed: {out.stdout} {out.stderr}")
    if len(problems) == before:
        print("every healthcheck passes")

    # A job through scheduler-b, seen and fetched through scheduler-a.
    first, second = sorted(schedulers)[:2]
    grpc_port = {n: started[n][1][port_of(flag_values(command_of(services[n]), "--listen")[0])] for n in schedulers}
    admin = os.path.join(secrets_dir, "admin.token")
    client = os.path.join(tmp, "client")
    os.makedirs(client)
    job = os.path.join(SOURCE, "jobs", "cornell.json")
    out = subprocess.run([FARM, "submit", job, "--width", "64", "--height", "64", "--scheduler",
                          f"127.0.0.1:{grpc_port[second]}", "--token-file", admin, "--wait"],
                         capture_output=True, text=True, timeout=300, cwd=client)
    if out.returncode != 0:
        problem(f"the job submitted to {second} failed: {out.stdout} {out.stderr}")
        raise SystemExit
    job_id = out.stdout.split()[0]
    subprocess.run([FARM, "render", job, "--width", "64", "--height", "64", "--out", f"{tmp}/reference.exr",
                    "--preview", "none", "--quiet"], check=True, capture_output=True, timeout=300)
    same = subprocess.run([FARM, "compare", f"{tmp}/reference.exr", f"{client}/out/cornell.exr", "--metric", "exact"],
                          capture_output=True, text=True)
    if same.returncode != 0:
        problem(f"the job's EXR differs from farm render's: {same.stdout}")
    out = subprocess.run([FARM, "status", job_id, "--json", "--scheduler", f"127.0.0.1:{grpc_port[first]}",
                          "--token-file", admin], capture_output=True, text=True, timeout=60)
    state = json.loads(out.stdout).get("state") if out.returncode == 0 else out.stderr
    if "SUCCEEDED" not in str(state):
        problem(f"{first} does not see the job {second} ran as succeeded (one store?): {state}")
    fetched = os.path.join(tmp, "fetched")
    out = subprocess.run([FARM, "fetch", job_id, "-o", fetched, "--scheduler", f"127.0.0.1:{grpc_port[first]}",
                          "--token-file", admin], capture_output=True, text=True, timeout=120)
    exrs = glob.glob(os.path.join(fetched, "*.exr"))
    if out.returncode != 0 or not exrs or subprocess.run(
            [FARM, "compare", f"{tmp}/reference.exr", exrs[0], "--metric", "exact"], capture_output=True).returncode != 0:
        problem(f"{first} could not serve the result {second} made (one data volume?): {out.stderr}")
    print(f"a job submitted to {second} is bit-identical to farm render, SUCCEEDED on {first}, and fetched from it identical")

    # The dashboard, on the port the first scheduler publishes.
    http_port = port_of(flag_values(command_of(services[first]), "--http")[0])
    if not any(cp == http_port for _, _, cp in published(services[first])):
        problem(f"{first} does not publish its dashboard port")
    base = f"http://127.0.0.1:{started[first][1][http_port]}"
    token = open(admin).read().strip()

    def get(path):
        request = urllib.request.Request(base + path, headers={"Authorization": f"Bearer {token}"})
        with urllib.request.urlopen(request, timeout=30) as response:
            return json.loads(response.read())

    job_json = get(f"/api/v1/jobs/{job_id}")
    workers_json = get("/api/v1/workers")
    if job_id not in json.dumps(job_json) or "SUCCEEDED" not in json.dumps(job_json):
        problem(f"the dashboard of {first} does not show the job: {job_json}")
    worker_list = workers_json.get("workers", workers_json) if isinstance(workers_json, dict) else workers_json
    if len(worker_list) != replicas:
        problem(f"the dashboard of {first} lists {len(worker_list)} workers, not {replicas}: {workers_json}")
    print(f"the dashboard of {first} shows the job and {replicas} workers")

    # docker compose stop: SIGTERM; each farm process leaves cleanly.
    for name, (process, _) in started.items():
        process.send_signal(signal.SIGTERM)
    for name, (process, _) in started.items():
        try:
            code = process.wait(60)
        except subprocess.TimeoutExpired:
            code = "still running after 60 s"
        if code != 0:
            problem(f"{name}: exit {code} after SIGTERM; its log:\n{log_of(name)[-2000:]}")
    print("SIGTERM stopped every farm process with exit 0")
except SystemExit:
    pass
finally:
    cleanup()
finish()
