#!/usr/bin/env python3
"""Compares two robotperf results files field by field, leaving out what a rerun changes anyway.

Usage: same-results.py BEFORE.json AFTER.json

A refactoring must leave results as they were: the same fields, the same configuration, counts,
nodes, checks and validity. What differs from one run to the next of one build is left out:
measured times and rates (latency, throughput, control-loop timing, resources, power), the run's
identity (start time, message-ID base, run token), the build's revision, and the wording of
warnings about the machine's load. Accuracy metrics are compared to 1e-9 (a controller's goal
error is a few 1e-16 rad of floating-point noise that depends on timing). Exits 1 when a field
differs, is missing on one side or has another type.
"""
import json
import math
import re
import sys

# Paths (array indices written []) whose values change from run to run of one build.
VOLATILE = re.compile(
    r"^(started_utc|configuration\.(id_base_ns|run_token|warmup_repeated_s)"
    r"|latency_ms\..*|headline\..*|throughput\.(output_hz|offered_hz|window_s)"
    r"|resources\..*|power\..*|control_loops\[\]\.[a-z_]+_(ms|us)\..*"
    r"|software\.git_revision|warnings\[\]\.message|validity\.reasons\[\])$")
# Warnings about the machine rather than the run: present or not depending on the load.
LOAD_WARNINGS = {"system_busy", "interference"}
TOLERANT = re.compile(r"^functional\.metrics\.[^.]+\.value$")


def flatten(prefix, value, out):
    if isinstance(value, dict):
        for key, item in value.items():
            flatten(f"{prefix}.{key}" if prefix else key, item, out)
    elif isinstance(value, list):
        for index, item in enumerate(value):
            flatten(f"{prefix}[{index}]", item, out)
    else:
        out[prefix] = value


def load(path):
    with open(path, encoding="utf-8") as f:
        results = json.load(f)
    results["warnings"] = [w for w in results.get("warnings", [])
                           if w.get("rule") not in LOAD_WARNINGS]
    fields = {}
    flatten("", results, fields)
    return fields


def same(path, a, b):
    if type(a) is not type(b):
        return False
    if TOLERANT.match(path) and isinstance(a, float):
        return math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-9)
    return a == b


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    before, after = load(sys.argv[1]), load(sys.argv[2])
    differences = 0
    for path in sorted(set(before) | set(after)):
        if VOLATILE.match(re.sub(r"\[\d+\]", "[]", path)):
            continue
        a, b = before.get(path, "<missing>"), after.get(path, "<missing>")
        if not same(path, a, b):
            differences += 1
            print(f"  {path}: {a!r} -> {b!r}")
    return 1 if differences else 0


if __name__ == "__main__":
    sys.exit(main())
