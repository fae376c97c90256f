#!/usr/bin/env python3
"""Deploy.kubernetes: deploy/k8s renders with kustomize, and what it renders hangs together.

Renders `kubectl kustomize deploy/k8s` with the kubectl on PATH and with each one named in
FARM_EXTRA_KUBECTL (colon-separated paths, e.g. Debian 12's kubernetes-client 1.20, whose
kustomize is v2.0.3); without any kubectl the manifest files are assembled here instead (the
secretGenerator and images: entries applied by hand), and that part is said to be skipped. On
every rendering it checks:
  - each workload's selector matches its pod template's labels; each Service's and
    PodDisruptionBudget's selector matches some workload's pods, and each Service port's
    targetPort (name or number) is a port of every container behind it;
  - every container has requests and limits of CPU and memory, requests within limits;
  - every container of a Deployment or StatefulSet has liveness and readiness probes on one of
    its own ports; the scheduler's and the worker's are native gRPC probes on the port the farm
    listens on (--listen);
  - every volume names an existing PersistentVolumeClaim, Secret (and its keys) or ConfigMap;
    every mount names a volume; every secretKeyRef an existing key; every file a farm container
    is given under a Secret's mount (--tokens, --token-file) is a key that Secret projects there;
  - every address a farm container is given (--scheduler, --store) is a Service of this
    deployment, on one of its ports, selecting pods that run what is asked for there;
  - every `$(VAR)` in a container's args is one of its env variables;
  - every flag a farm container is given is one `farm <command> --help` lists (FARM_BINARY);
  - the HorizontalPodAutoscaler (autoscaling/v2) scales an existing Deployment on CPU, and that
    Deployment leaves its replica count to it;
  - the scheduler runs 2 replicas, its data dir on a ReadWriteMany claim; the regress Job's suite
    is one the .deb ships (jobs/ of this tree, installed as /usr/share/renderfarm/jobs);
  - the placeholder secrets fail safe: `farm scheduler` refuses the placeholder tokens file and
    `farm worker` the placeholder token.
Then (with FARM_BINARY) it runs what the rendering says to run, here: the scheduler's, the worker's
and the regress Job's command lines with their env, volumes (Secrets as the keys they project,
from deploy/compose/make-secrets.sh), working folder and Service addresses mapped onto this
machine; the worker must register, the Job's init container end, and `farm regress` pass the
example suite (jobs/regress/engines.json, as the image ships it) against them; SIGTERM must stop
both with exit 0. (One scheduler, on SQLite: tests/deploy/compose_test.py runs two on PostgreSQL.)
Prints every problem found and exits 1 if there is any.
"""
import copy
import os
import re
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

import yaml

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "lib"))
from command_line import flag_values  # noqa: E402

SOURCE = os.environ.get("FARM_SOURCE_DIR") or sys.exit("run through ctest, which sets FARM_SOURCE_DIR")
FARM = os.environ.get("FARM_BINARY", "")
K8S = os.path.join(SOURCE, "deploy", "k8s")
WORKLOAD_KINDS = ("Deployment", "StatefulSet", "DaemonSet", "Job")
LONG_RUNNING = ("Deployment", "StatefulSet", "DaemonSet")
# What kustomize v2.0.3 (kubectl 1.20) knows of, among what this deployment may use.
OLD_KUSTOMIZE_FIELDS = {"apiVersion", "kind", "resources", "images", "secretGenerator",
                        "configMapGenerator", "generatorOptions", "commonLabels",
                        "commonAnnotations", "namespace", "namePrefix", "nameSuffix"}
SHELLS = ("/bin/sh", "sh", "/bin/bash", "bash")

problems = []


def problem(where, text):
    problems.append(f"{where}: {text}")


def name_of(doc):
    return f"{doc.get('kind')}/{doc.get('metadata', {}).get('name')}"


# ---------------------------------------------------------------- the manifest files themselves

with open(os.path.join(K8S, "kustomization.yaml")) as f:
    kustomization = yaml.safe_load(f)
for field in sorted(set(kustomization) - OLD_KUSTOMIZE_FIELDS):
    problem("kustomization.yaml", f"'{field}' is unknown to kustomize v2.0.3 (Debian 12's kubectl)")
