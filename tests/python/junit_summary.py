#!/usr/bin/env python3
"""Reads a JUnit XML file with junitparser (a parser nobody here wrote) and prints what it found.

Usage: junit_summary.py FILE
Prints JSON: {"tests", "failures", "errors", "skipped", "cases": {name: "passed|failure|error|skipped"},
"messages": {name: message}, "properties": {name: {property: value}}}.
"""
import json
import sys

from junitparser import Error, Failure, JUnitXml, Properties, Skipped


def main():
    xml = JUnitXml.fromfile(sys.argv[1])
    out = {"tests": 0, "failures": 0, "errors": 0, "skipped": 0, "cases": {}, "messages": {}, "properties": {}}
    for suite in xml:
        out["tests"] += suite.tests
        out["failures"] += suite.failures
        out["errors"] += suite.errors
        out["skipped"] += suite.skipped
        for case in suite:
            kind = "passed"
            for result in case.result:
                if isinstance(result, Failure):
                    kind = "failure"
                elif isinstance(result, Error):
                    kind = "error"
                elif isinstance(result, Skipped):
                    kind = "skipped"
                out["messages"][case.name] = result.message
            out["cases"][case.name] = kind
            props = case.child(Properties)
            out["properties"][case.name] = {p.name: p.value for p in props} if props is not None else {}
    print(json.dumps(out))


if __name__ == "__main__":
    main()
