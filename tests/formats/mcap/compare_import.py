#!/usr/bin/env python3
"""A run imported from a bag (node/make_bag.mjs) against the run the bag was sampled from.

The bag holds the source run's motion and forces resampled (wrench 1 kHz, linear between rows;
pose and joints 125 Hz); `hil import` synchronises them as an acquisition does (20 Hz low-pass
FIR, decimation to 50 Hz), so values agree up to that filter, which rounds the contact's onset.
Thresholds (fixed before the first comparison, for this one case): positions within 1e-4 m;
each force and moment component's error, relative to the largest |force| (|moment|) of the
source: median < 0.2 %, 95th percentile < 1 %, largest < 10 % (the onset); joints within 0.01 rad
of the generator's formula; at least 95 % of the source's samples.

Usage: compare_import.py SOURCE_SAMPLES.csv IMPORTED_SAMPLES.csv"""
import sys

import numpy as np


def load(path):
    with open(path) as f:
        lines = [l for l in f.read().splitlines() if l and not l.startswith("#")]
    cols = lines[0].split(",")
    data = np.array([[float(x) for x in l.split(",")] for l in lines[1:]])
    return {c: data[:, i] for i, c in enumerate(cols)}


src, imp = load(sys.argv[1]), load(sys.argv[2])
t = imp["t"]
problems = []
if len(t) < 0.95 * len(src["t"]):
    problems.append(f"{len(t)} samples imported of {len(src['t'])}")
for c in ("px", "py", "pz"):
    err = np.abs(imp[c] - np.interp(t, src["t"], src[c])).max()
    if err > 1e-4:
        problems.append(f"{c}: off by {err:.3g} m")
for group in (("fx", "fy", "fz"), ("mx", "my", "mz")):
    scale = max(np.abs(src[c]).max() for c in group)
    for c in group:
        err = np.abs(imp[c] - np.interp(t, src["t"], src[c])) / scale
        med, p95, top = np.median(err), np.percentile(err, 95), err.max()
        print(f"{c}: median {med:.2%}, p95 {p95:.2%}, max {top:.2%} of {scale:g}")
        if med > 0.002 or p95 > 0.01 or top > 0.10:
            problems.append(f"{c}: median {med:.3%}, p95 {p95:.3%}, max {top:.3%}")
for j in range(1, 7):
    want = 0.1 * j * np.sin(2 * np.pi * 0.2 * t + j)
    err = np.abs(imp[f"j{j}"] - want).max()
    if err > 0.01:
        problems.append(f"j{j}: off by {err:.3g} rad")
if problems:
    print("FAIL:\n  " + "\n  ".join(problems), file=sys.stderr)
    sys.exit(1)
print(f"imported run agrees with its source: {len(t)} samples")
