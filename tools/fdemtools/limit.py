"""`limit`: rigid-block limit analysis of a case (issue 49), by linear programming with scipy's HiGHS.

The model comes from the engine: `fdem mesh CASE --out DIR` writes DIR/limit_model.json (fdem/limit_export.hpp:
rigid bodies, interface segments, groups, the last stage's supports and loads, gravity), so the bodies and joints are
those `fdem run` uses and no case file is parsed here.

Static (lower-bound) formulation, after Livesley (1978), "Limit analysis of structures formed from rigid blocks",
IJNME 12, 1853-1871: at both end points of every interface segment a normal force n (compression positive) and a
tangential force t, with

    n >= 0                       (no tension; --bonded: n >= -f_t A, A = half the segment length x thickness)
    |t| <= mu n                  (Coulomb friction, mu = tan(phi); --bonded: |t| <= mu n + c A)

and the equilibrium of every free rigid body (two forces and the moment about its centroid) under the dead loads
(weights, the stage's loads) plus lambda times the live load (the stage's driving action). Maximise lambda.
Reactions: a body with nodes fixed in x and y at two or more distinct points is fixed (no equations); any other
constrained DOF (a pinned node, a fixed component, a rigid group) gets a free reaction at that node.

Kinematic (upper-bound) formulation, written separately for the tests: body velocities (u, v, omega); at each
contact point the jump of the velocity of body b over body a, normal w_n and tangential w_t, follows the associative
flow rule w_n = r1 + mu (r2 + r3), w_t = r3 - r2 with multipliers r >= 0 of the three yield planes; the live load's
power is 1 and lambda = min (dissipation - dead-load power), the dissipation being r1 f_t A + (r2 + r3) c A. LP duality
makes both optima equal; the mechanism printed is the static LP's dual (the equilibrium rows' multipliers are the
bodies' virtual velocities).

Non-associative estimate, after Gilbert, Casapulla & Ahmed (2006), "Limit analysis of masonry block structures with
non-associative frictional joints using linear programming", Computers & Structures 84, 873-887: the friction limit
is replaced by |t| <= mu n_prev (+ c A), n_prev the normal forces of the previous solution (the associative one
first), and the LP solved again until the load factor changes by less than 1e-4 of itself between two iterations
(the LP's forces are not unique, so the last iterates of a wall scatter by some 1e-5 of the factor). The joints then slide
without dilating. It is an estimate: the solution need not be unique nor the iteration converge, and it is never a
bound.
"""
from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import tempfile
import time

import numpy as np

from .common import ToolError, write_csv, write_json

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# HiGHS tolerances: tighter than its defaults (1e-7), so that the static and kinematic optima agree to 1e-9.
HIGHS_OPTIONS = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}


# ------------------------------------------------------------------------------------------------ export

def fdem_binary(given: str | None) -> str:
    from .batch import fdem_binary as fb
    return fb(given)


def export_model(case: str, sets: list | None, fdem: str | None, out_dir: str) -> tuple:
    """Runs `fdem mesh CASE --out out_dir [--set ...]`; returns (the model dict, seconds)."""
    exe = fdem_binary(fdem)
    cmd = [exe, "mesh", case, "--out", out_dir]
    for s in sets or []:
        cmd += ["--set", s]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, OMP_NUM_THREADS="1"))
    dt = time.perf_counter() - t0
    if r.returncode != 0:
        msg = (r.stderr.strip() or r.stdout.strip()).splitlines()
        raise ToolError(f"fdem mesh failed (exit {r.returncode}): " + (" | ".join(msg[-3:]) if msg else "no message"))
    path = os.path.join(out_dir, "limit_model.json")
    if not os.path.isfile(path):
        raise ToolError(f"{exe} wrote no limit_model.json (an fdem build older than issue 49?)")
    with open(path, encoding="utf-8") as f:
        return json.load(f), dt


# ------------------------------------------------------------------------------------------------ problem

class Refused(ToolError):
    """The case's loading has no limit-analysis reading (a settlement, no driving action)."""