listed = kustomization.get("resources", [])
file_docs = []
for resource in listed:
    path = os.path.join(K8S, resource)
    if not os.path.isfile(path):
        problem("kustomization.yaml", f"resource '{resource}' is not a file (kustomize v2.0.3 takes files only)")
        continue
    with open(path) as f:
        for doc in yaml.safe_load_all(f):
            if doc is None:
                continue
            for key in ("apiVersion", "kind"):
                if not doc.get(key):
                    problem(resource, f"a document without {key}")
            if not doc.get("metadata", {}).get("name"):
                problem(resource, f"{doc.get('kind')} without metadata.name")
            file_docs.append(doc)
for entry in sorted(os.listdir(K8S)):
    if entry.endswith((".yaml", ".yml")) and entry != "kustomization.yaml" and entry not in listed:
        problem("kustomization.yaml", f"{entry} is not among its resources")


def assembled_here():
    """The rendering without kubectl: the files, the generated Secrets and the images rewritten."""
    docs = copy.deepcopy(file_docs)
    for generator in kustomization.get("secretGenerator", []):
        data = {}
        for entry in generator.get("files", []):
            key, _, path = entry.rpartition("=")
            data[key or os.path.basename(path)] = ""
            if not os.path.isfile(os.path.join(K8S, path)):
                problem("kustomization.yaml", f"secretGenerator {generator['name']}: {path} is missing")
        for literal in generator.get("literals", []):
            data[literal.split("=", 1)[0]] = ""
        docs.append({"apiVersion": "v1", "kind": "Secret", "metadata": {"name": generator["name"]}, "data": data})
    for doc in docs:
        for container in containers_of(doc):
            for image in kustomization.get("images", []):
                if container.get("image", "").split(":")[0] == image["name"]:
                    container["image"] = f"{image.get('newName', image['name'])}:{image.get('newTag', 'latest')}"
    return docs


# ---------------------------------------------------------------- helpers over rendered documents

def pod_spec(doc):
    return doc.get("spec", {}).get("template", {}).get("spec", {})


def pod_labels(doc):
    return doc.get("spec", {}).get("template", {}).get("metadata", {}).get("labels", {}) or {}


def containers_of(doc, init=True):
    if doc.get("kind") not in WORKLOAD_KINDS:
        return []
    spec = pod_spec(doc)
    return list(spec.get("containers", [])) + (list(spec.get("initContainers", [])) if init else [])


def farm_argv(container):
    """The farm command lines a container runs: [[subcommand, args...], ...]."""
    command = container.get("command") or []
    args = container.get("args") or []
    if command and command[0] in SHELLS and "-c" in command:
        script = command[command.index("-c") + 1]
        lexer = shlex.shlex(script, posix=True, punctuation_chars=True)
        lexer.whitespace_split = True
        words = list(lexer)
        lines = []
        for i, word in enumerate(words):
            if word in ("farm", "/usr/bin/farm"):
                line = []
                for w in words[i + 1:]:
                    if w in (";", "&&", "||", "|", "do", "done", "then", "fi"):
                        break
                    line.append(w)
                lines.append(line)
        return lines
    if command and os.path.basename(command[0]) == "farm":
        return [command[1:] + args]
    if not command and "renderfarm" in container.get("image", ""):
        return [args]  # the image's entrypoint is farm
    return []


def listen_port(argv):
    for value in flag_values(argv, "--listen"):
        return int(value.rsplit(":", 1)[1])
    return None


def quantity(text):
    text = str(text)
    units = {"m": 1e-3, "Ki": 2**10, "Mi": 2**20, "Gi": 2**30, "Ti": 2**40, "k": 1e3, "M": 1e6, "G": 1e9}
    for suffix, factor in units.items():
        if text.endswith(suffix):
            return float(text[: -len(suffix)]) * factor
    return float(text)


def matches(selector, labels):
    return bool(selector) and all(labels.get(k) == v for k, v in selector.items())


help_cache = {}


