#!/usr/bin/env python3
"""compare_outputs.py A B: two folders of scripts/dev/acceptance_outputs.sh, file by file.

Prints the files only one side has, the JSON keys that differ (a key path per line, with how
many times), and the other files that differ. Timing keys (milliseconds, fps, CPU, wall time,
memory) are expected to differ, and so are the checksums and sizes of the files that hold
them, the charts of timings and the report's speed line; anything else is a change.
"""
import collections
import json
import os
import sys

A, B = sys.argv[1], sys.argv[2]


def files(root):
    return {os.path.relpath(os.path.join(d, f), root) for d, _, fs in os.walk(root) for f in fs}


def walk(a, b, path, found):
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            walk(a.get(k), b.get(k), path + [k], found)
    elif isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for x, y in zip(a, b):
            walk(x, y, path + ["[]"], found)
    elif a != b:
        found[".".join(path)] += 1


fa, fb = files(A), files(B)
for f in sorted(fa ^ fb):
    print("only in", A if f in fa else B + ":", f)
keys, other, same = collections.Counter(), [], 0
for f in sorted(fa & fb):
    a = open(os.path.join(A, f), "rb").read()
    b = open(os.path.join(B, f), "rb").read()
    if a == b:
        same += 1
    elif f.endswith(".json"):
        walk(json.loads(a), json.loads(b), [os.path.basename(f)], keys)
    else:
        other.append(f)
print(f"{same} files identical")
for k, n in sorted(keys.items()):
    print(f"json key differs ({n}×): {k}")
for f in other:
    print("file differs:", f)