class Problem:
    """The rigid-block model of one case: bodies, contact points, supports, dead and live loads.

    All forces are kept in N and lengths in m here; the LP builders scale them (F0, L0).
    """

    def __init__(self, model: dict, bonded: bool = False):
        self.model = model
        self.bonded = bonded
        self.t = float(model["case"]["thickness"])
        self.notes: list = []
        bodies = model["bodies"]
        self.nb = len(bodies)
        self.mass = np.array([b["mass"] for b in bodies], float)
        self.centroid = np.array([b["centroid"] for b in bodies], float)
        self.node_xy = np.asarray(model["nodes"]["xy"], float).reshape(-1, 2)
        self.node_body = np.asarray(model["nodes"]["body"], int)
        self.groups = model["groups"]
        span = self.node_xy.max(axis=0) - self.node_xy.min(axis=0) if len(self.node_xy) else np.ones(2)
        self.L0 = float(max(span.max(), 1e-12))
        self._points()
        self._supports()
        self._loads()

    # contact points: both ends of every interface segment
    def _points(self):
        P = []
        segs = self.model["interfaces"]
        self.segments = []
        missing = 0
        for i, s in enumerate(segs):
            phi = s["friction_deg"]
            if phi is None:
                missing += 1
                continue
            p0, p1 = np.array(s["p0"], float), np.array(s["p1"], float)
            d = p1 - p0
            L = float(np.hypot(*d))
            if not L > 0:
                continue
            sv = d / L
            nv = np.array([sv[1], -sv[0]])  # from body a into body b
            mu = math.tan(math.radians(phi))
            bonded = self.bonded and s["kind"] == "bonded"
            c = float(s["cohesion"] or 0.0) if bonded else 0.0
            ft = float(s["tensile_strength"] or 0.0) if bonded else 0.0
            A = 0.5 * L * self.t
            self.segments.append({"index": i, "kind": s["kind"], "a": s["body_a"], "b": s["body_b"], "p0": p0,
                                  "p1": p1, "points": (len(P), len(P) + 1)})
            for p in (p0, p1):
                P.append((s["body_a"], s["body_b"], p, nv, sv, mu, c * A, ft * A))
        if missing:
            self.notes.append(f"{missing} interface segment(s) without a friction rule left out")
        self.np = len(P)
        self.pa = np.array([p[0] for p in P], int)
        self.pb = np.array([p[1] for p in P], int)
        self.pxy = np.array([p[2] for p in P], float).reshape(-1, 2)
        self.pn = np.array([p[3] for p in P], float).reshape(-1, 2)
        self.ps = np.array([p[4] for p in P], float).reshape(-1, 2)
        self.mu = np.array([p[5] for p in P], float)
        self.cA = np.array([p[6] for p in P], float)
        self.ftA = np.array([p[7] for p in P], float)
        self.n_joints = len({(min(s["a"], s["b"]), max(s["a"], s["b"])) for s in self.segments})

    # supports: fixed bodies, reactions, driving actions
    def _supports(self):
        g = np.array(self.model["gravity"]["vector"], float)
        self.gravity = g
        fixed_pts = {}            # body -> set of fixed-xy positions
        comp_nodes = {}           # (node, comp) -> mode, for the reaction list
        drivers = {}              # group -> [vx, vy]
        rigid_groups = []         # (comp, nodes)
        self.settlement = None
        for s in self.model["supports"]:
            c = 0 if s["component"] == "x" else 1
            mode = s["mode"]
            nodes = s["nodes"]
            if mode == "velocity" and s["velocity"] == 0:
                mode = "fixed"
            if mode == "protocol":
                u = s["protocol_first_displacement"] or 0.0
                mode, vel = ("fixed", 0.0) if u == 0 else ("velocity", math.copysign(1.0, u))
            else:
                vel = s["velocity"]
            if mode == "fixed":
                for n in nodes:
                    comp_nodes[(n, c)] = "fixed"
            elif mode == "velocity":
                if s["has_function"]:
                    self.notes.append(f"support on '{s['group']}' has a time function: its direction taken from vx/vy")
                drivers.setdefault(s["group"], [0.0, 0.0, []])
                drivers[s["group"]][c] = vel
                drivers[s["group"]][2] = sorted(set(drivers[s["group"]][2]) | set(nodes))
            elif mode == "rigid":
                rigid_groups.append((c, list(nodes), s["group"]))
            elif mode == "rigid_body" and c == 0:
                if len({int(self.node_body[n]) for n in nodes}) > 1:
                    self.notes.append(f"support on '{s['group']}' (rigid = \"body\") joins several blocks into one "
                                      "rigid body in the run; the limit model keeps them separate")
        # a body fixed in x and y at two or more distinct points is fixed
        xy_fixed = [n for (n, c), m in comp_nodes.items() if c == 0 and comp_nodes.get((n, 1)) == "fixed"]
        for n in xy_fixed:
            b = int(self.node_body[n])
            fixed_pts.setdefault(b, set()).add(tuple(np.round(self.node_xy[n] / self.L0, 9)))
        self.fixed = np.zeros(self.nb, bool)
        for b, pts in fixed_pts.items():
            if len(pts) >= 2:
                self.fixed[b] = True
        # settlement: a driven support moving along gravity
        self.drivers = []
        for grp, (vx, vy, nodes) in drivers.items():
            v = np.array([vx, vy])
            if np.dot(v, g) > 0 and np.hypot(*g) > 0:
                self.settlement = grp
            self.drivers.append((grp, v / np.hypot(*v), nodes))
        # reactions at single nodes: (body, point, direction); fixed bodies need none
        R = {}
        for (n, c), m in comp_nodes.items():
            b = int(self.node_body[n])
            if self.fixed[b] or any(n in d[2] for d in self.drivers if d[1][c] != 0):
                continue
            key = (b, c) + tuple(np.round(self.node_xy[n] / self.L0, 9))
            R[key] = (b, self.node_xy[n].copy(), c)
        self.reactions = list(R.values())
        self.rigid = []  # (comp, list of (body, point)) whose reactions sum to zero
        for c, nodes, grp in rigid_groups:
            if any(self.fixed[self.node_body[n]] for n in nodes):
                # the group's common velocity is that of a fixed body: each node is held in that component
                for n in nodes:
                    b = int(self.node_body[n])
                    if not self.fixed[b]:
                        key = (b, c) + tuple(np.round(self.node_xy[n] / self.L0, 9))
                        R[key] = (b, self.node_xy[n].copy(), c)
                self.reactions = list(R.values())
                continue
            items = [(int(self.node_body[n]), self.node_xy[n].copy()) for n in nodes]
            self.rigid.append((c, items, grp))
        self.tilt_rate = float(self.model["gravity"].get("tilt_rate_deg_s") or 0.0)

    # dead and live loads per body: [Fx, Fy, M about the centroid]
    def _wrench(self, b, p, f):
        r = p - self.centroid[b]
        return np.array([f[0], f[1], r[0] * f[1] - r[1] * f[0]])

    def _loads(self):
        nb = self.nb
        self.dead_gravity = np.zeros((nb, 3))
        self.dead_other = np.zeros((nb, 3))
        self.live = np.zeros((nb, 3))
        g = self.gravity
        for b in range(nb):
            self.dead_gravity[b, :2] = self.mass[b] * g
        for ld in self.model["loads"]:
            if ld["kind"] == "spring":
                v = ld["spring_velocity"] or 0.0
                if v != 0:
                    c = 0 if ld["spring_component"] == "x" else 1
                    d = np.zeros(2)
                    d[c] = math.copysign(1.0, v)
                    nodes = self.groups[ld["group"]]["nodes"]
                    self.drivers.append((ld["group"], d, nodes))
                continue
            if ld["kind"] == "foundation":
                self.notes.append(f"load on '{ld['group']}' is an elastic foundation: left out of the rigid-block model")
                continue
            if ld["has_function"]:
                self.notes.append(f"load on '{ld['group']}' has a time function: taken at its set value")
            for n, fx, fy in ld["node_forces"]:
                b = int(self.node_body[int(n)])
                self.dead_other[b] += self._wrench(b, self.node_xy[int(n)], (fx, fy))
        if self.model["gravity"].get("has_function"):
            self.notes.append("gravity has a time function: taken at its set value")
        self.mode = "load"
        if self.tilt_rate != 0:
            if self.drivers:
                raise Refused("the last stage both tilts gravity and drives a support: one driving action expected")
            if not np.hypot(*g) > 0:
                raise Refused("the last stage tilts gravity, but gravity is zero")
            self.mode = "tilt"
            sgn = 1.0 if self.tilt_rate > 0 else -1.0
            gperp = sgn * np.array([-g[1], g[0]])  # d g / d alpha for the stage's turning sense
            for b in range(nb):
                self.live[b, :2] = self.mass[b] * gperp
            self.live_total = float(self.mass.sum() * np.hypot(*g))
            return
        if self.settlement is not None:
            raise Refused(f"the last stage moves group '{self.settlement}' along gravity: a settlement (a prescribed "
                          "support movement) has no load to multiply; the rigid-block answer is the mechanism, not a "
                          "factor, so limit analysis is not run (give a driving load or a tilt instead)")
        if not self.drivers:
            raise Refused("the last stage has no driving action (no support driven at a velocity or protocol, no "
                          "spring with a velocity, no tilt_rate): nothing to take as the live load")
        for grp, d, nodes in self.drivers:
            nodes = list(nodes)
            f = d / len(nodes)  # a unit total along the drive, equal shares over the group's nodes
            for n in nodes:
                b = int(self.node_body[n])
                self.live[b] += self._wrench(b, self.node_xy[n], f)
        self.live_total = float(len(self.drivers))
        self.driver_groups = [d[0] for d in self.drivers]
        self.driver_direction = [d[1].tolist() for d in self.drivers]

    @property
    def free(self):
        return np.flatnonzero(~self.fixed)


