#!/usr/bin/env python3
"""`hil diagnose` on the shipped ACU runs (examples/acu/runs), against the truth they were simulated
with (examples/acu/truth_*.yaml): the cause is the geometric shifts alone, with μ and every
practically identifiable shift inside its 95 % interval. A change to the nominal contact model or
to the engine that brings back a spurious second cause fails here (2026-11-26: a fitted friction
depth did, and only a hand run showed it); the one second cause allowed is slow_slip, reading the
sliding contacts the reported twist's resolution misreads as sticking (test_1a, since 2026-12-05).

Label `blind`: about a minute, minutes under sanitizers."""
import json
import os
import subprocess
import sys
import unittest

HIL, SRC = sys.argv[1], sys.argv[2]
ACU = os.path.join(SRC, "examples", "acu")


def truth_of(name):
    """The truth file's top-level numbers and its `geometric:` block (flat YAML, no library needed)."""
    top, geometric, block = {}, {}, None
    with open(os.path.join(ACU, f"truth_{name}.yaml")) as f:
        for line in f:
            line = line.split("#", 1)[0].rstrip()
            if not line.strip():
                continue
            key, _, value = line.strip().partition(":")
            if not line.startswith(" "):
                block = key
                if value.strip():
                    top[key] = float(value)
            elif block == "geometric":
                geometric[key] = float(value)
    return top, geometric


def diagnose(name):
    r = subprocess.run([HIL, "diagnose", "--quiet", "--json", "-", os.path.join(ACU, "runs", f"test_{name}")],
                       capture_output=True, text=True, timeout=600)
    if r.returncode != 0:
        raise AssertionError(r.stderr)
    return json.loads(r.stdout)


class ShippedAcuRuns(unittest.TestCase):
    def check(self, name, shifts=True):
        top, geometric = truth_of(name)
        d = diagnose(name)
        self.assertEqual(d["cause"]["name"], "geometric_offset")
        p = d["extended"]["parameters"]
        if d["second_cause"] is not None:
            # slow_slip, friction on contacts the rig calls sticking, and only it (2026-12-05). This
            # truth *is* the nominal sticking rule (no friction below 0.3 mm/s of true slip), but the
            # reported twist's 0.2 mm/s step reads sliding contacts below the threshold: friction the
            # nominal model misses where it declares sticking ("Known limits"), which slow_slip
            # names. Its μ_s / μ is then the share misread, well below the 1 of a threshold declared
            # too high, which this truth does not have.
            self.assertEqual(d["second_cause"]["name"], "slow_slip", d["second_step"] if "second_step" in d else "")
            r = p["slow_slip_mu_ratio"]
            self.assertLess(r["value"] + 1.96 * r["std"], 1.0, r)
        self.assertGreater(d["gain_percent"], 50.0)
        mu = p["mu"]
        self.assertLessEqual(abs(mu["value"] - top["friction_coefficient"]), 1.96 * mu["std"], mu)
        fixed = {u["name"] for u in d["extended"]["unidentifiable"]}
        if not shifts:
            return d, fixed
        checked = 0
        for k, truth in geometric.items():
            if k in fixed or k not in p or p[k]["pnr"] < 5.0:
                continue
            q = p[k]
            self.assertLessEqual(abs(q["value"] - truth), 1.96 * q["std"], f"{k}: {q['value']} ± {1.96 * q['std']}, truth {truth}")
            checked += 1
        self.assertGreaterEqual(checked, 2)
        return d, fixed

    def test_2a(self):
        self.check("2a")

    def test_1a(self):
        # On a turn about the plate normal one combination of the guides' shifts (and one of their
        # rotations) does not show: guide 4's are fixed, and the others absorb the hidden
        # combination, so they are not compared with the truth one by one. Checked on the cause's
        # own fit: slow_slip's columns, added in the second step, follow the contact points and
        # make the combination visible to the joint fit's collinearity check (wide, not fixed).
        d, _ = self.check("1a", shifts=False)
        cause = next(c for c in d["candidates"] if c["name"] == "geometric_offset")
        fixed = {u["name"] for u in cause["unidentifiable"]}
        self.assertIn("guide4_shift", fixed)
        self.assertIn("guide4_rot", fixed)


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1], verbosity=2)
