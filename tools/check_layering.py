#!/usr/bin/env python3
"""Fails when a source file includes a header from a component it must not depend on, or when a
library links one it must not.

The components and their DAG (docs/architecture.md, "Components"; an arrow never points up):

    renderer:  util <- geometry <- scene <- image <- loaders <- job <- accel <- {raster, trace}
               <- renderer (engine.h, render_frame.h);  image <- compare
    server:    renderer <- common <- {worker, scheduler, client} <- embedded <- {regress, grade}
               <- bench <- cli
    scheduler: options <- store <- events;  assets <- workers;  {events, workers} <- jobs
               <- dispatch <- scheduler (core, front door, service, lease) <- http

A component may include its own headers and those of every component it depends on, directly or
through others; ONLY narrows that for an adapter (the dashboard sees the front door alone). Usage:

    check_layering.py [--root DIR]      every #include "..." under renderer/ and server/
    check_layering.py --links FILE      the libraries' link lines as CMake wrote them (one
                                        "library: dependency;dependency;..." per line)

Prints every offending line (FILE:LINE, or the library) and exits 1, or prints a one-line
summary and exits 0.
"""
import argparse
import pathlib
import re
import sys

# component -> the components it depends on directly.
DEPENDS = {
    "renderer/util": [],
    "renderer/geometry": ["renderer/util"],
    "renderer/scene": ["renderer/geometry"],
    "renderer/image": ["renderer/scene"],
    "renderer/texture": ["renderer/image"],
    "renderer/loaders": ["renderer/texture"],
    "renderer/job": ["renderer/loaders"],
    "renderer/accel": ["renderer/job"],
    "renderer/raster": ["renderer/accel"],
    "renderer/trace": ["renderer/accel"],
    "renderer": ["renderer/raster", "renderer/trace"],
    "renderer/compare": ["renderer/image"],
    "proto": [],
    "server/common": ["renderer", "renderer/compare", "proto"],
    "server/worker": ["server/common"],
    "server/client": ["server/common"],
    "server/scheduler/options": ["server/common"],
    "server/scheduler/store": ["server/scheduler/options"],
    "server/scheduler/events": ["server/scheduler/store"],
    "server/scheduler/assets": ["server/common"],
    "server/scheduler/workers": ["server/scheduler/options", "server/scheduler/assets"],
    "server/scheduler/jobs": ["server/scheduler/events", "server/scheduler/workers"],
    "server/scheduler/dispatch": ["server/scheduler/jobs"],
    "server/scheduler": ["server/scheduler/dispatch"],
    "server/scheduler/http": ["server/scheduler"],
    "server/embedded": ["server/worker", "server/scheduler/http", "server/client"],
    "server/regress": ["server/embedded"],
    "server/grade": ["server/embedded"],
    "server/bench": ["server/regress", "server/grade"],
    "server/cli": ["server/bench"],
}

# component -> {component below it: the only headers of it that it may include}. The dashboard is
# an adapter over the scheduler's front door: of the scheduler's root it sees the front door alone,
# so that it cannot reach around the authorisation to the core.
ONLY = {
    "server/scheduler/http": {"server/scheduler": ["server/scheduler/front_door.h"]},
}

# library -> the component (with every folder under it) it is built from.
LIBRARIES = {
    "farm_renderer": "renderer",
    "farm_proto": "proto",
    "farm_common": "server/common",
    "farm_worker": "server/worker",
    "farm_scheduler": "server/scheduler",
    "farm_client": "server/client",
    "farm_embedded": "server/embedded",
    "farm_regress": "server/regress",
    "farm_grade": "server/grade",
    "farm_bench": "server/bench",
    "farm_cli": "server/cli",
}
INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')


def below(component):
    """Every component `component` may use, itself included (the DAG's closure)."""
    seen, stack = set(), [component]
    while stack:
        name = stack.pop()
        if name not in seen:
            seen.add(name)
            stack.extend(DEPENDS[name])
    return seen


def cycle():
    """A cycle in DEPENDS as a list of components, or None: the DAG must be one."""
    state = {}

    def visit(name, path):
        state[name] = "open"
        for dep in DEPENDS[name]:
            if state.get(dep) == "open":
                return path + [name, dep]
            if dep not in state:
                found = visit(dep, path + [name])
                if found:
                    return found
        state[name] = "done"
        return None

    for name in DEPENDS:
        if name not in state:
            found = visit(name, [])
            if found:
                return found
    return None


def component_of(path: str):
    """The most specific component a repository-relative path lies in, or None."""
    best = None
    for name in DEPENDS:
        if path == name or path.startswith(name + "/"):
            if best is None or len(name) > len(best):
                best = name
    return best


def check_includes(root: pathlib.Path):
    problems, files = [], 0
    for top in ("renderer", "server"):
        for path in sorted((root / top).rglob("*")):
            if path.suffix not in (".h", ".cpp") or not path.is_file():
                continue
            files += 1
            rel = path.relative_to(root).as_posix()
            own = component_of(rel)
            if own is None:
                problems.append(f"{rel}: lies in no known component (add it to tools/check_layering.py)")
                continue
            allowed = below(own)
            text = path.read_text(encoding="utf-8", errors="replace")
            for number, line in enumerate(text.splitlines(), 1):
                m = INCLUDE.match(line)
                if not m:
                    continue
                target = component_of(m.group(1))
                only = ONLY.get(own, {}).get(target)
                if only is not None and m.group(1) not in only:
                    problems.append(f"{rel}:{number}: includes \"{m.group(1)}\" from {target}, of which {own} may "
                                    f"include only {', '.join(only)}")
                    continue
                if target is None or target in allowed:
                    continue
                problems.append(f"{rel}:{number}: includes \"{m.group(1)}\" from {target}, which "
                                f"{own} must not depend on (it may use: {', '.join(sorted(allowed))})")
    return problems, f"{files} files"


def library_below(library):
    """The libraries `library` may link: those whose component lies below its own."""
    allowed = below(LIBRARIES[library])
    return {name for name, component in LIBRARIES.items() if component in allowed}


def check_links(links: pathlib.Path):
    problems, libraries = [], 0
    for number, line in enumerate(links.read_text(encoding="utf-8").splitlines(), 1):
        if not line.strip():
            continue
        library, _, deps = line.partition(":")
        library = library.strip()
        if library not in LIBRARIES:
            problems.append(f"{links}:{number}: {library} is in no known component (add it to LIBRARIES)")
            continue
        libraries += 1
        allowed = library_below(library)
        for dep in filter(None, (d.strip() for d in deps.split(";"))):
            if dep.startswith("farm_") and dep not in allowed:
                problems.append(f"{links}:{number}: {library} links {dep}, which it must not depend on "
                                f"(it may link: {', '.join(sorted(allowed))})")
    return problems, f"{libraries} libraries"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=pathlib.Path(__file__).resolve().parent.parent,
                        type=pathlib.Path, help="repository root (default: this script's)")
    parser.add_argument("--links", type=pathlib.Path,
                        help="check this link graph (written by server/CMakeLists.txt) instead of the includes")
    args = parser.parse_args()
    loop = cycle()
    if loop:
        print(f"layering: the components' dependencies form a cycle: {' -> '.join(loop)}")
        return 1
    problems, scope = check_links(args.links) if args.links else check_includes(args.root)
    for p in problems:
        print(p)
    what = "link(s)" if args.links else "include(s)"
    if problems:
        print(f"layering: {len(problems)} {what} against the layering in {scope}")
        return 1
    print(f"layering: {scope}, every {what[:-3]} points down the DAG or within its component")
    return 0


if __name__ == "__main__":
    sys.exit(main())
