#!/usr/bin/env python3
"""Validates JSON files against a JSON Schema with jsonschema (a validator nobody here wrote).

Usage: validate_json_schema.py SCHEMA FILE...
Checks the schema itself first. Prints "FILE: ok" for each valid file and "FILE: PATH: MESSAGE" for
every error; exits 0 when all files are valid, 1 when any is not (or cannot be read as JSON),
2 on a bad schema or usage.
"""
import json
import sys

import jsonschema


def main():
    if len(sys.argv) < 3:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    with open(sys.argv[1], encoding="utf-8") as f:
        schema = json.load(f)
    validator_class = jsonschema.validators.validator_for(schema)
    try:
        validator_class.check_schema(schema)
    except jsonschema.exceptions.SchemaError as e:
        print(f"{sys.argv[1]}: not a valid schema: {e.message}", file=sys.stderr)
        return 2
    validator = validator_class(schema)
    failed = False
    for name in sys.argv[2:]:
        try:
            with open(name, encoding="utf-8") as f:
                document = json.load(f)
        except (OSError, ValueError) as e:
            print(f"{name}: cannot read: {e}")
            failed = True
            continue
        errors = sorted(validator.iter_errors(document), key=lambda e: list(e.absolute_path))
        for error in errors:
            path = "/".join(str(p) for p in error.absolute_path) or "(top)"
            print(f"{name}: {path}: {error.message}")
        if errors:
            failed = True
        else:
            print(f"{name}: ok")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
