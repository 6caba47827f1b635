"""Builds CasADi functions for the mass matrix M(q) and the inverse dynamics with zero
acceleration, C(q, qd) qd + g(q) (recursive Newton-Euler), of a ball-finger scene file (its DH
table, masses, centres of mass and inertias), and writes them as C with CasADi's code generator.

The model follows the scene conventions of bf-codegen: standard DH,
A_i = Rz(q_i + offset_i) Tz(d_i) Tx(a_i) Rx(alpha_i), world frame = base transform, centre of
mass and inertia about it in link-frame axes, gravity vector g_0 in world axes. sin/cos of DH
angles that are multiples of pi/2 are exact (0, +-1), as in bf-codegen.

Usage: python casadi_model.py SCENE.toml OUT_DIR
Writes OUT_DIR/<scene>_casadi.c with three functions (all with CasADi's common subexpression
elimination): <scene>_fused(q, qd) -> (M, tau), <scene>_mass(q) -> M, <scene>_rnea(q, qd) -> tau.
M is column-major (symmetric), tau = C qd + g.
"""

import math
import os
import re
import sys
import tomllib

import casadi as ca


def angle(v):
    """(radians, exact (sin, cos) or None) of a scene angle: a number or "k*pi/n"."""
    if isinstance(v, (int, float)):
        return float(v), None
    s = v.replace(" ", "")
    m = re.fullmatch(r"([+-]?)(\d*)\*?pi(?:/(\d+))?", s)
    if not m:
        x = float(s)
        return x, None
    num = int(m.group(2) or "1") * (-1 if m.group(1) == "-" else 1)
    den = int(m.group(3) or "1")
    x = num * math.pi / den
    if (2 * num) % den == 0:  # a multiple of pi/2
        k = (2 * num // den) % 4
        return x, [(0.0, 1.0), (1.0, 0.0), (0.0, -1.0), (-1.0, 0.0)][k]
    return x, None


def sc(v):
    x, exact = angle(v)
    return exact if exact else (math.sin(x), math.cos(x))


def rot_axis(axis, v):
    s, c = sc(v)
    if axis == "x":
        return ca.DM([[1, 0, 0], [0, c, -s], [0, s, c]])
    if axis == "y":
        return ca.DM([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return ca.DM([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def base_transform(scene):
    b = scene.get("base", {})
    t = ca.DM(b.get("translation", [0.0, 0.0, 0.0]))
    r = b.get("rotation")
    if r is None:
        R = ca.DM.eye(3)
    elif isinstance(r, dict):
        R = rot_axis(r["axis"], r["angle"])
    else:
        R = ca.DM(r)
    return R, t


def inertia(v):
    if isinstance(v[0], list):
        return ca.DM(v)
    return ca.diag(ca.DM(v))


def model(scene):
    if scene.get("dh", "standard") != "standard":
        raise SystemExit("only standard DH is implemented here")
    links = scene["links"]
    n = len(links)
    q = ca.SX.sym("q", n)
    qd = ca.SX.sym("qd", n)
    g0 = ca.DM(scene.get("gravity", [0.0, 0.0, -9.81]))
    R, o = base_transform(scene)
    R = ca.SX(R)
    o = ca.SX(o)
    frames = []  # (z_{i-1}, o_{i-1}, R_i, o_i) in world axes
    for i, l in enumerate(links):
        z_prev, o_prev = R[:, 2], o
        th_off = angle(l.get("offset", 0.0))[0]
        th = q[i] + th_off
        st, ct = ca.sin(th), ca.cos(th)
        sa, ca_ = sc(l.get("alpha", 0.0))
        a, d = float(l.get("a", 0.0)), float(l.get("d", 0.0))
        A_R = ca.vertcat(
            ca.horzcat(ct, -st * ca_, st * sa),
            ca.horzcat(st, ct * ca_, -ct * sa),
            ca.horzcat(0, sa, ca_),
        )
        A_t = ca.vertcat(a * ct, a * st, d)
        o = o + R @ A_t
        R = R @ A_R
        frames.append((z_prev, o_prev, R, o))
    coms = [frames[i][3] + frames[i][2] @ ca.DM(l["com"]) for i, l in enumerate(links)]
    Iw = [frames[i][2] @ inertia(l["inertia"]) @ frames[i][2].T for i, l in enumerate(links)]
    masses = [float(l["mass"]) for l in links]

    # M = sum m J_v^T J_v + J_w^T I_w J_w (eq. 22a).
    M = ca.SX.zeros(n, n)
    for i in range(n):
        Jv = ca.jacobian(coms[i], q)
        Jw = ca.horzcat(*[frames[j][0] if j <= i else ca.SX.zeros(3) for j in range(n)])
        M += masses[i] * Jv.T @ Jv + Jw.T @ Iw[i] @ Jw

    # RNEA with qdd = 0 (world axes; base acceleration -g0 carries gravity).
    w = ca.SX.zeros(3)
    wd = ca.SX.zeros(3)
    acc = ca.SX(-g0)
    o_prev = frames[0][1]
    ac = []
    ws, wds = [], []
    for i in range(n):
        z, op, _, oi = frames[i]
        wd = wd + ca.cross(w, z * qd[i])
        w = w + z * qd[i]
        r = oi - op
        acc = acc + ca.cross(wd, r) + ca.cross(w, ca.cross(w, r))
        rc = coms[i] - oi
        ac.append(acc + ca.cross(wd, rc) + ca.cross(w, ca.cross(w, rc)))
        ws.append(w)
        wds.append(wd)
    f_next = ca.SX.zeros(3)
    n_next = ca.SX.zeros(3)
    tau = [None] * n
    for i in reversed(range(n)):
        z, op, _, oi = frames[i]
        fi = masses[i] * ac[i] + f_next
        ni = (
            n_next
            + ca.cross(oi - op, f_next)
            + ca.cross(coms[i] - op, masses[i] * ac[i])
            + Iw[i] @ wds[i]
            + ca.cross(ws[i], Iw[i] @ ws[i])
        )
        tau[i] = ca.dot(z, ni)
        f_next, n_next = fi, ni
    tau = ca.vertcat(*tau)
    return q, qd, M, tau


def main():
    scene_path, out_dir = sys.argv[1], sys.argv[2]
    with open(scene_path, "rb") as f:
        scene = tomllib.load(f)
    name = scene["name"]
    q, qd, M, tau = model(scene)
    opts = {"cse": True}
    fused = ca.Function(f"{name}_fused", [q, qd], [M, tau], ["q", "qd"], ["M", "tau"], opts)
    mass = ca.Function(f"{name}_mass", [q], [M], ["q"], ["M"], opts)
    rnea = ca.Function(f"{name}_rnea", [q, qd], [tau], ["q", "qd"], ["tau"], opts)
    cg = ca.CodeGenerator(f"{name}_casadi.c", {"with_header": True})
    for fn in (fused, mass, rnea):
        cg.add(fn)
    os.makedirs(out_dir, exist_ok=True)
    cg.generate(out_dir + os.sep)
    print(
        f"{name}: n = {len(scene['links'])}; CasADi operations: fused {fused.n_instructions()}, "
        f"mass {mass.n_instructions()}, rnea {rnea.n_instructions()} (instructions)"
    )


if __name__ == "__main__":
    main()
