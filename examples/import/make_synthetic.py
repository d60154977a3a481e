#!/usr/bin/env python3
"""Writes synthetic_markers.csv: a 4-marker probe (marker coordinates in mm, time in ms) pressing on a
force plate, with what real exports contain: an occluded marker (empty cells), a zero-filled marker,
a marker seen by only two cameras on one row, a duplicated timestamp and a 30 ms gap.
Import it with:  hil import examples/import/synthetic_markers.csv --config examples/import/synthetic.yaml --out /tmp/synth
"""
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))
REF_MM = [(60.0, 0.0, 0.0), (0.0, 80.0, 0.0), (-50.0, -30.0, 10.0), (0.0, 0.0, 90.0)]  # body frame, mm


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]


def main():
    rows = []
    t_ms = 0.0
    for i in range(101):
        if i > 0:
            t_ms += 30.0 if i == 70 else 10.0
        t = t_ms / 1000.0
        yaw = 0.2 * t  # rad
        p = (400.0 + 20.0 * t, 300.0, 150.0 - 10.0 * t)  # mm: slides along x while pressing down
        R = rot_z(yaw)
        cells = [f"{t_ms:.1f}"]
        for k, b in enumerate(REF_MM):
            w = [sum(R[r][c] * b[c] for c in range(3)) + p[r] for r in range(3)]
            if k == 1 and 20 <= i < 24:
                cells += ["", "", ""]  # occluded
            elif k == 2 and i == 40:
                cells += ["0", "0", "0"]  # zero-filled by the exporter
            else:
                cells += [f"{v:.4f}" for v in w]
        fz = -(50.0 + 100.0 * t)  # N, pressing down on the plate
        fx = 0.3 * fz * 0.1
        cells += [f"{fx:.4f}", "0.0000", f"{fz:.4f}"]
        x_m, y_m = p[0] / 1000.0 - 0.4, p[1] / 1000.0 - 0.3  # contact point in the plate frame
        cells += [f"{y_m * fz:.5f}", f"{-x_m * fz:.5f}", "0.00000"]  # moment about the plate origin
        cells += ["1" if 30 <= i < 60 else "0"]
        rows.append(cells)
    rows[51][0] = rows[50][0]  # a duplicated timestamp
    rows[85][1:4] = ["", "", ""]
    rows[85][4:7] = ["", "", ""]  # two markers lost: this row has no pose and is dropped
    header = ["time_ms", "p1_x", "p1_y", "p1_z", "p2_x", "p2_y", "p2_z", "p3_x", "p3_y", "p3_z", "p4_x", "p4_y", "p4_z",
              "Fx", "Fy", "Fz", "Mx", "My", "Mz", "trigger"]
    with open(os.path.join(HERE, "synthetic_markers.csv"), "w") as f:
        f.write("# synthetic marker + force-plate export, written by make_synthetic.py\n")
        f.write(",".join(header) + "\n")
        for r in rows:
            f.write(",".join(r) + "\n")


if __name__ == "__main__":
    main()
