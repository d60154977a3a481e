#!/usr/bin/env python3
"""Writes examples/runs/press_slide: the cube of rigs/press_bench.yaml is lowered onto the block,
pressed, slid along x and lifted. Flat face on flat face: the four bottom vertices of the cube
each penetrate the block by delta, so the normal force is 4 K delta and, while sliding faster
than the sticking threshold, the friction force is mu 4 K delta against the sliding direction.
Forces are what the plate feels (the cube pushes it down: fz < 0), moments about the plate
origin, force-plate frame = world. Resolution as in the contact paper: forces quantised to 1.5 N
is too coarse for a small example, so 0.05 N and 2 um are used. Deterministic (seeded).
Only standard-library Python, so that the example can be remade anywhere."""
import math, os, random

K, MU, VTM = 1.8e5, 0.2, 1e-3
RATE = 50.0
HALF = 0.015
random.seed(7)
out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "runs", "press_slide")
os.makedirs(out, exist_ok=True)

def z_of(t):   # cube bottom height above the block top (negative = interference)
    if t < 1.0: return 0.004 * (1.0 - t)            # approach
    if t < 2.0: return -0.0005 * (t - 1.0)          # press to 0.5 mm
    if t < 5.0: return -0.0005                      # hold while sliding
    if t < 6.0: return -0.0005 + 0.0045 * (t - 5.0) # lift
    return 0.004
def x_of(t):
    if t < 2.5: return 0.0
    if t < 4.5: return 0.02 * (t - 2.5) / 2.0       # 1 cm/s slide along x
    return 0.02

q = lambda v, r: round(v / r) * r
n = int(6.5 * RATE)
with open(os.path.join(out, "samples.csv"), "w") as f:
    f.write("t,px,py,pz,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,fx,fy,fz,mx,my,mz\n")
    for i in range(n):
        t = i / RATE
        h = 1e-4
        x, z = x_of(t), z_of(t)
        vx = (x_of(t + h) - x_of(t - h)) / (2 * h)
        vz = (z_of(t + h) - z_of(t - h)) / (2 * h)
        pz = 0.05 + z  # block top is at z = 0.05 in world; the ee sits on the cube bottom
        delta = max(0.0, -z)
        fn = 4 * K * delta                          # force of the block on the cube, +z
        ft = -MU * fn * (1 if vx > 0 else -1) if abs(vx) > VTM else 0.0  # friction on the cube, against sliding
        # The plate feels the opposite of what the cube feels.
        F = (-ft, 0.0, -fn)
        # All four contact points at (x +- HALF, +-HALF, 0.05): their resultant acts at (x, 0, 0.05).
        r = (x, 0.0, 0.05)
        M = (r[1] * F[2] - r[2] * F[1], r[2] * F[0] - r[0] * F[2], r[0] * F[1] - r[1] * F[0])
        noise = lambda s: random.gauss(0.0, s)
        row = [t, q(x, 2e-6), 0.0, q(pz, 2e-6), 1.0, 0.0, 0.0, 0.0, q(vx, 2e-4), 0.0, q(vz, 2e-4), 0.0, 0.0, 0.0,
               q(F[0] + noise(0.1), 0.05), q(F[1] + noise(0.1), 0.05), q(F[2] + noise(0.1), 0.05),
               q(M[0] + noise(0.005), 0.001), q(M[1] + noise(0.005), 0.001), q(M[2] + noise(0.005), 0.001)]
        f.write(",".join(("%.10g" % v) for v in row) + "\n")
with open(os.path.join(out, "run.yaml"), "w") as f:
    f.write("""format_version: 1
rig: press_bench
start_time: 2026-11-21T09:00:00.000Z
output_rate_hz: 50
sources:
  - {name: simulation, kind: simulation, rate_hz: 50}
notes: |
  Made by examples/make_press_slide_run.py: cube pressed 0.5 mm into the block, slid 2 cm along x
  at 1 cm/s and lifted. K = 1.8e5 N/m, mu = 0.2, flat face contact (4 vertices).
""")