# ------------------------------------------------------------------------------------------------ LPs

def _point_wrench_rows(pr: Problem, body_row: dict, L0: float):
    """Sparse triplets: the wrench on the free bodies of a unit force at each point along a direction.
    Returns a function f(directions (np x 2), column offset) -> (rows, cols, vals)."""
    def build(dirs, col0):
        rows, cols, vals = [], [], []
        for k in range(pr.np):
            for b, sgn in ((pr.pb[k], 1.0), (pr.pa[k], -1.0)):
                r0 = body_row.get(int(b))
                if r0 is None:
                    continue
                f = sgn * dirs[k]
                r = (pr.pxy[k] - pr.centroid[b]) / L0
                w = (f[0], f[1], r[0] * f[1] - r[1] * f[0])
                for i in range(3):
                    if w[i] != 0:
                        rows.append(r0 + i), cols.append(col0 + k), vals.append(w[i])
        return rows, cols, vals
    return build


def static_lp(pr: Problem, friction_ref: np.ndarray | None = None, const_scale: float = 1.0, dead_scale=None):
    """Maximises the load factor. friction_ref: fixed normal forces (N) in the friction limit (the non-associative
    iteration); const_scale multiplies the constant capacities and non-gravity dead loads (the tilt iteration).
    Returns a dict: lam, status, message, n, t (N), velocities (nb x 3: u, v, omega; zero on fixed bodies), time."""
    from scipy.optimize import linprog
    from scipy.sparse import coo_matrix
    free = pr.free
    body_row = {int(b): 3 * i for i, b in enumerate(free)}
    nfree = len(free)
    L0 = pr.L0
    dead = pr.dead_gravity + const_scale * pr.dead_other
    F0 = max(float(np.abs(dead[:, :2]).sum()), float(np.abs(pr.cA).sum()), 1e-30)
    lt = pr.live_total
    P, R = pr.np, len(pr.reactions)
    nrig = sum(len(items) for _, items, _ in pr.rigid)
    # variables: lambda_s, n (P), t (P), reactions (R), rigid-group reactions (nrig)
    nv = 1 + 2 * P + R + nrig
    ilam, in0, it0, ir0, ig0 = 0, 1, 1 + P, 1 + 2 * P, 1 + 2 * P + R
    build = _point_wrench_rows(pr, body_row, L0)
    rows, cols, vals = [], [], []
    for part in (build(pr.pn, in0), build(pr.ps, it0)):
        rows.extend(part[0])
        cols.extend(part[1])
        vals.extend(part[2])

    def add_force(col, b, p, f):
        r0 = body_row.get(int(b))
        if r0 is None:
            return
        r = (p - pr.centroid[b]) / L0
        w = (f[0], f[1], r[0] * f[1] - r[1] * f[0])
        for i in range(3):
            if w[i] != 0:
                rows.append(r0 + i), cols.append(col), vals.append(w[i])

    for j, (b, p, c) in enumerate(pr.reactions):
        e = np.zeros(2)
        e[c] = 1.0
        add_force(ir0 + j, b, p, e)
    j = 0
    rig_rows = []
    for c, items, _ in pr.rigid:
        e = np.zeros(2)
        e[c] = 1.0
        cols_g = []
        for b, p in items:
            add_force(ig0 + j, b, p, e)
            cols_g.append(ig0 + j)
            j += 1
        rig_rows.append(cols_g)
    # live load column (scaled so that the live load's total is F0: lambda = lam_s F0 / live_total)
    live_s = pr.live / lt
    for b in free:
        r0 = body_row[int(b)]
        w = live_s[b] * np.array([1.0, 1.0, 1.0 / L0])
        for i in range(3):
            if w[i] != 0:
                rows.append(r0 + i), cols.append(ilam), vals.append(w[i])
    neq = 3 * nfree + len(rig_rows)
    for k, cg in enumerate(rig_rows):
        for cc in cg:
            rows.append(3 * nfree + k), cols.append(cc), vals.append(1.0)
    Aeq = coo_matrix((vals, (rows, cols)), shape=(neq, nv)).tocsr()
    beq = np.zeros(neq)
    for b in free:
        r0 = body_row[int(b)]
        beq[r0:r0 + 3] = -dead[b] / F0 * np.array([1.0, 1.0, 1.0 / L0])
    # friction: t - mu n <= cA, -t - mu n <= cA (or |t| <= mu n_ref + cA with n_ref fixed)
    cap = const_scale * pr.cA / F0
    ur, uc, uv = [], [], []
    bub = np.zeros(2 * P)
    for k in range(P):
        for s, row in ((1.0, 2 * k), (-1.0, 2 * k + 1)):
            ur.append(row), uc.append(it0 + k), uv.append(s)
            if friction_ref is None:
                ur.append(row), uc.append(in0 + k), uv.append(-pr.mu[k])
                bub[row] = cap[k]
            else:
                bub[row] = cap[k] + pr.mu[k] * max(friction_ref[k], 0.0) / F0
    Aub = coo_matrix((uv, (ur, uc)), shape=(2 * P, nv)).tocsr()
    bounds = [(None, None)] + [(-const_scale * f / F0, None) for f in pr.ftA] + [(None, None)] * (P + R + nrig)
    cvec = np.zeros(nv)
    cvec[ilam] = -1.0
    t0 = time.perf_counter()
    res = linprog(cvec, A_ub=Aub if P else None, b_ub=bub if P else None, A_eq=Aeq, b_eq=beq, bounds=bounds,
                  method="highs", options=HIGHS_OPTIONS)
    solve_s = time.perf_counter() - t0
    out = {"status": int(res.status), "message": str(res.message), "solve_s": solve_s, "variables": nv,
           "equalities": neq, "inequalities": 2 * P, "F0": F0}
    if res.status != 0:
        out["lam"] = math.nan
        return out
    x = res.x
    out["lam"] = float(x[ilam] * F0 / lt)
    out["n"] = x[in0:in0 + P] * F0
    out["t"] = x[it0:it0 + P] * F0
    y = np.asarray(res.eqlin.marginals, float)
    vel = np.zeros((pr.nb, 3))
    for b in free:
        r0 = body_row[int(b)]
        vel[b] = y[r0:r0 + 3] * np.array([1.0, 1.0, 1.0 / L0])
    # sign: the live load does positive work
    pw = float(np.sum(pr.live[:, :2] * vel[:, :2]) + np.sum(pr.live[:, 2] * vel[:, 2]))
    if pw < 0:
        vel = -vel
        pw = -pw
    if pw > 0:
        vel = vel / pw
    out["velocities"] = vel
    return out


