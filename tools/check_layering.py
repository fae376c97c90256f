#!/usr/bin/env python3
"""Fails when a source file includes a header from a component it must not depend on.

The layering (DESIGN.md "Layout"; an arrow never points up):

    renderer/util <- renderer <- server/common <- server/{worker,scheduler,client}
        <- server/embedded <- server/{bench,cli}

Each component may include its own headers and those of the components below it, plus the
generated proto headers from server/common up. Usage: check_layering.py [--root DIR]; prints
every offending line as FILE:LINE and exits 1, or prints a one-line summary and exits 0.
"""
import argparse
import pathlib
import re
import sys

# component -> the components it may include (itself always included).
ALLOWED = {
    "renderer/util": [],
    "renderer": ["renderer/util"],
    "server/common": ["renderer", "renderer/util", "proto"],
    "server/worker": ["server/common", "renderer", "renderer/util", "proto"],
    "server/scheduler": ["server/common", "renderer", "renderer/util", "proto"],
    "server/client": ["server/common", "renderer", "renderer/util", "proto"],
    "server/embedded": ["server/worker", "server/scheduler", "server/client", "server/common",
                        "renderer", "renderer/util", "proto"],
    "server/review": ["server/embedded", "server/worker", "server/scheduler", "server/client",
                      "server/common", "renderer", "renderer/util", "proto"],
    "server/bench": ["server/review", "server/embedded", "server/worker", "server/scheduler", "server/client",
                     "server/common", "renderer", "renderer/util", "proto"],
    "server/cli": ["server/bench", "server/review", "server/embedded", "server/worker", "server/scheduler",
                   "server/client", "server/common", "renderer", "renderer/util", "proto"],
}
INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')


def component_of(path: str):
    """The most specific component a repository-relative path lies in, or None."""
    best = None
    for name in ALLOWED:
        if path == name or path.startswith(name + "/"):
            if best is None or len(name) > len(best):
                best = name
    if best is None and path.startswith("proto/"):
        return "proto"
    return best


def check(root: pathlib.Path):
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
            allowed = {own, *ALLOWED[own]}
            text = path.read_text(encoding="utf-8", errors="replace")
            for number, line in enumerate(text.splitlines(), 1):
                m = INCLUDE.match(line)
                if not m:
                    continue
                target = component_of(m.group(1))
                if target is None or target in allowed:
                    continue
                problems.append(f"{rel}:{number}: includes \"{m.group(1)}\" from {target}, which "
                                f"{own} must not depend on (it may use: {', '.join(sorted(allowed))})")
    return problems, files


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=pathlib.Path(__file__).resolve().parent.parent,
                        type=pathlib.Path, help="repository root (default: this script's)")
    args = parser.parse_args()
    problems, files = check(args.root)
    for p in problems:
        print(p)
    if problems:
        print(f"layering: {len(problems)} include(s) against the layering in {files} files")
        return 1
    print(f"layering: {files} files, every include points down or sideways within its component")
    return 0


if __name__ == "__main__":
    sys.exit(main())