def farm_flags(subcommand):
    """The flags `farm SUBCOMMAND --help` lists; None without a farm binary."""
    if not FARM or not os.access(FARM, os.X_OK):
        return None
    if subcommand not in help_cache:
        out = subprocess.run([FARM, subcommand, "--help"], capture_output=True, text=True, timeout=60)
        help_cache[subcommand] = set(re.findall(r"^\s+(?:-\w,)?(--[\w-]+)", out.stdout, re.M)) if out.returncode == 0 else set()
    return help_cache[subcommand]


# ---------------------------------------------------------------- the checks over one rendering

def check_rendering(docs, where):
    def p(text):
        problem(where, text)

    by_kind = {}
    for doc in docs:
        by_kind.setdefault(doc["kind"], {})[doc["metadata"]["name"]] = doc
    workloads = [d for d in docs if d["kind"] in WORKLOAD_KINDS]
    services = by_kind.get("Service", {})
    secrets = by_kind.get("Secret", {})
    claims = by_kind.get("PersistentVolumeClaim", {})
    config_maps = by_kind.get("ConfigMap", {})

    # Selectors and labels.
    for w in workloads:
        selector = w["spec"].get("selector")
        if selector is None:
            if w["kind"] != "Job":
                p(f"{name_of(w)} has no selector")
        elif not matches(selector.get("matchLabels"), pod_labels(w)) or selector.get("matchExpressions"):
            p(f"{name_of(w)}: selector {selector} does not match its pod labels {pod_labels(w)}")
    for pdb in by_kind.get("PodDisruptionBudget", {}).values():
        selector = pdb["spec"].get("selector", {}).get("matchLabels")
        if not any(matches(selector, pod_labels(w)) for w in workloads):
            p(f"{name_of(pdb)}: selector {selector} matches no workload's pods")

    def workloads_behind(service):
        return [w for w in workloads if matches(service["spec"].get("selector"), pod_labels(w))]

    for s in services.values():
        behind = workloads_behind(s)
        if not behind:
            p(f"{name_of(s)}: selector {s['spec'].get('selector')} matches no workload's pods")
        for port in s["spec"].get("ports", []):
            target = port.get("targetPort", port["port"])
            for w in behind:
                found = any(cp.get("name") == target if isinstance(target, str) else cp.get("containerPort") == target
                            for c in containers_of(w, init=False) for cp in c.get("ports", []))
                if not found:
                    p(f"{name_of(s)} port {port.get('name', port['port'])}: targetPort {target} is no container port of {name_of(w)}")
    for w in by_kind.get("StatefulSet", {}).values():
        governing = services.get(w["spec"].get("serviceName"))
        if governing is None or governing["spec"].get("clusterIP") != "None" or w not in workloads_behind(governing):
            p(f"{name_of(w)}: serviceName {w['spec'].get('serviceName')} is not a headless Service selecting its pods")

    # Resources, probes, volumes, env, the farm's own arguments.
    for w in workloads:
        spec = pod_spec(w)
        volumes = {v["name"]: v for v in spec.get("volumes", [])}
        templates = {t["metadata"]["name"] for t in w["spec"].get("volumeClaimTemplates", [])}
        for v in volumes.values():
            if "persistentVolumeClaim" in v and v["persistentVolumeClaim"]["claimName"] not in claims:
                p(f"{name_of(w)} volume {v['name']}: no PersistentVolumeClaim {v['persistentVolumeClaim']['claimName']}")
            if "secret" in v:
                secret = secrets.get(v["secret"]["secretName"])
                if secret is None:
                    p(f"{name_of(w)} volume {v['name']}: no Secret {v['secret']['secretName']}")
                else:
                    keys = set((secret.get("data") or {}) | (secret.get("stringData") or {}))
                    for item in v["secret"].get("items", []):
                        if item["key"] not in keys:
                            p(f"{name_of(w)} volume {v['name']}: Secret {v['secret']['secretName']} has no key {item['key']}")
            if "configMap" in v and v["configMap"]["name"] not in config_maps:
                p(f"{name_of(w)} volume {v['name']}: no ConfigMap {v['configMap']['name']}")
        for c in containers_of(w):
            here = f"{name_of(w)} container {c['name']}"
            resources = c.get("resources", {})
            for kind in ("requests", "limits"):
                for resource in ("cpu", "memory"):
                    if resource not in resources.get(kind, {}):
                        p(f"{here}: no {kind}.{resource}")
            for resource in ("cpu", "memory"):
                try:
                    if quantity(resources["requests"][resource]) > quantity(resources["limits"][resource]):
                        p(f"{here}: {resource} request above its limit")
                except KeyError:
                    pass
            env = {e["name"]: e for e in c.get("env", [])}
            for e in env.values():
                ref = e.get("valueFrom", {}).get("secretKeyRef")
                if ref:
                    secret = secrets.get(ref["name"])
                    if secret is None or ref["key"] not in (secret.get("data") or {}):
                        p(f"{here}: env {e['name']} names Secret {ref['name']} key {ref['key']}, which does not exist")
            for word in c.get("args", []) + c.get("command", []):
                for var in re.findall(r"\$\((\w+)\)", word):
                    if var not in env:
                        p(f"{here}: $({var}) in its arguments is none of its env variables")
            mounts = {}
            for m in c.get("volumeMounts", []):
                if m["name"] not in volumes and m["name"] not in templates:
                    p(f"{here}: mount {m['name']} names no volume")
                mounts[m["mountPath"]] = volumes.get(m["name"], {"name": m["name"], "template": True})
            ports = {cp.get("name"): cp["containerPort"] for cp in c.get("ports", [])}
            if w["kind"] in LONG_RUNNING and c in spec.get("containers", []):
                for probe_kind in ("livenessProbe", "readinessProbe"):
                    probe = c.get(probe_kind)
                    if not probe:
                        p(f"{here}: no {probe_kind}")
                        continue
                    for handler in ("grpc", "httpGet", "tcpSocket"):
                        if handler in probe:
                            port = probe[handler]["port"]
                            if port not in ports.values() and port not in ports:
                                p(f"{here}: {probe_kind} asks port {port}, none of its own")
            for argv in farm_argv(c):
                if not argv:
                    p(f"{here}: runs farm with no command")
                    continue
                command = argv[0]
                known = farm_flags(command)
                if known is not None:
                    if not known:
                        p(f"{here}: `farm {command}` is no farm command")
                    for word in argv[1:]:
                        if word.startswith("--") and word.split("=", 1)[0] not in known:
                            p(f"{here}: `farm {command}` has no flag {word.split('=', 1)[0]}")
                # Files under a Secret's mount must be keys the Secret puts there.
                for word in argv[1:]:
                    value = word.split("=", 1)[1] if word.startswith("--") and "=" in word else word
                    for mount_path, volume in mounts.items():
                        if value.startswith(mount_path.rstrip("/") + "/") and "secret" in volume:
                            inside = value[len(mount_path.rstrip("/")) + 1:]
                            items = volume["secret"].get("items")
                            secret = secrets.get(volume["secret"]["secretName"], {})
                            present = {i["path"] for i in items} if items else set(secret.get("data") or {})
                            if inside not in present:
                                p(f"{here}: {value} is not in the Secret mounted at {mount_path}")
                # Addresses: Services of this deployment, on their ports, in front of the right pods.
                if command == "scheduler":
                    for url in flag_values(argv, "--store"):
                        m = re.match(r"postgres(?:ql)?://(?:[^@/]*@)?([^:/]+):?(\d*)/", url)
                        host, port = m.group(1), int(m.group(2) or 5432)
                        check_address(p, here, "--store", host, port, services, workloads_behind, None, 5432)
                for value in flag_values(argv, "--scheduler"):
                    for address in value.split(","):
                        host, _, port = address.rpartition(":")
                        check_address(p, here, "--scheduler", host, int(port), services, workloads_behind, "scheduler", None)
                if command in ("scheduler", "worker"):
                    listen = listen_port(argv)
                    if listen not in ports.values():
                        p(f"{here}: listens on {listen}, which is not among its container ports")
                    if w["kind"] in LONG_RUNNING:
                        for probe_kind in ("livenessProbe", "readinessProbe"):
                            probe = c.get(probe_kind) or {}
                            if probe.get("grpc", {}).get("port") != listen:
                                p(f"{here}: {probe_kind} is not a native gRPC probe on the farm's port {listen}")
                if command == "scheduler":
                    if w["kind"] != "Deployment" or w["spec"].get("replicas") != 2:
                        p(f"{here}: the scheduler should be a Deployment of 2 replicas")
                    for data_dir in flag_values(argv, "--data-dir"):
                        volume = mounts.get(data_dir, {})
                        claim = claims.get(volume.get("persistentVolumeClaim", {}).get("claimName"))
                        if claim is None or "ReadWriteMany" not in claim["spec"].get("accessModes", []):
                            p(f"{here}: --data-dir {data_dir} is not on a ReadWriteMany claim")
                if command == "regress":
                    suite = argv[1]
                    prefix = "/usr/share/renderfarm/jobs/"
                    if not suite.startswith(prefix) or not os.path.isfile(os.path.join(SOURCE, "jobs", suite[len(prefix):])):
                        p(f"{here}: suite {suite} is not one of jobs/ as the .deb installs them ({prefix})")
            if "renderfarm" in c.get("image", "") and where != "assembled" and ":" not in c["image"].rsplit("/", 1)[-1]:
                p(f"{here}: image {c['image']} was not rewritten by kustomization.yaml's images:")

    # Autoscaling.
    hpas = by_kind.get("HorizontalPodAutoscaler", {})
    if not hpas:
        p("no HorizontalPodAutoscaler")
    for h in hpas.values():
        if h["apiVersion"] != "autoscaling/v2":
            p(f"{name_of(h)}: apiVersion {h['apiVersion']}, not autoscaling/v2")
        ref = h["spec"]["scaleTargetRef"]
        target = by_kind.get(ref["kind"], {}).get(ref["name"])
        if target is None or ref["kind"] != "Deployment":
            p(f"{name_of(h)}: scales {ref['kind']}/{ref['name']}, which is no Deployment here")
        elif "replicas" in target["spec"]:
            p(f"{name_of(h)}: {name_of(target)} sets replicas, which every apply would reset under the autoscaler")
        if not any(m.get("type") == "Resource" and m["resource"]["name"] == "cpu" for m in h["spec"].get("metrics", [])):
            p(f"{name_of(h)}: no CPU metric")
        if h["spec"].get("minReplicas", 1) > h["spec"]["maxReplicas"]:
            p(f"{name_of(h)}: minReplicas above maxReplicas")


