#!/usr/bin/env python3
"""Writes the re-created ACU experiment of the contact paper (Verscheure et al., IJRR 2010, sec. 4-5):

  acu.yaml          the rig: an ACU-like box with four radial V-guides (prisms with a truncated,
                    chamfered apex) and a receptacle whose four V-grooves are unions of two convex
                    walls each; nine geometric uncertainties as in the paper (a transverse shift and
                    a rotation about the insertion axis per V-guide, and the insertion-axis offset of
                    the grooves, the paper's x_u,delta).
  traj_1a.csv       test 1a: retract 2.7 cm, rotate by 2 deg about the plate normal, insert while the
                    V-grooves turn the ACU back (1 kHz).
  traj_2a.csv       test 2a: retract, translate by 2.7 cm, come back to a 6 mm offset and insert
                    while the grooves centre the ACU (1 kHz).
  truth_1a.yaml,    the hidden truth used by `hil contact simulate`: K, mu and small V-guide shifts
  truth_2a.yaml     and rotations (about 1e-4 m, 1e-4 rad) that the nominal rig does not know.

Frames: the insertion axis is the world/plate z axis (the paper's X axis of o2); o1 = ee. When
o1 = o2 the ACU is fully mated with zero interference. The trajectory is force-controlled in the
sense that the descent keeps the normal force near 50 N under the nominal geometry (an analytic
face model below; the real forces come from the C++ simulation). Standard library only.
"""
import math, os

HERE = os.path.dirname(os.path.abspath(__file__))
K, F_TARGET = 1.8e5, 50.0
R = 0.10          # radial position of the guide centres
L = 0.032         # guide length (half length 1.6 cm, as in the paper)
H = 0.010         # ridge height
W = 0.020         # ridge width at the root (45 deg faces)
TIP = 0.0015      # apex truncation (the "chamfer" that keeps the apex off the groove bottom)
GAP = 0.002       # receptacle top below the ACU bottom when mated
LG = L + 0.02     # groove length
WALL = 0.015      # wall thickness
ALPHA = math.atan2(W / 2, H)  # face angle from the vertical (45 deg)

# guide k: centre (cx, cy), along-guide unit (ax, ay), transverse unit (tx, ty)
GUIDES = [((R, 0.0), (1.0, 0.0), (0.0, 1.0)),
          ((0.0, R), (0.0, 1.0), (-1.0, 0.0)),
          ((-R, 0.0), (-1.0, 0.0), (0.0, -1.0)),
          ((0.0, -R), (0.0, -1.0), (1.0, 0.0))]


def local(c, a, t, v, u, z):
    """Point at along-guide v, transverse u, height z in the guide's local frame."""
    return (c[0] + v * a[0] + u * t[0], c[1] + v * a[1] + u * t[1], z)


def ridge(c, a, t):
    """The V-guide: a prism along the guide, truncated apex, its ends chamfered at the bottom."""
    ut = W / 2 * TIP / H  # half width of the truncated tip
    pts = []
    for v, ch in ((-L / 2, 1), (L / 2, -1)):
        pts += [local(c, a, t, v, -W / 2, 0.0), local(c, a, t, v, W / 2, 0.0)]
        vb = v + ch * 0.002  # end chamfer: the tip is 2 mm shorter at each end
        pts += [local(c, a, t, vb, -ut, -H + TIP), local(c, a, t, vb, ut, -H + TIP)]
    return pts


def walls(c, a, t):
    """The two convex walls of a V-groove; their inner faces touch the ridge faces when mated."""
    out = []
    zb = -H - 0.002  # groove bottom, below the apex
    for s in (-1.0, 1.0):
        u_top = s * (H - GAP) * math.tan(ALPHA)  # face line at the receptacle top z = -GAP
        u_bot = s * (H + zb) * math.tan(ALPHA)   # face line at the bottom (crosses the axis)
        pts = []
        for v in (-LG / 2, LG / 2):
            pts += [local(c, a, t, v, u_top, -GAP), local(c, a, t, v, u_top + s * WALL, -GAP),
                    local(c, a, t, v, u_top + s * WALL, zb), local(c, a, t, v, u_bot, zb)]
        out.append(pts)
    return out


def fmt_pts(pts):
    return "[" + ", ".join("[%.6g, %.6g, %.6g]" % p for p in pts) + "]"