def kinematic_lp(pr: Problem, const_scale: float = 1.0):
    """Upper-bound formulation (see the module text): min dissipation - dead-load power, live power 1."""
    from scipy.optimize import linprog
    from scipy.sparse import coo_matrix
    free = pr.free
    col = {int(b): 3 * i for i, b in enumerate(free)}
    nfree = len(free)
    L0 = pr.L0
    dead = pr.dead_gravity + const_scale * pr.dead_other
    F0 = max(float(np.abs(dead[:, :2]).sum()), float(np.abs(pr.cA).sum()), 1e-30)
    P = pr.np
    nrig = len(pr.rigid)
    # variables: body velocities (u, v, omega L0) per free body, r1, r2, r3 per point, a common velocity per rigid group
    nvar = 3 * nfree + 3 * P + nrig
    ir = 3 * nfree
    rows, cols, vals = [], [], []
    rhs = []
    row = 0

    def point_velocity_terms(b, p, d):
        """(column, coefficient) pairs of the velocity of body b at point p along d."""
        c0 = col.get(int(b))
        if c0 is None:
            return []
        r = (p - pr.centroid[b]) / L0
        # v(p) = (u - omega r_y, v + omega r_x), omega in units of 1/L0
        return [(c0, d[0]), (c0 + 1, d[1]), (c0 + 2, -r[1] * d[0] + r[0] * d[1])]

    for k in range(P):
        p = pr.pxy[k]
        for d, flow in ((pr.pn[k], [(ir + 3 * k, -1.0), (ir + 3 * k + 1, -pr.mu[k]), (ir + 3 * k + 2, -pr.mu[k])]),
                        (pr.ps[k], [(ir + 3 * k + 1, 1.0), (ir + 3 * k + 2, -1.0)])):
            terms = point_velocity_terms(pr.pb[k], p, d) + [(c, -v) for c, v in point_velocity_terms(pr.pa[k], p, d)]
            for c, v in terms + flow:
                if v != 0:
                    rows.append(row), cols.append(c), vals.append(v)
            rhs.append(0.0)
            row += 1
    for b, p, c in pr.reactions:
        e = np.zeros(2)
        e[c] = 1.0
        terms = point_velocity_terms(b, p, e)
        if terms:
            for cc, v in terms:
                if v != 0:
                    rows.append(row), cols.append(cc), vals.append(v)
            rhs.append(0.0)
            row += 1
    for g, (c, items, _) in enumerate(pr.rigid):
        e = np.zeros(2)
        e[c] = 1.0
        for b, p in items:
            for cc, v in point_velocity_terms(b, p, e) + [(3 * nfree + 3 * P + g, -1.0)]:
                if v != 0:
                    rows.append(row), cols.append(cc), vals.append(v)
            rhs.append(0.0)
            row += 1
    live_s = pr.live / pr.live_total
    for b in free:
        c0 = col[int(b)]
        for i, s in enumerate((1.0, 1.0, 1.0 / L0)):
            if live_s[b, i] != 0:
                rows.append(row), cols.append(c0 + i), vals.append(live_s[b, i] * s)
    rhs.append(1.0)
    row += 1
    Aeq = coo_matrix((vals, (rows, cols)), shape=(row, nvar)).tocsr()
    cvec = np.zeros(nvar)
    for b in free:
        c0 = col[int(b)]
        cvec[c0:c0 + 3] = -dead[b] / F0 * np.array([1.0, 1.0, 1.0 / L0])
    for k in range(P):
        cvec[ir + 3 * k] = const_scale * pr.ftA[k] / F0
        cvec[ir + 3 * k + 1] = cvec[ir + 3 * k + 2] = const_scale * pr.cA[k] / F0
    bounds = [(None, None)] * (3 * nfree) + [(0, None)] * (3 * P) + [(None, None)] * nrig
    t0 = time.perf_counter()
    res = linprog(cvec, A_eq=Aeq, b_eq=np.array(rhs), bounds=bounds, method="highs", options=HIGHS_OPTIONS)
    out = {"status": int(res.status), "message": str(res.message), "solve_s": time.perf_counter() - t0}
    out["lam"] = float(res.fun * F0 / pr.live_total) if res.status == 0 else math.nan
    return out


