#!/usr/bin/env python3
"""Mean FLIP errors from NVIDIA's flip-evaluator, for the cross-check of renderer/compare/flip.

Usage: flip_means.py MODE REFERENCE TEST [MODE REFERENCE TEST ...]
MODE is LDR (8-bit sRGB PNGs) or HDR (linear EXRs). Prints one JSON list on stdout, an object per
pair: {"mean": ..., "start_exposure": ..., "stop_exposure": ..., "exposure_count": ...} (the
exposure fields for HDR only). Run with the venv that deploy/install-deps.sh makes.
"""
import json
import sys

import flip_evaluator


def main(argv):
    if len(argv) == 0 or len(argv) % 3 != 0:
        sys.exit(__doc__)
    results = []
    for i in range(0, len(argv), 3):
        mode, reference, test = argv[i:i + 3]
        if mode not in ("LDR", "HDR"):
            sys.exit(f"flip_means.py: unknown mode {mode!r} (LDR or HDR)")
        _, mean, parameters = flip_evaluator.evaluate(reference, test, mode, applyMagma=False)
        result = {"mean": float(mean)}
        if mode == "HDR":
            result["start_exposure"] = float(parameters["startExposure"])
            result["stop_exposure"] = float(parameters["stopExposure"])
            result["exposure_count"] = int(parameters["numExposures"])
        results.append(result)
    json.dump(results, sys.stdout)
    print()


if __name__ == "__main__":
    main(sys.argv[1:])