def write_rig():
    y = ["# The re-created ACU experiment of the contact paper (examples/acu/make_acu.py wrote this file).",
         "# Object 1: the ACU, held by the end effector (o1 = ee); object 2: the receptacle on the force plate.",
         "# Insertion along -z; o1 = o2 means fully mated with zero interference.",
         "format_version: 1", "name: acu_bench", "", "frames:",
         "  - {name: force_plate, parent: world, translation_m: [0.0, 0.0, -0.06]}",
         "  - {name: receptacle_frame, parent: force_plate, translation_m: [0.0, 0.0, 0.06]}",
         "  - {name: acu_frame, parent: ee, translation_m: [0.0, 0.0, 0.0]}", "", "objects:",
         "  - name: acu", "    frame: acu_frame", "    features:",
         "      - name: body", "        polyhedra:",
         "          - vertices_m: " + fmt_pts([(x, yy, z) for z in (0.0, 0.15) for x in (-0.15, 0.15) for yy in (-0.15, 0.15)]),
         "      - name: handle", "        polyhedra:",
         "          - vertices_m: " + fmt_pts([(x, yy, z) for z in (0.15, 0.2) for x in (-0.03, 0.03) for yy in (-0.02, 0.02)])]
    for k, (c, a, t) in enumerate(GUIDES, 1):
        y += ["      - name: guide%d" % k, "        polyhedra:", "          - vertices_m: " + fmt_pts(ridge(c, a, t))]
    y += ["  - name: receptacle", "    frame: receptacle_frame", "    features:",
          "      - name: grooves", "        polyhedra:"]
    for c, a, t in GUIDES:
        for w in walls(c, a, t):
            y.append("          - vertices_m: " + fmt_pts(w))
    y += ["      - name: base", "        polyhedra:",
          "          - vertices_m: " + fmt_pts([(x, yy, z) for z in (-0.05, -0.012) for x in (-0.2, 0.2) for yy in (-0.2, 0.2)])]
    y += ["", "devices:", "  force_plate:", "    protocol: ati_netcanoem", "    interface: vcan0", "    rate_hz: 1000",
          "    sensor_pose: {translation_m: [0.0, 0.0, 0.0]}",
          # The controller's pose as float32 registers: the UR map's 0.1 mm steps are coarser than
          # the contact's interference (50 N / K = 0.3 mm).
          "  robot:", "    transport: tcp", "    host: 127.0.0.1", "    port: 5020", "    unit_id: 1", "    rate_hz: 125",
          "    register_map: float32",
          "", "model:", "  contact:", "    stiffness_n_per_m: 1.8e5", "    friction_coefficient: 0.2",
          "    sticking_threshold_m_per_s: 3.0e-4", "    force_scale_n: 50.0", "    moment_scale_nm: 6.0",
          "  uncertainties:",
          "    - {name: grooves_depth, object: receptacle, feature: grooves, kind: translation, axis: [0, 0, 1], design_value: 0.0, prior_std: 3.0e-5}"]
    for k, (c, a, t) in enumerate(GUIDES, 1):
        y.append("    - {name: guide%d_shift, object: acu, feature: guide%d, kind: translation, axis: [%g, %g, 0], design_value: 0.0, prior_std: 1.0e-4}"
                 % (k, k, t[0], t[1]))
    for k, (c, a, t) in enumerate(GUIDES, 1):
        y.append("    - {name: guide%d_rot, object: acu, feature: guide%d, kind: rotation, axis: [0, 0, 1], point_m: [%g, %g, 0], design_value: 0.0, prior_std: 6.25e-3}"
                 % (k, k, c[0], c[1]))
    with open(os.path.join(HERE, "acu.yaml"), "w") as f:
        f.write("\n".join(y) + "\n")


def face_normals():
    """(guide centre, transverse unit, outward groove-face normal) for the 8 faces, nominal geometry."""
    out = []
    for c, a, t in GUIDES:
        for s in (-1.0, 1.0):
            # The wall on side s pushes the ridge towards -s t and up.
            n = (-s * t[0] * math.cos(ALPHA), -s * t[1] * math.cos(ALPHA), math.sin(ALPHA))
            out.append((c, a, t, s, n))
    return out


def vertical_force(dx, dy, phi, dz):
    """Nominal vertical force for an ACU displaced by (dx, dy, dz) and turned by phi about z."""
    fz = 0.0
    for c, a, t, s, n in face_normals():
        best = 0.0
        for v in (-L / 2 + 0.002, L / 2 - 0.002):  # the ends of the ridge faces
            px, py = c[0] + v * a[0], c[1] + v * a[1]
            qx = px * math.cos(phi) - py * math.sin(phi) + dx - px
            qy = px * math.sin(phi) + py * math.cos(phi) + dy - py
            pen = -(qx * n[0] + qy * n[1] + dz * n[2])
            best = max(best, pen)
        fz += K * best * n[2]
    return fz


def descend(dx, dy, phi):
    """dz giving the target vertical force (bisection; the force grows as dz decreases)."""
    lo, hi = -0.01, 0.02
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if vertical_force(dx, dy, phi, mid) > F_TARGET:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def smooth(s):
    s = min(1.0, max(0.0, s))
    return s * s * (3 - 2 * s)