def check_address(p, here, flag, host, port, services, workloads_behind, role, container_port):
    service = services.get(host.split(".")[0])
    if service is None:
        p(f"{here}: {flag} {host}:{port} names no Service of this deployment")
        return
    port_entry = next((sp for sp in service["spec"].get("ports", []) if sp["port"] == port), None)
    if port_entry is None:
        p(f"{here}: {flag} {host}:{port}: Service {host} has no port {port}")
        return
    target = port_entry.get("targetPort", port)
    for w in workloads_behind(service):
        for c in containers_of(w, init=False):
            runs = [argv[0] for argv in farm_argv(c) if argv]
            ports = {cp.get("name"): cp["containerPort"] for cp in c.get("ports", [])}
            number = ports.get(target) if isinstance(target, str) else target
            if number not in ports.values():
                continue
            if role is not None:
                if role not in runs:
                    p(f"{here}: {flag} {host}:{port} reaches {name_of(w)}, which does not run `farm {role}`")
                else:
                    argv = next(a for a in farm_argv(c) if a and a[0] == role)
                    if listen_port(argv) != number:
                        p(f"{here}: {flag} {host}:{port} reaches port {number}, not the one `farm {role}` listens on")
            elif number != container_port:
                p(f"{here}: {flag} {host}:{port} reaches port {number}, not {container_port}")


