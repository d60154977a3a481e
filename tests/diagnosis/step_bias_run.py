"""A press-bench run whose force plate gains a constant fz offset half-way: the test of a windowed
diagnosis (`hil diagnose --window`). Written from the situation, not with the diagnosis' code: the
shipped press-and-slide trajectory is played forward, backward, forward, backward (26 s, a contact
in each quarter), simulated clean by `hil contact simulate`, and the offset is then added to the
recorded fz column from `t_step_s` on, as a plate whose zero shifts would record it."""
import csv
import os
import subprocess


def long_trajectory(src, out_csv):
    """press_slide.csv, then time-reversed (velocities negated), twice over; returns its length in s."""
    with open(os.path.join(src, "examples", "trajectories", "press_slide.csv")) as f:
        rows = list(csv.reader(f))
    head, data = rows[0], [[float(x) for x in r] for r in rows[1:]]
    period, dt = data[-1][0], data[1][0] - data[0][0]
    moving = [head.index(k) for k in ("vx", "vy", "vz", "wx", "wy", "wz")]
    back = []
    for r in reversed(data):
        q = list(r)
        q[0] = period - r[0]
        for i in moving:
            q[i] = -r[i]
        back.append(q)
    out, t0 = [], 0.0
    for segment in (data, back, data, back):
        for r in segment:
            out.append([round(r[0] + t0, 6)] + r[1:])
        t0 = out[-1][0] + dt
    with open(out_csv, "w") as f:
        f.write(",".join(head) + "\n")
        for q in out:
            f.write(",".join(repr(x) for x in q) + "\n")
    return t0


def make(hil, src, out, seed, offset_n, t_step_s, drift_n=0.0):
    """The run in `out`: returns the trajectory's length (s). drift_n: an fz offset growing linearly
    from 0 at the start to drift_n at the end (a plate whose zero drifts), on top of the step."""
    traj = out + ".trajectory.csv"
    length = long_trajectory(src, traj)
    r = subprocess.run([hil, "contact", "simulate", "--rig", os.path.join(src, "examples", "rigs", "press_bench.yaml"), "--trajectory",
                        traj, "--out", out, "--force-resolution", "0.1", "--force-noise", "0.1", "--moment-resolution", "0.005",
                        "--moment-noise", "0.005", "--seed", str(seed)], capture_output=True, text=True, timeout=300)
    if r.returncode != 0:
        raise RuntimeError(r.stderr)
    path = os.path.join(out, "samples.csv")
    with open(path) as f:
        lines = f.read().splitlines()
    head = lines[0].split(",")
    it, iz = head.index("t"), head.index("fz")
    rows = [lines[0]]
    t_end = float(lines[-1].split(",")[it])
    for ln in lines[1:]:
        cells = ln.split(",")
        t = float(cells[it])
        fz = float(cells[iz]) + drift_n * t / t_end
        if t >= t_step_s:
            fz += offset_n
        cells[iz] = repr(fz)
        rows.append(",".join(cells))
    with open(path, "w") as f:
        f.write("\n".join(rows) + "\n")
    return length