def nonassociative(pr: Problem, assoc: dict, const_scale: float = 1.0, tol: float = 1e-4, max_iter: int = 50):
    """Gilbert, Casapulla & Ahmed (2006): friction limits from the previous normal forces, until lambda settles."""
    n_ref = np.asarray(assoc["n"], float)
    lam_prev = assoc["lam"]
    history = [lam_prev]
    for it in range(1, max_iter + 1):
        r = static_lp(pr, friction_ref=n_ref, const_scale=const_scale)
        if r["status"] != 0:
            return {"lam": math.nan, "iterations": it, "converged": False, "history": history,
                    "message": r["message"]}
        history.append(r["lam"])
        if abs(r["lam"] - lam_prev) <= tol * max(abs(r["lam"]), 1e-300):
            return {"lam": r["lam"], "iterations": it, "converged": True, "history": history, "result": r}
        lam_prev = r["lam"]
        n_ref = r["n"]
    return {"lam": lam_prev, "iterations": max_iter, "converged": False, "history": history, "result": r}


def solve(pr: Problem, nonassoc: bool = True) -> dict:
    """The associative factor (and for a tilt the critical angle), the mechanism and the non-associative estimate."""
    def tilt_iter(fun):
        # lambda = tan(alpha) exactly when every force scales with gravity; other dead loads and the cohesion are
        # constant, so they are divided by cos(alpha) and alpha found by a fixed point.
        const = 1.0
        r = fun(const)
        if pr.mode != "tilt" or not (np.abs(pr.dead_other).sum() > 0 or pr.cA.sum() > 0 or pr.ftA.sum() > 0):
            return r, 1
        for k in range(50):
            if r["status"] != 0:
                return r, k + 1
            const_new = 1.0 / math.cos(math.atan(r["lam"]))
            if abs(const_new - const) < 1e-12:
                return r, k + 1
            const = const_new
            r = fun(const)
        return r, 50

    assoc, _ = tilt_iter(lambda c: dict(static_lp(pr, const_scale=c), const_scale=c))
    out = {"assoc": assoc}
    if assoc["status"] != 0:
        return out
    if nonassoc:
        cs = assoc.get("const_scale", 1.0)
        na = nonassociative(pr, assoc, const_scale=cs)
        # The associative limit load bounds the non-associative one from above (Radenkovic's theorem), but an iterate
        # with fixed normal forces may land a little above it: the estimate is then the bound itself.
        na["uncapped"] = na["lam"]
        na["capped"] = bool(na["lam"] > assoc["lam"] * (1 + 1e-9))  # above round-off
        na["lam"] = min(na["lam"], assoc["lam"])
        out["nonassoc"] = na
    return out


# ------------------------------------------------------------------------------------------------ mechanism

def point_jumps(pr: Problem, vel: np.ndarray) -> tuple:
    """Normal and tangential velocity jumps (body b over body a) at every contact point."""
    def v_at(b, p):
        u = vel[b]
        r = p - pr.centroid[b]
        return np.array([u[0] - u[2] * r[1], u[1] + u[2] * r[0]])
    wn, wt = np.zeros(pr.np), np.zeros(pr.np)
    for k in range(pr.np):
        d = v_at(pr.pb[k], pr.pxy[k]) - v_at(pr.pa[k], pr.pxy[k])
        wn[k], wt[k] = d @ pr.pn[k], d @ pr.ps[k]
    return wn, wt


def node_velocities(pr: Problem, vel: np.ndarray) -> np.ndarray:
    b = pr.node_body
    r = pr.node_xy - pr.centroid[b]
    u = vel[b]
    return np.column_stack([u[:, 0] - u[:, 2] * r[:, 1], u[:, 1] + u[:, 2] * r[:, 0]])


def classify(pr: Problem, vel: np.ndarray, rel: float = 1e-4) -> dict:
    nv = node_velocities(pr, vel)
    scale = max(float(np.abs(nv).max()) if len(nv) else 0.0, 1e-300)
    wn, wt = point_jumps(pr, vel)
    opening = wn > rel * scale
    sliding = np.abs(wt) > rel * scale
    seg_open = np.array([opening[s["points"][0]] or opening[s["points"][1]] for s in pr.segments], bool)
    seg_slide = np.array([sliding[s["points"][0]] or sliding[s["points"][1]] for s in pr.segments], bool)
    bmax = np.abs(nv).max(axis=1)
    moving = np.zeros(pr.nb, bool)
    for b in range(pr.nb):
        sel = pr.node_body == b
        moving[b] = bool(sel.any() and bmax[sel].max() > rel * scale)
    return {"node_velocity": nv, "wn": wn, "wt": wt, "point_opening": opening, "point_sliding": sliding,
            "segment_opening": seg_open, "segment_sliding": seg_slide, "body_moving": moving, "scale": scale}