# ---------------------------------------------------------------- rendering

kubectls, rendered = [], None
if shutil.which("kubectl"):
    kubectls.append(shutil.which("kubectl"))
kubectls += [k for k in os.environ.get("FARM_EXTRA_KUBECTL", "").split(":") if k]
for kubectl in kubectls:
    version = subprocess.run([kubectl, "version", "--client"], capture_output=True, text=True).stdout.splitlines()
    label = f"{kubectl} ({' '.join(version[:2]).strip()})"
    out = subprocess.run([kubectl, "kustomize", K8S], capture_output=True, text=True, timeout=300)
    if out.returncode != 0:
        problem(label, f"kubectl kustomize failed: {out.stderr.strip()}")
        continue
    docs = [d for d in yaml.safe_load_all(out.stdout) if d]
    rendered = rendered or docs
    print(f"{label}: rendered {len(docs)} documents: " + ", ".join(sorted(name_of(d) for d in docs)))
    check_rendering(docs, label)
if not kubectls:
    print("note: kubectl is not installed; the rendering by kustomize is skipped, the files are checked as assembled here")
check_rendering(assembled_here(), "assembled")

# ---------------------------------------------------------------- the placeholders fail safe

secrets_dir = os.path.join(K8S, "secrets")


def refuses(argv, expected):
    """The farm exits non-zero, saying `expected`, instead of serving."""
    try:
        out = subprocess.run(argv, capture_output=True, text=True, timeout=60)
    except subprocess.TimeoutExpired:
        return "it kept running"
    said = out.stdout + out.stderr
    if out.returncode == 0 or expected not in said:
        return f"exit {out.returncode}: {said.strip()}"
    return None


