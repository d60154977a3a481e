#!/usr/bin/env python3
"""Writes examples/trajectories/press_slide.csv: the end-effector path of the press-and-slide
example (rigs/press_bench.yaml). The cube is lowered onto the block, pressed 0.5 mm into it, slid
2 cm along x at 1 cm/s and lifted, at 50 Hz. The run examples/runs/press_slide is this trajectory
through hil's own contact simulation (K = 1.8e5 N/m, mu = 0.2, from the rig):

  hil contact simulate --rig examples/rigs/press_bench.yaml \\
      --trajectory examples/trajectories/press_slide.csv --out examples/runs/press_slide \\
      --force-resolution 0.05 --moment-resolution 0.001 --position-resolution 2e-6 \\
      --velocity-resolution 2e-4 --force-noise 0.1 --moment-noise 0.005 --seed 7
"""
import os

RATE = 50.0
here = os.path.dirname(os.path.abspath(__file__))
os.makedirs(os.path.join(here, "trajectories"), exist_ok=True)

def z_of(t):  # cube bottom height above the block top (negative = interference)
    if t < 1.0: return 0.004 * (1.0 - t)
    if t < 2.0: return -0.0005 * (t - 1.0)
    if t < 5.0: return -0.0005
    if t < 6.0: return -0.0005 + 0.0045 * (t - 5.0)
    return 0.004

def x_of(t):
    if t < 2.5: return 0.0
    if t < 4.5: return 0.02 * (t - 2.5) / 2.0
    return 0.02

with open(os.path.join(here, "trajectories", "press_slide.csv"), "w") as f:
    f.write("t,px,py,pz,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz\n")
    for i in range(int(6.5 * RATE)):
        t = i / RATE
        h = 1e-4
        vx = (x_of(t + h) - x_of(t - h)) / (2 * h)
        vz = (z_of(t + h) - z_of(t - h)) / (2 * h)
        row = [t, x_of(t), 0.0, 0.05 + z_of(t), 1.0, 0.0, 0.0, 0.0, vx, 0.0, vz, 0.0, 0.0, 0.0]
        f.write(",".join("%.10g" % v for v in row) + "\n")