def write_vtu(path: str, pr: Problem, mech: dict) -> str:
    """VTK XML (ASCII): triangles with point data mechanism_velocity and cell data body; line cells for the joints
    with joint_opening / joint_sliding flags (two extra points per joint segment, carrying body a's velocity)."""
    tri = np.asarray(pr.model["triangles"]["nodes"], int).reshape(-1, 3)
    tri_body = np.asarray(pr.model["triangles"]["body"], int)
    xy = pr.node_xy
    nv = mech["node_velocity"]
    seg_pts, seg_vel = [], []
    for s in pr.segments:
        for k in s["points"]:
            seg_pts.append(pr.pxy[k])
            b = pr.pa[k]
            vb = mech["velocities"][b]
            r = pr.pxy[k] - pr.centroid[b]
            seg_vel.append([vb[0] - vb[2] * r[1], vb[1] + vb[2] * r[0]])
    pts = np.vstack([xy, np.array(seg_pts).reshape(-1, 2)])
    vel = np.vstack([nv, np.array(seg_vel).reshape(-1, 2)])
    nn, nt, ns = len(xy), len(tri), len(pr.segments)
    conn = [" ".join(map(str, t)) for t in tri] + [f"{nn + 2 * i} {nn + 2 * i + 1}" for i in range(ns)]
    offs = list(range(3, 3 * nt + 1, 3)) + [3 * nt + 2 * (i + 1) for i in range(ns)]
    types = [5] * nt + [3] * ns

    def arr(name, values, ncomp=1, typ="Float64"):
        body = " ".join(repr(float(v)) if typ == "Float64" else str(int(v)) for v in np.ravel(values))
        return (f'<DataArray type="{typ}" Name="{name}" NumberOfComponents="{ncomp}" format="ascii">'
                f"{body}</DataArray>\n")
    cell_body = np.concatenate([tri_body, -np.ones(ns, int)])
    op = np.concatenate([np.zeros(nt, int), mech["segment_opening"].astype(int)])
    sl = np.concatenate([np.zeros(nt, int), mech["segment_sliding"].astype(int)])
    nforce = np.concatenate([np.full(nt, np.nan), mech.get("segment_normal_force", np.full(ns, np.nan))])
    p3 = np.column_stack([pts, np.zeros(len(pts))])
    v3 = np.column_stack([vel, np.zeros(len(vel))])
    doc = ['<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian">\n'
           "<UnstructuredGrid>\n", f'<Piece NumberOfPoints="{len(pts)}" NumberOfCells="{nt + ns}">\n',
           "<Points>\n", arr("Points", p3, 3), "</Points>\n<Cells>\n",
           f'<DataArray type="Int64" Name="connectivity" format="ascii">{" ".join(conn)}</DataArray>\n',
           f'<DataArray type="Int64" Name="offsets" format="ascii">{" ".join(map(str, offs))}</DataArray>\n',
           f'<DataArray type="UInt8" Name="types" format="ascii">{" ".join(map(str, types))}</DataArray>\n',
           "</Cells>\n<PointData Vectors=\"mechanism_velocity\">\n", arr("mechanism_velocity", v3, 3),
           "</PointData>\n<CellData>\n", arr("body", cell_body, 1, "Int32"), arr("joint_opening", op, 1, "Int32"),
           arr("joint_sliding", sl, 1, "Int32"), arr("joint_normal_force", nforce), "</CellData>\n",
           "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n"]
    tmp = path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write("".join(doc))
    os.replace(tmp, path)
    return path