def write_traj(name, pose_of, duration, rate=1000.0):
    """Poses at `rate`; velocities by central differences on that grid (as a robot controller would)."""
    n = int(duration * rate) + 1
    P = [pose_of(i / rate) for i in range(n)]
    with open(os.path.join(HERE, name), "w") as f:
        f.write("t,px,py,pz,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz\n")
        for i in range(n):
            a, b = P[max(0, i - 1)], P[min(n - 1, i + 1)]
            dt = (min(n - 1, i + 1) - max(0, i - 1)) / rate
            x, y, z, phi = P[i]
            f.write("%.4f,%.9g,%.9g,%.9g,%.12g,0,0,%.12g,%.6g,%.6g,%.6g,0,0,%.6g\n" % (
                i / rate, x, y, z, math.cos(phi / 2), math.sin(phi / 2),
                (b[0] - a[0]) / dt, (b[1] - a[1]) / dt, (b[2] - a[2]) / dt, (b[3] - a[3]) / dt))


def test_1a(t):
    # 0-2 s: retracted 2.7 cm and turned 2 deg; 2-4 s: lowered to first contact; 4-24 s: insertion
    # while the grooves turn it back; 24-30 s: pressed home.
    phi0 = math.radians(2.0)
    if t < 2.0:
        return 0.0, 0.0, 0.027, phi0
    z_touch = Z_TOUCH_1A
    if t < 4.0:
        return 0.0, 0.0, 0.027 + (z_touch - 0.027) * smooth((t - 2.0) / 2.0), phi0
    phi = phi0 * (1.0 - smooth((t - 4.0) / 20.0))
    dz = descend(0.0, 0.0, phi)
    blend = smooth((t - 4.0) / 1.0)
    return 0.0, 0.0, z_touch + (dz - z_touch) * blend, phi


def test_2a(t):
    # 0-2 s: retracted, 2-4 s: translated by 2.7 cm, 4-6 s: back to a 6 mm offset and lowered to
    # first contact, 6-26 s: insertion while the grooves centre the ACU, 26-32 s: pressed home.
    e0 = 0.006
    if t < 2.0:
        return 0.0, 0.0, 0.027, 0.0
    if t < 4.0:
        return 0.027 * smooth((t - 2.0) / 2.0), 0.0, 0.027, 0.0
    z_touch = Z_TOUCH_2A
    if t < 6.0:
        s = smooth((t - 4.0) / 2.0)
        return 0.027 + (e0 - 0.027) * s, 0.0, 0.027 + (z_touch - 0.027) * s, 0.0
    e = e0 * (1.0 - smooth((t - 6.0) / 20.0))
    dz = descend(e, 0.0, 0.0)
    blend = smooth((t - 6.0) / 1.0)
    return e, 0.0, z_touch + (dz - z_touch) * blend, 0.0


TRUTH_GEOM = {  # hidden from the nominal rig: V-guide shifts (m) and rotations (rad)
    "grooves_depth": 0.0,
    "guide1_shift": 1.2e-4, "guide2_shift": -0.8e-4, "guide3_shift": 0.6e-4, "guide4_shift": -1.0e-4,
    "guide1_rot": 2.0e-4, "guide2_rot": -1.5e-4, "guide3_rot": 1.0e-4, "guide4_rot": -2.5e-4,
}


def write_truth(name, mu, seed):
    with open(os.path.join(HERE, name), "w") as f:
        f.write("# Hidden truth for `hil contact simulate --truth` (examples/acu/make_acu.py).\n")
        f.write("stiffness_n_per_m: 1.8e5\nfriction_coefficient: %g\n" % mu)
        f.write("sensor:\n  position_resolution_m: 2.0e-6\n  velocity_resolution_m_per_s: 2.0e-4\n"
                "  force_resolution_n: 1.5\n  moment_resolution_nm: 0.05\n  force_noise_n: 0.3\n"
                "  moment_noise_nm: 0.02\n  seed: %d\n" % seed)
        f.write("geometric:\n")
        for k, v in TRUTH_GEOM.items():
            f.write("  %s: %g\n" % (k, v))


Z_TOUCH_1A = descend(0.0, 0.0, math.radians(2.0)) + 0.001
Z_TOUCH_2A = descend(0.006, 0.0, 0.0) + 0.001

if __name__ == "__main__":
    write_rig()
    write_traj("traj_1a.csv", test_1a, 30.0)
    write_traj("traj_2a.csv", test_2a, 32.0)
    write_truth("truth_1a.yaml", 0.08, 1)
    write_truth("truth_2a.yaml", 0.2, 2)
