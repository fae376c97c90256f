#!/usr/bin/python3
"""Reads a Prometheus text exposition on stdin with prometheus_client's own parser (Debian's
python3-prometheus-client) and prints one JSON object: {"families": {name: type}, "samples":
{"name{label="v",...}": value}}. Exits 1, naming the problem, when the parser refuses the text or
a histogram breaks its rules (buckets that fall as `le` rises, a +Inf bucket that is not _count).

  /usr/bin/python3 tests/python/prometheus_metrics.py < metrics.txt
"""
import json
import math
import sys

from prometheus_client.parser import text_string_to_metric_families


def sample_key(sample) -> str:
    if not sample.labels:
        return sample.name
    labels = ",".join(f'{k}="{v}"' for k, v in sorted(sample.labels.items()))
    return f"{sample.name}{{{labels}}}"


def check_histogram(family) -> None:
    buckets = [(float(s.labels["le"]), s.value) for s in family.samples if s.name.endswith("_bucket")]
    counts = [s.value for s in family.samples if s.name.endswith("_count")]
    if not buckets or not counts:
        raise ValueError(f"histogram {family.name}: no buckets or no _count")
    ordered = sorted(buckets)
    for (_, low), (le, high) in zip(ordered, ordered[1:]):
        if high < low:
            raise ValueError(f"histogram {family.name}: bucket le={le} holds fewer than the one below it")
    if not math.isinf(ordered[-1][0]) or ordered[-1][1] != counts[0]:
        raise ValueError(f"histogram {family.name}: the +Inf bucket is not _count")


def main() -> int:
    try:
        families, samples = {}, {}
        for family in text_string_to_metric_families(sys.stdin.read()):
            families[family.name] = family.type
            if family.type == "histogram":
                check_histogram(family)
            for sample in family.samples:
                samples[sample_key(sample)] = sample.value
    except ValueError as e:
        print(f"prometheus_metrics: {e}", file=sys.stderr)
        return 1
    print(json.dumps({"families": families, "samples": samples}, sort_keys=True))
    return 0


if __name__ == "__main__":
    sys.exit(main())