def plot_mechanism(path: str, pr: Problem, mech: dict, title: str) -> str:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection, PolyCollection
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    tri = np.asarray(pr.model["triangles"]["nodes"], int).reshape(-1, 3)
    tri_body = np.asarray(pr.model["triangles"]["body"], int)
    xy = pr.node_xy
    nv = mech["node_velocity"]
    vmax = max(float(np.abs(nv).max()), 1e-300)
    k = 0.08 * pr.L0 / vmax  # the largest virtual displacement drawn is 8 % of the model's size
    dxy = xy + k * nv
    fig, ax = plt.subplots(figsize=(8, 7))
    # body outlines: mesh edges (keyed by their end points' coordinates, so that the faces of a crack inside a unit
    # meet) on the free boundary or between two bodies
    key = np.round(xy / pr.L0, 9)
    edges = {}
    for e, t in enumerate(tri):
        for i in range(3):
            a, b = t[i], t[(i + 1) % 3]
            ka, kb = tuple(key[a]), tuple(key[b])
            k2 = (min(ka, kb), max(ka, kb))
            edges.setdefault(k2, []).append((a, b, tri_body[e]))
    outline = [lst[0][:2] for lst in edges.values() if len(lst) == 1 or len({x[2] for x in lst}) > 1]
    outline += [lst[1][:2] for lst in edges.values() if len(lst) > 1 and len({x[2] for x in lst}) > 1]
    ax.add_collection(LineCollection([xy[[a, b]] for a, b in outline], colors="0.75", linewidths=0.5, zorder=1))
    moving = mech["body_moving"][tri_body]
    fixed = pr.fixed[tri_body]
    colours = np.where(fixed, "0.55", np.where(moving, "#e8b86d", "#cdd9e5"))
    ax.add_collection(PolyCollection(dxy[tri], facecolors=colours, edgecolors="none", alpha=0.9, zorder=2))
    ax.add_collection(LineCollection([dxy[[a, b]] for a, b in outline], colors="k", linewidths=0.6, zorder=3))
    op = [np.array([s["p0"], s["p1"]]) for s, o in zip(pr.segments, mech["segment_opening"]) if o]
    sl = [np.array([s["p0"], s["p1"]]) for s, o in zip(pr.segments, mech["segment_sliding"]) if o]
    if op:
        ax.add_collection(LineCollection(op, colors="red", linewidths=2.5, zorder=4))
    if sl:
        ax.add_collection(LineCollection(sl, colors="blue", linewidths=1.5, linestyles="--", zorder=5))
    lo, hi = np.minimum(xy.min(0), dxy.min(0)), np.maximum(xy.max(0), dxy.max(0))
    pad = 0.05 * (hi - lo).max()
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title, fontsize=9)
    ax.legend(handles=[Patch(color="#e8b86d", label="moving body (displaced by the virtual velocity)"),
                       Patch(color="#cdd9e5", label="body at rest"), Patch(color="0.55", label="fixed body"),
                       Line2D([], [], color="0.75", label="bodies at their start"),
                       Line2D([], [], color="red", lw=2.5, label="joint opening"),
                       Line2D([], [], color="blue", lw=1.5, ls="--", label="joint sliding")],
              loc="upper left", fontsize=7, framealpha=0.9)
    ax.text(0.99, 0.01, f"virtual displacements drawn x {k:.3g} (largest = 8 % of the model size)",
            transform=ax.transAxes, ha="right", va="bottom", fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


# ------------------------------------------------------------------------------------------------ command

def analyse(case: str, sets=None, fdem=None, bonded=False, out_dir=None, plot=True, nonassoc=True, kinematic=False,
            quiet=False) -> dict:
    """The whole command: export, LP, outputs. Returns the report (also written as limit.json)."""
    tmp = tempfile.mkdtemp(prefix="fdem_limit_")
    try:
        model, export_s = export_model(case, sets, fdem, tmp)
        name = model["case"]["name"]
        out = out_dir or os.path.join("runs", name, "limit")
        os.makedirs(out, exist_ok=True)
        shutil.copy(os.path.join(tmp, "limit_model.json"), os.path.join(out, "limit_model.json"))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    t0 = time.perf_counter()
    try:
        pr = Problem(model, bonded=bonded)
    except Refused as e:
        # the reason goes to limit.json too, so that a table over many cases can say why a case has no factor
        write_json(os.path.join(out, "limit.json"), {"case": case, "name": name, "overrides": list(sets or []),
                                                     "refused": str(e), "export_time_s": export_s})
        raise
    build_s = time.perf_counter() - t0
    sol = solve(pr, nonassoc=nonassoc)
    a = sol["assoc"]
    rep = {"case": case, "name": name, "overrides": list(sets or []), "bonded": bonded,
           "formulation": "static LP (Livesley 1978), associative Coulomb friction, rigid bodies, no tension"
                          + (" except bonded joints (c, f_t)" if bonded else "") + ", infinite compressive strength",
           "solver": "scipy.optimize.linprog(method='highs')",
           "bodies": pr.nb, "free_bodies": int((~pr.fixed).sum()), "fixed_bodies": int(pr.fixed.sum()),
           "joints": pr.n_joints, "interface_segments": len(pr.segments), "contact_points": pr.np,
           "reactions": len(pr.reactions), "lp_variables": a.get("variables"), "lp_equalities": a.get("equalities"),
           "lp_inequalities": a.get("inequalities"), "solver_status": a["status"], "solver_message": a["message"],
           "solve_time_s": a["solve_s"], "export_time_s": export_s, "build_time_s": build_s,
           "mode": pr.mode, "notes": pr.notes}
    if pr.mode == "tilt":
        rep["tilt_direction"] = "counter-clockwise" if pr.tilt_rate > 0 else "clockwise"
    else:
        rep["live_load"] = [{"group": g, "direction": d} for g, d in zip(pr.driver_groups, pr.driver_direction)]
        rep["live_load_rule"] = ("a unit force along the drive's velocity per driven group, shared equally by the "
                                 "group's nodes; collapse load = lambda x the live load's total")
    if a["status"] != 0:
        why = {2: "infeasible: the dead loads alone cannot be carried (a body with no support?)",
               3: "unbounded: no mechanism is compatible with the supports, so the associative bound is infinite "
                  "(the live load acts on fixed bodies only, or the supports forbid the dilatancy of associative "
                  "sliding and the uplift of rocking: a wall held in y between a fixed base and a held beam)"}
        rep["error"] = why.get(a["status"], a["message"])
        write_json(os.path.join(out, "limit.json"), rep)
        raise ToolError(f"{case}: LP {rep['error']} (solver: {a['message']})")
    lam = a["lam"]
    if pr.mode == "tilt":
        rep["load_factor"] = lam
        rep["critical_tilt_deg"] = math.degrees(math.atan(lam))
    else:
        rep["load_factor"] = lam
        rep["collapse_load_N"] = lam * pr.live_total
    if nonassoc and "nonassoc" in sol:
        na = sol["nonassoc"]
        key = "critical_tilt_nonassoc_deg" if pr.mode == "tilt" else "collapse_load_nonassoc_N"
        val = math.degrees(math.atan(na["lam"])) if pr.mode == "tilt" else na["lam"] * pr.live_total
        rep[key] = val
        rep["nonassoc"] = {"label": "estimate (Gilbert, Casapulla & Ahmed 2006 iteration), not a bound",
                           "iterations": na["iterations"], "converged": na["converged"],
                           "capped_at_the_bound": na["capped"], "last_iterate_load_factor": na["uncapped"],
                           "load_factor_history": na["history"]}
    if kinematic:
        k = kinematic_lp(pr, const_scale=a.get("const_scale", 1.0))
        rep["kinematic_load_factor"] = k["lam"]
        rep["kinematic_status"] = k["status"]
    vel = a["velocities"]
    mech = classify(pr, vel)
    mech["velocities"] = vel
    seg_n = np.array([0.5 * (a["n"][s["points"][0]] + a["n"][s["points"][1]]) for s in pr.segments])
    mech["segment_normal_force"] = seg_n
    rep["mechanism"] = {
        "velocity_rule": "virtual velocities (u, v in m/s, omega in rad/s about each body's centroid) of the static "
                         "LP's dual, scaled so that the live load's power is 1",
        "moving_bodies": int(mech["body_moving"].sum()),
        "opening_segments": int(mech["segment_opening"].sum()),
        "sliding_segments": int(mech["segment_sliding"].sum()),
        "opening_points": int(mech["point_opening"].sum()), "sliding_points": int(mech["point_sliding"].sum()),
        "bodies": [{"id": b, "centroid": pr.centroid[b].tolist(), "u": float(vel[b, 0]), "v": float(vel[b, 1]),
                    "omega": float(vel[b, 2]), "fixed": bool(pr.fixed[b])} for b in range(pr.nb)],
    }
    files = [os.path.join(out, "limit.json")]
    files.append(write_vtu(os.path.join(out, "mechanism.vtu"), pr, mech))
    if plot:
        if pr.mode == "tilt":
            head = f"critical tilt {rep['critical_tilt_deg']:.3f} deg (associative bound)"
        else:
            head = f"collapse load {rep['collapse_load_N'] / 1e3:.4g} kN (associative bound)"
        if "nonassoc" in rep:
            v = rep.get("critical_tilt_nonassoc_deg", rep.get("collapse_load_nonassoc_N"))
            head += (f"; non-associative estimate {v:.3f} deg" if pr.mode == "tilt"
                     else f"; non-associative estimate {v / 1e3:.4g} kN")
        files.append(plot_mechanism(os.path.join(out, "mechanism.png"), pr, mech, f"{name}: {head}"))
    write_json(files[0], rep)
    rep["files"] = files
    return rep


def bench(case, sets=None, fdem=None, bonded=False, repeats=7, csv_path=None) -> dict:
    tmp = tempfile.mkdtemp(prefix="fdem_limit_")
    try:
        model, export_s = export_model(case, sets, fdem, tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    rows = []
    for i in range(repeats):
        t0 = time.perf_counter()
        pr = Problem(model, bonded=bonded)
        t1 = time.perf_counter()
        r = static_lp(pr)
        t2 = time.perf_counter()
        rows.append([model["case"]["name"], i + 1, pr.nb, pr.n_joints, pr.np, r["variables"], r["equalities"],
                     r["inequalities"], f"{t1 - t0:.6f}", f"{r['solve_s']:.6f}", f"{t2 - t0:.6f}", f"{export_s:.4f}",
                     r["lam"]])
    header = ["case", "repeat", "bodies", "joints", "contact_points", "variables", "equalities", "inequalities",
              "build_s", "solve_s", "build_and_solve_s", "export_s", "load_factor"]
    if csv_path:
        write_csv(csv_path, header, rows)
    solve = sorted(float(r[9]) for r in rows)
    total = sorted(float(r[10]) for r in rows)
    return {"median_solve_s": solve[len(solve) // 2], "median_build_and_solve_s": total[len(total) // 2],
            "export_s": export_s, "rows": rows, "header": header}


def _na_flags(rep):
    na = rep["nonassoc"]
    return (("" if na["converged"] else " (not converged)")
            + (" (the last iterate was above the associative bound: capped at it)" if na["capped_at_the_bound"] else ""))


def cmd_limit(args):
    if args.bench:
        csv_path = args.bench_csv or os.path.join(args.out or ".", "limit_bench.csv")
        b = bench(args.case, args.set, args.fdem, args.bonded, args.bench, csv_path)
        r0 = b["rows"][0]
        print(f"{r0[0]}: {r0[2]} bodies, {r0[3]} joints, {r0[4]} contact points, LP {r0[5]} variables x "
              f"{r0[6]} equalities + {r0[7]} inequalities")
        print(f"  median of {args.bench}: HiGHS solve {b['median_solve_s'] * 1e3:.1f} ms, set-up and solve "
              f"{b['median_build_and_solve_s'] * 1e3:.1f} ms; export (fdem mesh) {b['export_s']:.2f} s; "
              f"load factor {r0[12]:.6g}")
        print(f"wrote {csv_path}")
        return 0
    rep = analyse(args.case, args.set, args.fdem, args.bonded, args.out, plot=not args.no_plot,
                  nonassoc=not args.no_nonassoc, kinematic=args.kinematic)
    lab = "bonded joints with c and f_t (--bonded)" if args.bonded else "no tension, no cohesion"
    print(f"{rep['name']}: {rep['bodies']} bodies ({rep['fixed_bodies']} fixed), {rep['joints']} joints, "
          f"{rep['interface_segments']} interface segments, {rep['contact_points']} contact points; {lab}")
    if rep["mode"] == "tilt":
        print(f"  critical tilt (associative bound): {rep['critical_tilt_deg']:.4f} deg (tan = {rep['load_factor']:.6g})")
        if "critical_tilt_nonassoc_deg" in rep:
            print(f"  non-associative estimate (not a bound): {rep['critical_tilt_nonassoc_deg']:.4f} deg, "
                  f"{rep['nonassoc']['iterations']} iterations" + _na_flags(rep))
    else:
        print(f"  collapse load (associative bound): {rep['collapse_load_N']:.6g} N = {rep['collapse_load_N'] / 1e3:.5g} kN "
              f"along {', '.join(d['group'] for d in rep['live_load'])}")
        if "collapse_load_nonassoc_N" in rep:
            print(f"  non-associative estimate (not a bound): {rep['collapse_load_nonassoc_N'] / 1e3:.5g} kN, "
                  f"{rep['nonassoc']['iterations']} iterations" + _na_flags(rep))
    if args.kinematic:
        print(f"  kinematic (upper-bound) LP load factor: {rep['kinematic_load_factor']:.10g} "
              f"(static {rep['load_factor']:.10g})")
    m = rep["mechanism"]
    print(f"  mechanism: {m['moving_bodies']} bodies move, {m['opening_segments']} segments open, "
          f"{m['sliding_segments']} slide; HiGHS {rep['solve_time_s'] * 1e3:.1f} ms, export {rep['export_time_s']:.2f} s")
    for n in rep["notes"]:
        print(f"  note: {n}")
    print("wrote " + ", ".join(rep["files"]))
    return 0


def add_parser(sub):
    p = sub.add_parser("limit", help="rigid-block limit analysis of a case (LP, HiGHS): collapse load or critical tilt",
                       description="Rigid-block limit analysis (Livesley 1978) of a case's last stage: the bodies, "
                                   "joints, supports and loads come from `fdem mesh` (limit_model.json); the load "
                                   "factor of the driving action is maximised with scipy's HiGHS. Prints the collapse "
                                   "load (N) or the critical tilt (deg), an associative bound, and a non-associative "
                                   "estimate (Gilbert, Casapulla & Ahmed 2006); writes limit.json, mechanism.png and "
                                   "mechanism.vtu (tools/README.md 'limit').")
    p.add_argument("case", metavar="CASE.toml", help="case file")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a case value (as fdem --set)")
    p.add_argument("--out", help="output folder (default runs/<case name>/limit)")
    p.add_argument("--bonded", action="store_true",
                   help="bonded joints keep their cohesion c and tensile strength f_t (times the end point's "
                        "tributary area); default: every joint dry, no tension, no cohesion")
    p.add_argument("--fdem", help="fdem executable (default: $FDEM_BIN, else build/fdem/fdem)")
    p.add_argument("--kinematic", action="store_true", help="also solve the kinematic (upper-bound) LP and print both")
    p.add_argument("--no-nonassoc", action="store_true", help="skip the non-associative estimate")
    p.add_argument("--no-plot", action="store_true", help="no mechanism.png")
    p.add_argument("--bench", type=int, metavar="N", default=0,
                   help="benchmark: set up and solve the LP N times, print the median solve time, write a CSV")
    p.add_argument("--bench-csv", metavar="PATH", help="CSV of --bench (default OUT/limit_bench.csv or ./limit_bench.csv)")
    p.set_defaults(func=cmd_limit)