with open(os.path.join(secrets_dir, "tokens")) as f:
    placeholders = "PLACEHOLDER" in f.read()
if not placeholders:
    print("note: deploy/k8s/secrets holds real secrets (make-secrets.sh ran): the placeholder checks are skipped")
elif not FARM or not os.access(FARM, os.X_OK):
    print("note: no FARM_BINARY: the placeholder checks are skipped")
else:
    with tempfile.TemporaryDirectory(prefix="farm-k8s-test.") as tmp:
        why = refuses([FARM, "scheduler", "--listen", "127.0.0.1:0", "--data-dir", tmp,
                       "--tokens", os.path.join(secrets_dir, "tokens")], "lists no tokens")
        if why:
            problem("secrets/tokens", f"farm scheduler did not refuse the placeholder: {why}")
        why = refuses([FARM, "worker", "--listen", "127.0.0.1:0", "--cache-dir", tmp,
                       "--token-file", os.path.join(secrets_dir, "worker.token")], "not a farm token")
        if why:
            problem("secrets/worker.token", f"farm worker did not refuse the placeholder: {why}")
    print("the placeholder secrets: farm scheduler and farm worker refuse them")
    if os.path.getsize(os.path.join(secrets_dir, "postgres-password")) != 0:
        problem("secrets/postgres-password", "the placeholder should be empty, which the postgres image refuses")

# ---------------------------------------------------------------- the farm as the manifests run it

def run_as_manifests(docs):
    """The scheduler, worker and regress containers' command lines, run here as the pods would run
    them: env (the pod IP as 127.0.0.1, the CPU limit as a number) in $(VAR), each volume as a
    folder (a Secret's as the keys it projects, from make-secrets.sh; a claim's shared by all who
    mount it), workingDir, and every address as this machine's (a Service's name to the port of
    the process behind it). One scheduler replica, on SQLite: a cluster's PostgreSQL is not here
    (tests/deploy/compose_test.py runs two schedulers on one). The regress Job, its init container
    first, must pass against them."""
    tmp = tempfile.mkdtemp(prefix="farm-k8s-run.")
    running = []
    try:
        secrets_made = os.path.join(tmp, "secrets")
        out = subprocess.run(["sh", os.path.join(SOURCE, "deploy", "compose", "make-secrets.sh"), secrets_made],
                             env=dict(os.environ, FARM=FARM), capture_output=True, text=True, timeout=120)
        if out.returncode != 0:
            problem("make-secrets.sh", out.stderr.strip())
            return
        by_kind = {}
        for doc in docs:
            by_kind.setdefault(doc["kind"], {})[doc["metadata"]["name"]] = doc
        generated = {}  # a generated Secret's name (with its hash) -> the files it was made from
        for generator in kustomization.get("secretGenerator", []):
            for name in by_kind.get("Secret", {}):
                if name == generator["name"] or name.startswith(generator["name"] + "-"):
                    generated[name] = {e.rpartition("=")[0] or os.path.basename(e): os.path.basename(e.rpartition("=")[2])
                                       for e in generator.get("files", [])}
        ports = {}  # (Service name, port) -> the local port behind it

        def free_port():
            with socket.socket() as s:
                s.bind(("127.0.0.1", 0))
                return s.getsockname()[1]

        def prepare(workload, container, label):
            """(argv, cwd) for one container, its volumes made as folders."""
            spec = pod_spec(workload)
            env = {}
            for e in container.get("env", []):
                source = e.get("valueFrom", {})
                if "value" in e:
                    env[e["name"]] = e["value"]
                elif source.get("fieldRef", {}).get("fieldPath") == "status.podIP":
                    env[e["name"]] = "127.0.0.1"
                elif "resourceFieldRef" in source:
                    limit = container["resources"]["limits"][source["resourceFieldRef"]["resource"].split(".")[1]]
                    env[e["name"]] = str(int(-(-quantity(limit) // quantity(source["resourceFieldRef"].get("divisor", "1")))))
                elif "secretKeyRef" in source:
                    env[e["name"]] = ""
            paths = {}
            for mount in container.get("volumeMounts", []):
                volume = next(v for v in spec.get("volumes", []) if v["name"] == mount["name"])
                if "persistentVolumeClaim" in volume:
                    local = os.path.join(tmp, "claims", volume["persistentVolumeClaim"]["claimName"])
                else:
                    local = os.path.join(tmp, label, mount["name"])
                os.makedirs(local, exist_ok=True)
                if "secret" in volume:
                    files = generated.get(volume["secret"]["secretName"], {})
                    items = volume["secret"].get("items") or [{"key": k, "path": k} for k in files]
                    for item in items:
                        shutil.copy(os.path.join(secrets_made, files.get(item["key"], item["key"])),
                                    os.path.join(local, item["path"]))
                paths[mount["mountPath"]] = local
            argv = []
            for word in farm_argv(container)[0] if farm_argv(container) else []:
                word = re.sub(r"\$\((\w+)\)", lambda m: env.get(m.group(1), ""), word)
                head, _, value = word.rpartition("=") if word.startswith("--") else ("", "", word)
                for mount_path, local in sorted(paths.items(), key=lambda p: -len(p[0])):
                    if value == mount_path or value.startswith(mount_path.rstrip("/") + "/"):
                        word = (head + "=" if head else "") + local + value[len(mount_path.rstrip("/")):]
                        break
                word = word.replace("/usr/share/renderfarm/jobs/", os.path.join(SOURCE, "jobs") + "/")
                word = re.sub(r"^(--(?:listen|http)=)[^=]*:(\d+)$",
                              lambda m: f"{m.group(1)}127.0.0.1:{ports.setdefault((label, int(m.group(2))), free_port())}", word)
                word = re.sub(r"([a-z][\w-]*):(\d+)", lambda m: f"127.0.0.1:{ports[(m.group(1), int(m.group(2)))]}"
                              if (m.group(1), int(m.group(2))) in ports else m.group(0), word)
                argv.append(word)
            return argv, paths.get(container.get("workingDir"), tmp)

        def start(label, argv, cwd):
            log = open(os.path.join(tmp, f"{label}.log"), "w")
            process = subprocess.Popen([FARM] + argv, stdout=log, stderr=subprocess.STDOUT, cwd=cwd)
            running.append(process)
            return process, os.path.join(tmp, f"{label}.log")

        def wait_for(process, log, text):
            deadline = time.time() + 90
            while time.time() < deadline:
                if text in open(log).read():
                    return True
                if process.poll() is not None:
                    break
                time.sleep(0.2)
            problem("run", f"no '{text}' from {' '.join(process.args)}:\n{open(log).read()[-2000:]}")
            return False

        def role_of(workload):
            for c in containers_of(workload, init=False):
                for argv in farm_argv(c):
                    if argv:
                        return argv[0], c
            return None, None

        workloads = {role_of(w)[0]: w for w in docs if w["kind"] in WORKLOAD_KINDS}
        scheduler, worker, regress = workloads.get("scheduler"), workloads.get("worker"), workloads.get("regress")
        if not (scheduler and worker and regress):
            problem("run", "a scheduler, a worker and a regress Job are needed")
            return
        # The scheduler, behind its Services' ports.
        argv, cwd = prepare(scheduler, role_of(scheduler)[1], "scheduler")
        argv = [w for w in argv if not w.startswith("--store")]
        process, log = start("scheduler", argv, cwd)
        if not wait_for(process, log, "scheduler listening on"):
            return
        for service in by_kind.get("Service", {}).values():
            if matches(service["spec"].get("selector"), pod_labels(scheduler)):
                container = role_of(scheduler)[1]
                for sp in service["spec"]["ports"]:
                    target = sp.get("targetPort", sp["port"])
                    number = next(cp["containerPort"] for cp in container["ports"]
                                  if cp.get("name") == target or cp["containerPort"] == target)
                    ports[(service["metadata"]["name"], sp["port"])] = ports[("scheduler", number)]
        argv, cwd = prepare(worker, role_of(worker)[1], "worker")
        process, log = start("worker", argv, cwd)
        if not wait_for(process, log, "registered with the scheduler"):
            return
        # The Job: its init containers, then its container, which must pass.
        spec = pod_spec(regress)
        for init in spec.get("initContainers", []):
            command = init.get("command", [])
            if command[:1] and command[0] in SHELLS:
                script = command[command.index("-c") + 1]
                script = re.sub(r"(^|[;&|\s])farm(?=\s)", rf"\g<1>{FARM}", script)
                script = re.sub(r"([a-z][\w-]*):(\d+)", lambda m: f"127.0.0.1:{ports[(m.group(1), int(m.group(2)))]}"
                                if (m.group(1), int(m.group(2))) in ports else m.group(0), script)
                try:
                    out = subprocess.run(command[:command.index("-c") + 1] + [script], capture_output=True, text=True, timeout=60)
                    if out.returncode != 0:
                        problem("run", f"init container {init['name']}: exit {out.returncode}: {out.stdout} {out.stderr}")
                except subprocess.TimeoutExpired:
                    problem("run", f"init container {init['name']} did not end within 60 s")
        container = role_of(regress)[1]
        argv, cwd = prepare(regress, container, "regress")
        out = subprocess.run([FARM] + argv, capture_output=True, text=True, timeout=600, cwd=cwd)
        if out.returncode != 0:
            problem("run", f"the regress Job's command failed (exit {out.returncode}): {out.stdout[-3000:]} {out.stderr[-2000:]}")
            return
        junit = flag_values(argv, "--junit")
        if not junit or "failures=\"0\"" not in open(junit[0]).read():
            problem("run", "the regress Job's JUnit file is missing or counts failures")
        verdicts = [line for line in out.stdout.splitlines() if line.startswith(("PASS", "WARN", "FAIL"))]
        print(f"the manifests' command lines, run here: a scheduler, a worker registered with it, and the regress "
              f"Job after its init container: {out.stdout.strip().splitlines()[-3] if len(verdicts) else out.stdout.strip()}")
        for process in running:
            process.send_signal(signal.SIGTERM)
        for process in running:
            try:
                code = process.wait(60)
            except subprocess.TimeoutExpired:
                code = "still running after 60 s"
            if code != 0:
                problem("run", f"{' '.join(process.args[:2])}: exit {code} after SIGTERM")
        running.clear()
    finally:
        for process in running:
            if process.poll() is None:
                process.kill()
                process.wait()
        shutil.rmtree(tmp, ignore_errors=True)


if FARM and os.access(FARM, os.X_OK):
    run_as_manifests(rendered or assembled_here())
else:
    print("note: no FARM_BINARY: the manifests' command lines are not run")

if problems:
    print(f"FAIL: {len(problems)} problem(s):")
    for line in problems:
        print("  " + line)
    sys.exit(1)
print(f"PASS: deploy/k8s checked ({len(kubectls)} kubectl rendering(s) and the files as assembled here)")
