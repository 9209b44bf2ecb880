#!/usr/bin/env python3
"""liemid's multibody step against MuJoCo 4.0, with Pinocchio as the accuracy reference.

The models are written here once as MJCF (benchmarks/models/*.xml) and read by both
liemid (`liemid multibody FILE.xml`) and MuJoCo (`MjModel.from_xml_path`); the 1000-link
chain, deeper than MuJoCo's XML parser accepts, is built with `mujoco.MjSpec` and run by
liemid as its built-in `--problem chain-1000` (the same parameters). Pinocchio's model is
built from MuJoCo's compiled model (body frames, inertias, joint axes), so all three codes
integrate one set of numbers.

Reference: Pinocchio's joint-space dynamics (mass matrix by CRBA, Cholesky solve:
Pinocchio's `aba` loses digits on the long chains, printed per case) integrated by SciPy's DOP853 at rtol = atol = 1e-13 in joint coordinates
(quaternions of ball and free joints by q' = q (0, w)/2, renormalized before each ABA
call); checked against a second run at 1e-12 (printed as "reference check"). The
100-link chain is too stiff for that (DOP853 ran over 6 CPU minutes to t = 0.2): its
reference is liemid6 at a small step, its own error estimated from the run at twice the
step, cross-checked against MuJoCo's RK4 at the same small step.

Error: the final position of every body's frame origin (MuJoCo's `xpos`) and centre of
mass (`xipos`), the maximum over bodies of the distance to the reference, divided by a
link length (stated per case). CPU time: MuJoCo's `mj_step(m, d, nstep=N)` by
`time.process_time`; liemid's by `resource.getrusage(RUSAGE_CHILDREN)` around the CLI
process, less the same command run for a single step (start-up and model reading).

Run:  python benchmarks/vs_mujoco.py [--quick]      (LIEMID_BIN to point at the binary)
Writes docs/vs-mujoco.txt, docs/multibody-double-pendulum.png (and benchmarks/models/*.xml);
chain-10's long-run energy against RK4 is benchmarks/vs_mujoco_energy.py.
Peers: pip install mujoco==4.0.0 pin numpy scipy matplotlib (in a venv of your own).
"""

from __future__ import annotations

import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "benchmarks" / "models"
DOCS = ROOT / "docs"
QUICK = "--quick" in sys.argv

try:
    import numpy as np
    import scipy.integrate
    import scipy.linalg
    import mujoco
    import pinocchio as pin
except ImportError as e:  # pragma: no cover - the skip path
    print(f"vs_mujoco: skipped, a peer is missing ({e}); "
          "pip install mujoco==4.0.0 pin numpy scipy matplotlib")
    sys.exit(0)


sys.path.insert(0, str(Path(__file__).resolve().parent))
from liemid_binary import require_liemid  # noqa: E402

LIEMID = require_liemid("vs_mujoco")

OUT_LINES: list[str] = []


def say(line=""):
    print(line, flush=True)
    OUT_LINES.append(line)


# ----------------------------------------------------------------------------------------
# Models: the built-in problems of crates/liemid/src/multibody/problems.rs, written out.


def skew(a):
    return np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


def so3_exp(w):
    w = np.asarray(w, float)
    t = np.linalg.norm(w)
    if t == 0:
        return np.eye(3)
    k = skew(w / t)
    return np.eye(3) + math.sin(t) * k + (1 - math.cos(t)) * k @ k


def quat_axis_angle(w):
    """w, x, y, z of exp(w)."""
    w = np.asarray(w, float)
    t = np.linalg.norm(w)
    if t == 0:
        return [1.0, 0.0, 0.0, 0.0]
    n = w / t
    return [math.cos(t / 2), *(math.sin(t / 2) * n)]


def quat_to_mat(q):
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def rod_inertia(m, l, r, axis):
    d = [m * (3 * r * r + l * l) / 12] * 3
    d[axis] = 0.5 * m * r * r
    return np.diag(d)


def box_inertia(m, e):
    a, b, c = e
    return np.diag([m / 12 * (b * b + c * c), m / 12 * (a * a + c * c), m / 12 * (a * a + b * b)])


class ModelDesc:
    """Bodies in depth-first order: (name, parent index or -1, pos, ipos, mass, inertia,
    joint (kind, name, axis, stiffness))."""

    def __init__(self, name, gravity, timestep, qpos, qvel=None):
        self.name, self.gravity, self.timestep = name, gravity, timestep
        self.qpos, self.qvel = qpos, qvel
        self.bodies = []

    def add(self, name, parent, pos, ipos, mass, inertia, joint):
        self.bodies.append((name, parent, pos, ipos, mass, np.asarray(inertia), joint))
        return len(self.bodies) - 1


def double_pendulum():
    d = ModelDesc("double-pendulum", [0, 0, -9.81], 1e-3, [1.0, 0.5])
    i = rod_inertia(1.0, 1.0, 0.02, 2)
    a = d.add("link1", -1, [0, 0, 0], [0, 0, -0.5], 1.0, i, ("hinge", "hinge1", [0, 1, 0], 0))
    d.add("link2", a, [0, 0, -1], [0, 0, -0.5], 1.0, i, ("hinge", "hinge2", [0, 1, 0], 0))
    return d


def chain(n):
    inertia = so3_exp([0.1, 0.2, 0.3]) @ box_inertia(0.1, [0.02, 0.03, 0.1]) @ so3_exp([0.1, 0.2, 0.3]).T
    inertia = 0.5 * (inertia + inertia.T)
    qpos = []
    for k in range(n):
        tilt = [0.4, 0, 0] if k == 0 else ([0.05, 0, 0] if k % 2 == 0 else [0, 0.05, 0])
        qpos += quat_axis_angle(tilt)
    d = ModelDesc(f"chain-{n}", [0, 0, -9.81], 1e-4, qpos)
    parent = -1
    for k in range(n):
        parent = d.add(f"link{k}", parent, [0, 0, 0 if k == 0 else -0.1], [0.01, 0.005, -0.05],
                       0.1, inertia, ("ball", f"ball{k}", None, 0))
    return d


def spacecraft():
    w = np.array([1.0, 0.5, 0.3])
    w = w * (20 / np.linalg.norm(w))
    d = ModelDesc("spacecraft", [0, 0, 0], 1e-3, [0, 0, 0, 1, 0, 0, 0, 0, 0],
                  [0, 0, 0, *w, 0, 0])
    hub = d.add("hub", -1, [0, 0, 0], [0, 0, 0], 200.0, box_inertia(200, [1, 1, 1.2]),
                ("free", "hub", None, 0))
    panel = box_inertia(10, [1, 2, 0.02])
    d.add("panel+", hub, [0, 0.5, 0], [0, 1, 0], 10.0, panel, ("hinge", "hinge+", [1, 0, 0], 200.0))
    d.add("panel-", hub, [0, -0.5, 0], [0, -1, 0], 10.0, panel, ("hinge", "hinge-", [1, 0, 0], 200.0))
    return d


def f(x):
    return " ".join(repr(float(v)) for v in np.ravel(x))


def to_mjcf(d: ModelDesc) -> str:
    kids = {k: [] for k in range(-1, len(d.bodies))}
    for k, b in enumerate(d.bodies):
        kids[b[1]].append(k)
    out = [f'<!-- Written by benchmarks/vs_mujoco.py: liemid\'s built-in problem "{d.name}" '
           f"(crates/liemid/src/multibody/problems.rs) as MJCF, read by liemid and MuJoCo. -->",
           f'<mujoco model="{d.name}">', '  <compiler angle="radian"/>',
           f'  <option gravity="{f(d.gravity)}" timestep="{d.timestep!r}"/>', "  <worldbody>"]

    def body(k, ind):
        name, _, pos, ipos, mass, I, (kind, jname, axis, stiff) = d.bodies[k]
        sp = " " * ind
        out.append(f'{sp}<body name="{name}" pos="{f(pos)}">')
        if kind == "free":
            out.append(f'{sp}  <freejoint name="{jname}"/>')
        else:
            extra = f' axis="{f(axis)}"' if axis is not None else ""
            extra += f' stiffness="{stiff!r}"' if stiff else ""
            out.append(f'{sp}  <joint name="{jname}" type="{kind}"{extra}/>')
        if np.allclose(I, np.diag(np.diag(I)), rtol=0, atol=0):
            out.append(f'{sp}  <inertial pos="{f(ipos)}" mass="{mass!r}" diaginertia="{f(np.diag(I))}"/>')
        else:
            full = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]
            out.append(f'{sp}  <inertial pos="{f(ipos)}" mass="{mass!r}" fullinertia="{f(full)}"/>')
        for c in kids[k]:
            body(c, ind + 2)
        out.append(f"{sp}</body>")

    for k in kids[-1]:
        body(k, 4)
    out.append("  </worldbody>")
    key = f'qpos="{f(d.qpos)}"' + (f' qvel="{f(d.qvel)}"' if d.qvel is not None else "")
    out += ["  <keyframe>", f"    <key {key}/>", "  </keyframe>", "</mujoco>", ""]
    return "\n".join(out)


def to_mjspec(d: ModelDesc):
    """The same model through mujoco.MjSpec (no XML depth limit)."""
    s = mujoco.MjSpec()
    s.option.gravity = d.gravity
    s.option.timestep = d.timestep
    made = []
    for name, parent, pos, ipos, mass, I, (kind, jname, axis, stiff) in d.bodies:
        up = s.worldbody if parent < 0 else made[parent]
        full = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]
        b = up.add_body(name=name, pos=pos, mass=mass, ipos=ipos, fullinertia=full,
                        explicitinertial=True)
        types = {"ball": mujoco.mjtJoint.mjJNT_BALL, "hinge": mujoco.mjtJoint.mjJNT_HINGE,
                 "free": mujoco.mjtJoint.mjJNT_FREE}
        j = b.add_joint(name=jname, type=types[kind])
        if axis is not None:
            j.axis = axis
        if stiff:
            j.stiffness = [stiff, 0, 0]
        made.append(b)
    s.add_key(qpos=d.qpos, **({"qvel": d.qvel} if d.qvel is not None else {}))
    return s.compile()


def write_model(d: ModelDesc) -> Path:
    MODELS.mkdir(parents=True, exist_ok=True)
    p = MODELS / f"{d.name.replace('-', '_')}.xml"
    text = to_mjcf(d)
    if not p.exists() or p.read_text() != text:
        p.write_text(text)
    return p


# ----------------------------------------------------------------------------------------
# MuJoCo.

INTEGRATORS = {"rk4": mujoco.mjtIntegrator.mjINT_RK4, "euler": mujoco.mjtIntegrator.mjINT_EULER,
               "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST}


def mj_start(m):
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_forward(m, d)
    return d


def mj_poses(m, d):
    """Frame origins and centres of mass of bodies 1..nbody-1."""
    mujoco.mj_kinematics(m, d)
    return np.array(d.xpos[1:]), np.array(d.xipos[1:]), np.array(d.xquat[1:])


def mj_run(m, integ, n, t_end):
    m.opt.integrator = INTEGRATORS[integ]
    m.opt.timestep = t_end / n
    d = mj_start(m)
    t0 = time.process_time()
    mujoco.mj_step(m, d, nstep=n)
    cpu = time.process_time() - t0
    x, c, q = mj_poses(m, d)
    return x, c, q, cpu


def mj_energy(m, d):
    mujoco.mj_energyPos(m, d)
    mujoco.mj_energyVel(m, d)
    return float(d.energy[0] + d.energy[1])


# ----------------------------------------------------------------------------------------
# Pinocchio (built from MuJoCo's compiled model) and the DOP853 reference.


class PinModel:
    def __init__(self, m):
        self.m = m
        model = pin.Model()
        model.gravity = pin.Motion(np.r_[m.opt.gravity, 0, 0, 0])
        jid = {0: 0}
        self.kinds, self.levers = [], []
        for b in range(1, m.nbody):
            assert m.body_jntnum[b] == 1, "one joint per body"
            j = m.body_jntadr[b]
            assert np.all(m.jnt_pos[j] == 0), "joint at the body frame's origin"
            t = m.jnt_type[j]
            place = pin.SE3(quat_to_mat(m.body_quat[b]), np.array(m.body_pos[b]))
            if t == mujoco.mjtJoint.mjJNT_FREE:
                jm, place, kind = pin.JointModelFreeFlyer(), pin.SE3.Identity(), "free"
            elif t == mujoco.mjtJoint.mjJNT_BALL:
                jm, kind = pin.JointModelSpherical(), "ball"
            elif t == mujoco.mjtJoint.mjJNT_HINGE:
                jm, kind = pin.JointModelRevoluteUnaligned(np.array(m.jnt_axis[j])), "hinge"
            else:
                raise ValueError("joint type")
            k = model.addJoint(jid[m.body_parentid[b]], jm, place, f"j{b}")
            R = quat_to_mat(m.body_iquat[b])
            inertia = R @ np.diag(m.body_inertia[b]) @ R.T
            model.appendBodyToJoint(k, pin.Inertia(float(m.body_mass[b]), np.array(m.body_ipos[b]),
                                                   inertia), pin.SE3.Identity())
            jid[b] = k
            self.kinds.append(kind)
            self.levers.append(np.array(m.body_ipos[b]))
        self.model, self.data = model, model.createData()
        self.use_aba = False
        self.jids = [jid[b] for b in range(1, m.nbody)]
        self.nq, self.nv = model.nq, model.nv
        # index sets (pin layout): quaternions (x, y, z, w) and their local angular velocity
        qa, va, pa, pva, hq, hv, ks, refs = [], [], [], [], [], [], [], []
        for b, kind in zip(range(1, m.nbody), self.kinds):
            J = model.joints[jid[b]]
            iq, iv = J.idx_q, J.idx_v
            j = m.body_jntadr[b]
            if kind == "free":
                pa.append(iq)
                pva.append(iv)
                qa.append(iq + 3)
                va.append(iv + 3)
            elif kind == "ball":
                qa.append(iq)
                va.append(iv)
            else:
                hq.append(iq)
                hv.append(iv)
                ks.append(float(m.jnt_stiffness[j]))
                refs.append(float(m.qpos_spring[m.jnt_qposadr[j]]))
        self.qa, self.va = np.array(qa, int), np.array(va, int)
        self.pa, self.pva = np.array(pa, int), np.array(pva, int)
        self.hq, self.hv = np.array(hq, int), np.array(hv, int)
        self.ks, self.refs = np.array(ks), np.array(refs)
        assert np.all(m.jnt_stiffness[m.jnt_type != mujoco.mjtJoint.mjJNT_HINGE] == 0)
        assert np.all(m.dof_damping == 0) and np.all(m.dof_armature == 0)

    def from_mj(self, m, d):
        q, v = np.zeros(self.nq), np.zeros(self.nv)
        for b, kind in zip(range(1, m.nbody), self.kinds):
            j = m.body_jntadr[b]
            a, da = m.jnt_qposadr[j], m.jnt_dofadr[j]
            J = self.model.joints[self.jids[b - 1]]
            iq, iv = J.idx_q, J.idx_v
            if kind == "free":
                x, qw = d.qpos[a:a + 3], d.qpos[a + 3:a + 7]
                q[iq:iq + 3] = x
                q[iq + 3:iq + 7] = [*qw[1:], qw[0]]
                R = quat_to_mat(qw)
                v[iv:iv + 3] = R.T @ d.qvel[da:da + 3]
                v[iv + 3:iv + 6] = d.qvel[da + 3:da + 6]
            elif kind == "ball":
                qw = d.qpos[a:a + 4]
                q[iq:iq + 4] = [*qw[1:], qw[0]]
                v[iv:iv + 3] = d.qvel[da:da + 3]
            else:
                q[iq] = d.qpos[a]
                v[iv] = d.qvel[da]
        return q, v

    def crba_acc(self, q, v):
        """M(q)^-1 (tau - C(q, v)): the composite-rigid-body mass matrix and a Cholesky
        solve (the same dynamics as ABA, without its loss of precision on long chains)."""
        M = pin.crba(self.model, self.data, q)
        M = np.triu(M) + np.triu(M, 1).T
        b = self.tau(q) - pin.nonLinearEffects(self.model, self.data, q, v)
        return scipy.linalg.cho_solve(scipy.linalg.cho_factor(M), b)

    def normalized(self, q):
        q = q.copy()
        if len(self.qa):
            idx = self.qa[:, None] + np.arange(4)
            qq = q[idx]
            q[idx] = qq / np.linalg.norm(qq, axis=1)[:, None]
        return q

    def tau(self, q):
        t = np.zeros(self.nv)
        if len(self.hv):
            t[self.hv] = -self.ks * (q[self.hq] - self.refs)
        return t

    def rhs(self, _t, y):
        q = self.normalized(y[: self.nq])
        v = y[self.nq:]
        if self.use_aba:
            a = pin.aba(self.model, self.data, q, v, self.tau(q))
        else:
            a = self.crba_acc(q, v)
        qd = np.zeros(self.nq)
        if len(self.hq):
            qd[self.hq] = v[self.hv]
        if len(self.qa):
            idx = self.qa[:, None] + np.arange(4)
            qq = q[idx]
            w = v[self.va[:, None] + np.arange(3)]
            xyz, s = qq[:, :3], qq[:, 3:4]
            qd[idx[:, :3]] = 0.5 * (s * w + np.cross(xyz, w))
            qd[idx[:, 3]] = -0.5 * np.sum(xyz * w, axis=1)
        for iq, iv in zip(self.pa, self.pva):
            qq = q[iq + 3:iq + 7]
            R = quat_to_mat([qq[3], qq[0], qq[1], qq[2]])
            qd[iq:iq + 3] = R @ v[iv:iv + 3]
        return np.concatenate([qd, a])

    def poses(self, q):
        q = self.normalized(q)
        pin.forwardKinematics(self.model, self.data, q)
        xs, cs = [], []
        for k, lever in zip(self.jids, self.levers):
            M = self.data.oMi[k]
            xs.append(np.array(M.translation))
            cs.append(M.rotation @ lever + M.translation)
        return np.array(xs), np.array(cs)

    def energy(self, q, v):
        q = self.normalized(q)
        e = pin.computeKineticEnergy(self.model, self.data, q, v)
        e += pin.computePotentialEnergy(self.model, self.data, q)
        if len(self.hq):
            e += 0.5 * np.sum(self.ks * (q[self.hq] - self.refs) ** 2)
        return float(e)

    def solve(self, y0, t_end, rtol, t_eval=None):
        sol = scipy.integrate.solve_ivp(self.rhs, (0, t_end), y0, method="DOP853", rtol=rtol,
                                        atol=rtol, t_eval=t_eval)
        if not sol.success:
            raise RuntimeError(sol.message)
        return sol


def reference(m, t_end, name, tols=(1e-13, 1e-12)):
    P = PinModel(m)
    d = mj_start(m)
    q0, v0 = P.from_mj(m, d)
    y0 = np.r_[q0, v0]
    out = {}
    for rtol in tols:
        t0 = time.process_time()
        sol = P.solve(y0, t_end, rtol)
        out[rtol] = (P.poses(sol.y[: P.nq, -1]), time.process_time() - t0, sol.nfev)
    return P, out


# ----------------------------------------------------------------------------------------
# liemid through its CLI.


def child_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def liemid_run(model, method, h, t_end, out=None, every=None):
    """Runs the CLI; returns (json summary, child CPU seconds)."""
    cmd = [LIEMID, "multibody"]
    model = str(model)
    cmd += ["--problem", model[1:]] if model.startswith(":") else [model]
    cmd += ["--method", method, "--step", repr(h), "--t-end", repr(t_end), "--json", "-"]
    if out:
        cmd += ["--out", str(out), "--every", str(every)]
    c0 = child_cpu()
    r = subprocess.run(cmd, capture_output=True, text=True)
    cpu = child_cpu() - c0
    if r.returncode != 0:
        return None, cpu, r.stderr.strip()
    return json.loads(r.stdout), cpu, r.stderr.strip()


_BASE = {}


def liemid_base(model, method):
    """CPU of the same command for one step: start-up and model reading."""
    key = (str(model), method)
    if key not in _BASE:
        _BASE[key] = min(liemid_run(model, method, 1e-4, 1e-4)[1] for _ in range(3))
    return _BASE[key]


def liemid_poses(js, m):
    xs, cs, qs = [], [], []
    by = {b["name"]: b for b in js["final"]}
    for b in range(1, m.nbody):
        e = by[mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b)]
        x, q = np.array(e["xpos"]), np.array(e["xquat"])
        xs.append(x)
        cs.append(x + quat_to_mat(q) @ m.body_ipos[b])
        qs.append(q)
    return np.array(xs), np.array(cs), np.array(qs)


def err(a, b, length):
    (xa, ca), (xb, cb) = a[:2], b[:2]
    return float(max(np.max(np.linalg.norm(xa - xb, axis=1)),
                     np.max(np.linalg.norm(ca - cb, axis=1))) / length)


# ----------------------------------------------------------------------------------------
# Work-precision curves.


def interp_cpu(points, level):
    """CPU at `level` by log-log interpolation along (cpu, err) points sorted by cost;
    extrapolated (flag True) from the last two points when the level is not reached."""
    pts = [(c, e) for c, e, *_ in points if e > 0 and math.isfinite(e) and c > 0]
    pts.sort()
    if not pts:
        return None, False
    for (c1, e1), (c2, e2) in zip(pts, pts[1:]):
        if (e1 - level) * (e2 - level) <= 0 and e1 != e2:
            s = (math.log(level) - math.log(e1)) / (math.log(e2) - math.log(e1))
            return math.exp(math.log(c1) + s * (math.log(c2) - math.log(c1))), False
    if pts[0][1] <= level:
        return pts[0][0], "ub"  # reached at the cheapest run: an upper bound
    if len(pts) >= 2:
        (c1, e1), (c2, e2) = pts[-2], pts[-1]
        if e2 < e1:
            s = (math.log(level) - math.log(e1)) / (math.log(e2) - math.log(e1))
            return math.exp(math.log(c1) + s * (math.log(c2) - math.log(c1))), "ex"
    return None, "ex"


MARK = {False: "", "ex": " (extrapolated)", "ub": " (upper bound: coarsest step run)"}
SHORT = {False: "", "ex": "*", "ub": "<="}


def interp_steps(points, level):
    """Steps N at `level` by log-log interpolation of (N, err) between the two runs that
    bracket it; None when no two runs do."""
    pts = sorted((n, e) for _c, e, n in points if e > 0 and math.isfinite(e))
    for (n1, e1), (n2, e2) in zip(pts, pts[1:]):
        if (e1 - level) * (e2 - level) <= 0 and e1 != e2:
            s = (math.log(level) - math.log(e1)) / (math.log(e2) - math.log(e1))
            return math.exp(math.log(n1) + s * (math.log(n2) - math.log(n1)))
    return None


# Force evaluations per step: MuJoCo's RK4 runs its forward dynamics four times a step;
# a liemid method's stage (a whole RATTLE/EA step: kicks, drifts, position and velocity
# solves) is its unit of work.
EVALUATIONS = {"mujoco-rk4": 4, "liemid": 1, "liemid4": 5, "liemid6": 9, "liemid8": 17}


def evaluation_budget(case, curves, level, goal):
    """Why a ratio is what it is: each code's evaluations (RK4) or stages (liemid) to
    `level`, and the CPU of one; the ratio liemid would reach at one MuJoCo evaluation per
    stage, and the CPU a stage may cost for the goal ratio `goal` (MuJoCo / liemid)."""
    rk = curves.get("mujoco-rk4")
    n_rk = rk and interp_steps(rk, level)
    c_rk = rk and interp_cpu(rk, level)[0]
    if not n_rk or not c_rk:
        return
    per_eval = c_rk / (EVALUATIONS["mujoco-rk4"] * n_rk)
    say(f"  evaluation budget at {level:g} ({case}): MuJoCo RK4 {n_rk:.0f} steps ="
        f" {EVALUATIONS['mujoco-rk4'] * n_rk:.0f} forward evaluations of {per_eval * 1e6:.2f} us")
    for k, pts in curves.items():
        if k not in EVALUATIONS or k.startswith("mujoco"):
            continue
        n, (c, _) = interp_steps(pts, level), interp_cpu(pts, level)
        if not n or not c:
            continue
        stages = EVALUATIONS[k] * n
        say(f"    {k:<8} {n:.0f} steps = {stages:.0f} stages of {c / stages * 1e6:.2f} us"
            f" ({c / stages / per_eval:.2f} MuJoCo evaluations); at one evaluation per stage"
            f" MuJoCo / liemid would be {EVALUATIONS['mujoco-rk4'] * n_rk / stages:.3g}x;"
            f" {goal:g}x needs {c_rk / goal / stages * 1e6:.2f} us per stage")


def sweep(label, runner, ns, level, cpu_cap):
    """runner(n) -> (err, cpu); refines by ns until the error is below level/3 or a run
    costs more than cpu_cap. Returns (cpu, err, n) per run."""
    pts = []
    for n in ns:
        e, c = runner(n)
        pts.append((c, e, n))
        say(f"    {label:<16} N = {n:>9d}  h = {runner.t_end / n:.3e}  err = {e:.3e}  cpu = {c:.4f} s")
        if math.isfinite(e) and e < level / 3:
            break
        if 2 * c > cpu_cap or (not label.startswith("liemid") and "rk4" not in label and 4 * c > cpu_cap):
            break
    return pts


class Runner:
    def __init__(self, fn, t_end):
        self.fn, self.t_end = fn, t_end

    def __call__(self, n):
        return self.fn(n)


def geometric(n0, factor, count):
    return [int(round(n0 * factor ** k)) for k in range(count)]


# Runs shorter than SHORT_RUN CPU seconds are repeated REPEATS more times and the least CPU
# kept (for both codes): on a loaded machine a run of a few milliseconds varies by tens of
# per cent, and liemid's start-up, subtracted, is of the same size. Runs near the goals'
# levels take 0.1-0.4 s, and this machine's pairs of equal runs differ by up to 40 %.
SHORT_RUN = 0.5
REPEATS = 2


def work_precision(case, m, model_arg, t_end, length, levels, ref, lie_methods, ns_lie, ns_mj,
                   cpu_cap):
    say(f"  work-precision (error = max body |dx| / {length} m at t = {t_end})")
    curves = {}
    for meth in lie_methods:
        base = liemid_base(model_arg, meth)

        def fn(n, meth=meth, base=base):
            js, cpu, errtxt = liemid_run(model_arg, meth, t_end / n, t_end)
            if js is None:
                return float("nan"), max(cpu - base, 1e-6)
            for _ in range(REPEATS if cpu < SHORT_RUN else 0):
                cpu = min(cpu, liemid_run(model_arg, meth, t_end / n, t_end)[1])
            return err(liemid_poses(js, m), ref, length), max(cpu - base, 1e-6)

        curves[meth] = sweep(meth, Runner(fn, t_end), ns_lie[meth], min(levels), cpu_cap)
    for integ in ("rk4", "implicitfast", "euler"):
        def fn(n, integ=integ):
            x, c, _q, cpu = mj_run(m, integ, n, t_end)
            for _ in range(REPEATS if cpu < SHORT_RUN else 0):
                cpu = min(cpu, mj_run(m, integ, n, t_end)[3])
            e = err((x, c), ref, length)
            return (e if math.isfinite(e) else float("nan")), cpu

        curves["mujoco-" + integ] = sweep("mujoco " + integ, Runner(fn, t_end), ns_mj[integ],
                                          min(levels), cpu_cap)
    return curves


def report_levels(case, curves, levels):
    rows = []
    for level in levels:
        say(f"  CPU seconds to error {level:g} ({case}):")
        got = {}
        for k, pts in curves.items():
            c, ex = interp_cpu(pts, level)
            got[k] = (c, ex)
            txt = "not reached" if c is None else f"{c:.4g} s" + MARK[ex]
            say(f"    {k:<20} {txt}")
        lie = {k: v for k, v in got.items() if not k.startswith("mujoco") and v[0] is not None}
        mj = {k: v for k, v in got.items() if k.startswith("mujoco") and v[0] is not None}
        if lie and mj:
            bl = min(lie, key=lambda k: lie[k][0])
            bm = min(mj, key=lambda k: mj[k][0])
            ratio = mj[bm][0] / lie[bl][0]
            say(f"    best liemid {bl} {lie[bl][0]:.4g} s, best MuJoCo {bm} {mj[bm][0]:.4g} s:"
                f" MuJoCo / liemid = {ratio:.3g}x")
            rows.append((level, bl, bm, ratio, got))
        else:
            rows.append((level, None, None, None, got))
    return rows


# ----------------------------------------------------------------------------------------
# The cases.


def agreement(m, model_arg, P, t_short, length, dop=True):
    """t = 0 positions and energies of the three codes, and a short run at a tiny step
    (against Pinocchio/DOP853 too with `dop`)."""
    d = mj_start(m)
    x0, c0, _ = mj_poses(m, d)
    q0, v0 = P.from_mj(m, d)
    xp, cp = P.poses(q0)
    with tempfile.TemporaryDirectory() as tmp:
        js, _, _ = liemid_run(model_arg, "liemid4", 1e-4, 1e-4, out=Path(tmp) / "t.csv", every=1)
        rows = np.loadtxt(Path(tmp) / "t.csv", delimiter=",", skiprows=1, ndmin=2)
    e_lie = rows[0, 1]
    nb = m.nbody - 1
    xl = rows[0, 2:].reshape(nb, 7)[:, :3]
    e_mj, e_pin = mj_energy(m, d), P.energy(q0, v0)
    qn = P.normalized(q0)
    a_aba = pin.aba(P.model, P.data, qn, v0, P.tau(qn))
    a_crba = P.crba_acc(qn, v0)
    scale = np.max(np.abs(a_crba))
    say(f"  t = 0 accelerations (max {scale:.3g}): |MuJoCo - Pinocchio CRBA| "
        f"{np.max(np.abs(d.qacc - a_crba)):.1e}, |Pinocchio ABA - CRBA| {np.max(np.abs(a_aba - a_crba)):.1e}")
    say(f"  t = 0: energy MuJoCo {e_mj:.15g}, Pinocchio {e_pin:.15g}, liemid {e_lie:.15g}")
    say(f"         body origins: |MuJoCo - Pinocchio| {np.max(np.abs(x0 - xp)):.1e}, "
        f"|MuJoCo - liemid| {np.max(np.abs(x0 - xl)):.1e}; centres of mass |MuJoCo - Pinocchio| "
        f"{np.max(np.abs(c0 - cp)):.1e}")
    x, c, _q, _ = mj_run(m, "rk4", int(round(t_short / 1e-5)), t_short)
    js, _, _ = liemid_run(model_arg, "liemid4", 1e-4, t_short)
    lp = liemid_poses(js, m)
    if not dop:
        say(f"  t = {t_short}: liemid4 h = 1e-4 vs MuJoCo RK4 h = 1e-5: {err(lp, (x, c), length):.2e}")
        return e_mj, e_pin, e_lie
    sol = P.solve(np.r_[q0, v0], t_short, 1e-13)
    ref = P.poses(sol.y[: P.nq, -1])
    say(f"  t = {t_short}: error vs Pinocchio/DOP853: MuJoCo RK4 h = 1e-5 {err((x, c), ref, length):.2e},"
        f" liemid4 h = 1e-4 {err(lp, ref, length):.2e}; liemid4 vs MuJoCo {err(lp, (x, c), length):.2e}")
    return e_mj, e_pin, e_lie


def case_reference(m, t_end, length, name, tols=(1e-13, 1e-12)):
    P, out = reference(m, t_end, name, tols)
    (r13, c13, n13), (r12, c12, n12) = out[tols[0]], out[tols[1]]
    diff = err(r13, r12, length)
    say(f"  reference: Pinocchio (CRBA + Cholesky) + DOP853 rtol = atol = {tols[0]:g} ({n13} calls, {c13:.1f} s);"
        f" reference check: rtol {tols[1]:g} differs by {diff:.1e}")
    return P, r13, diff


def summary_table(results):
    say()
    say("Summary (CPU time of MuJoCo's best integrator / liemid's best, equal final error;"
        " taken on a 2-core machine):")
    say(f"  {'case':<32} {'error':>7} {'liemid best':>22} {'MuJoCo best':>26} {'ratio':>8}  goal")
    for case, level, bl, bm, ratio, goal, got in results:
        if ratio is None:
            say(f"  {case:<32} {level:>7g}  (a curve did not reach the level)  goal {goal}")
            continue
        lc, lx = got[bl]
        mc, mx = got[bm]
        ls = f"{bl} {lc:.3g}s" + SHORT[lx]
        ms = f"{bm} {mc:.3g}s" + SHORT[mx]
        say(f"  {case:<32} {level:>7g} {ls:>22} {ms:>26} {ratio:>7.3g}x  {goal}")
    say("  (* extrapolated along the method's last two points; <= reached at its coarsest step)")


def rk4_vs_liemid4(rows_dp):
    say("  double pendulum, liemid4 against MuJoCo RK4 alone:")
    for level, _bl, _bm, _r, got in rows_dp:
        l4, r4 = got.get("liemid4", (None, 0)), got.get("mujoco-rk4", (None, 0))
        if l4[0] and r4[0]:
            say(f"    error {level:g}: liemid4 {l4[0]:.4g} s, MuJoCo RK4 {r4[0]:.4g} s,"
                f" liemid4 / RK4 = {l4[0] / r4[0]:.3g}")


def double_pendulum_figure(m, model_arg, P, t_end=10.0, h=1e-3, t_long=100.0):
    """Trajectory (hinge angles) and energy error beside MuJoCo's, same step."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        say("  (matplotlib missing: no figure)")
        return
    say(f"\nDouble pendulum figure: h = {h}, trajectory to t = {t_end}, energy to t = {t_long}")
    d = mj_start(m)
    q0, v0 = P.from_mj(m, d)
    ts = np.linspace(0, t_end, 1001)
    sol = P.solve(np.r_[q0, v0], t_end, 1e-13, t_eval=ts)
    ang_ref = sol.y[P.hq]
    lie = {}
    with tempfile.TemporaryDirectory() as tmp:
        for meth in ("liemid", "liemid4"):
            p = Path(tmp) / f"{meth}.csv"
            js, cpu, _ = liemid_run(model_arg, meth, h, t_long, out=p, every=10)
            rows = np.loadtxt(p, delimiter=",", skiprows=1, ndmin=2)
            lie[meth] = (rows, cpu)

    def angles(rows):
        q1 = rows[:, 5:9]
        q2 = rows[:, 12:16]
        a1 = 2 * np.arctan2(q1[:, 2], q1[:, 0])
        a2 = 2 * np.arctan2(q2[:, 2], q2[:, 0])
        wrap = lambda x: (x + np.pi) % (2 * np.pi) - np.pi
        return wrap(a1), wrap(a2 - a1)

    mj = {}
    for integ in ("rk4", "euler", "implicitfast"):
        m.opt.integrator = INTEGRATORS[integ]
        m.opt.timestep = h
        d = mj_start(m)
        e0 = mj_energy(m, d)
        n = int(round(t_long / h))
        t, q, e, cpu = [0.0], [d.qpos.copy()], [0.0], 0.0
        for k in range(n // 10):
            c0 = time.process_time()
            mujoco.mj_step(m, d, nstep=10)
            cpu += time.process_time() - c0
            mujoco.mj_forward(m, d)
            t.append((k + 1) * 10 * h)
            q.append(d.qpos.copy())
            e.append((mj_energy(m, d) - e0) / abs(e0))
        mj[integ] = (np.array(t), np.array(q), np.array(e), cpu)
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.2))
    ax[0].plot(ts, ang_ref[0], "k-", lw=2.5, alpha=0.3, label="reference (Pinocchio+DOP853)")
    ax[0].plot(ts, ang_ref[1], "k-", lw=2.5, alpha=0.3)
    rows, _ = lie["liemid4"]
    sel = rows[:, 0] <= t_end + 1e-9
    a1, a2 = angles(rows[sel])
    ax[0].plot(rows[sel, 0], a1, "C0-", lw=0.9, label=f"liemid4 h={h:g}")
    ax[0].plot(rows[sel, 0], a2, "C0--", lw=0.9)
    t, q, _e, _c = mj["rk4"]
    sel = t <= t_end + 1e-9
    ax[0].plot(t[sel], q[sel, 0], "C3-", lw=0.7, label=f"MuJoCo RK4 h={h:g}")
    ax[0].plot(t[sel], q[sel, 1], "C3--", lw=0.7)
    ax[0].set_xlabel("t (s)")
    ax[0].set_ylabel("hinge angle (rad): shoulder solid, elbow dashed")
    ax[0].set_title("double pendulum")
    ax[0].legend(fontsize=7)
    for meth, (rows, cpu) in lie.items():
        e = rows[:, 1]
        ax[1].plot(rows[:, 0], np.abs((e - e[0]) / abs(e[0])), lw=0.6, label=f"{meth} (CPU {cpu:.2f} s)")
    for integ, (t, _q, e, cpu) in mj.items():
        ax[1].plot(t, np.abs(e), lw=0.6, label=f"MuJoCo {integ} (CPU {cpu:.2f} s)")
        say(f"  MuJoCo {integ}: max |dE/E| to t = {t_long:g}: {np.max(np.abs(e)):.3e}, CPU {cpu:.2f} s")
    for meth, (rows, cpu) in lie.items():
        e = rows[:, 1]
        rel = (e - e[0]) / abs(e[0])
        say(f"  {meth}: max |dE/E| to t = {t_long:g}: {np.max(np.abs(rel)):.3e}, CPU {cpu:.2f} s")
    ax[1].set_yscale("log")
    ax[1].set_ylim(1e-16, 10)
    ax[1].set_xlabel("t (s)")
    ax[1].set_ylabel("|relative energy error|")
    ax[1].set_title(f"same step h = {h:g}")
    ax[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(DOCS / "multibody-double-pendulum.png", dpi=120)
    say("  figure: docs/multibody-double-pendulum.png")


def cost_study():
    n = 1000
    say(f"\nCost per body-step on chain-{n} (built in code: MjSpec for MuJoCo, --problem for liemid):")
    m = to_mjspec(chain(n))
    steps = 20 if QUICK else 500
    h = 1e-4
    base = liemid_base(":chain-1000", "liemid")
    try:
        P = PinModel(m)
        n_pin = n
    except MemoryError:
        say(f"  Pinocchio: createData() raises MemoryError on the {n}-ball-joint chain (nv = {3 * n});"
            " ABA timed on chain-100 instead")
        n_pin = 100
        m = to_mjspec(chain(n_pin))
        P = PinModel(m)
    d = mj_start(m)
    q, v = P.from_mj(m, d)
    tau = np.zeros(P.nv)
    reps = 200 if QUICK else 1000
    pin.aba(P.model, P.data, q, v, tau)

    def aba_time():
        c0 = time.process_time()
        for _ in range(reps):
            pin.aba(P.model, P.data, q, v, tau)
        return (time.process_time() - c0) / reps / n_pin

    # Rounds of one liemid run and one batch of ABA calls in turn: single runs move by tens
    # of per cent on this shared machine, and so does its speed over minutes; the pair's
    # ratio is taken round by round, and the least of each code.
    rounds = 2 if QUICK else 5
    pers, abas, ratios, js = [], [], [], None
    for _ in range(rounds):
        js_k, cpu, _ = liemid_run(":chain-1000", "liemid", h, steps * h)
        if not js_k:
            say("  liemid: chain-1000 failed (see the work-precision runs)")
            return
        js = js_k
        pers.append((cpu - base) / (steps * n))
        abas.append(aba_time())
        ratios.append(pers[-1] / abas[-1])
    per, aba = min(pers), min(abas)
    say(f"  liemid (CLI, {steps} steps, least of {rounds}, CPU less start-up {base:.3f} s): {per * 1e6:.3f} us per"
        f" body-step ({1 / per:.3g} body-steps/s; wall-clock stepping_seconds of the last run gives"
        f" {js['stepping_seconds'] / (steps * n) * 1e6:.3f} us)")
    say(f"  Pinocchio aba on chain-{n_pin} (one call from Python, {reps} calls, least of {rounds}):"
        f" {aba * n_pin * 1e6:.1f} us, {aba * 1e6:.3f} us per body")
    say(f"  liemid per body-step / ABA per body: {per / aba:.2f} (least against least); round by round"
        f" {', '.join(f'{r:.2f}' for r in ratios)}, median {sorted(ratios)[len(ratios) // 2]:.2f}")
    n = n_pin
    say(f"  MuJoCo on chain-{n}:")
    for integ in ("euler", "rk4"):
        m.opt.integrator = INTEGRATORS[integ]
        m.opt.timestep = h
        d = mj_start(m)
        k = 2
        c0 = time.process_time()
        mujoco.mj_step(m, d, nstep=k)
        c = (time.process_time() - c0) / k
        say(f"  MuJoCo {integ}: {c * 1e3:.2f} ms per step, {c / n * 1e6:.2f} us per body-step")


def main():
    DOCS.mkdir(exist_ok=True)
    say(f"vs_mujoco.py: liemid ({LIEMID}) against MuJoCo {mujoco.__version__}, Pinocchio "
        f"{pin.__version__} (reference), numpy {np.__version__}, scipy {scipy.__version__}")
    say("CPU times are process times (liemid: the CLI child's, less its one-step start-up) on a"
        " 2-core machine (its load is stated below); liemid's CLI loop also evaluates energy and momenta"
        " every step.")
    results = []
    cap = 2.0 if QUICK else float(os.environ.get("VS_MUJOCO_CAP", "8"))

    cases = os.environ.get("VS_MUJOCO_CASES", "spacecraft,chain,dp").split(",")
    # spacecraft -------------------------------------------------------------------------
    d_sc = spacecraft()
    p_sc = write_model(d_sc)
    if "spacecraft" not in cases:
        say("\n(spacecraft skipped: VS_MUJOCO_CASES)")
    else:
        results += spacecraft_case(p_sc, cap)
    return chain_and_rest(results, cap, cases)


def spacecraft_case(p_sc, cap):
    results = []
    m_sc = mujoco.MjModel.from_xml_path(str(p_sc))
    t_sc = 2.0 if QUICK else 10.0
    say(f"\n== spacecraft ({p_sc.relative_to(ROOT)}), t = {t_sc}, length 1 m (hub edge) ==")
    js_b, _, _ = liemid_run(":spacecraft", "liemid4", 1e-3, 1.0)
    js_f, _, _ = liemid_run(p_sc, "liemid4", 1e-3, 1.0)
    same = max(np.max(np.abs(np.array(a["xpos"]) - np.array(b["xpos"])))
               for a, b in zip(js_b["final"], js_f["final"]))
    say(f"  liemid built-in --problem spacecraft vs the MJCF file, t = 1: max |dxpos| {same:.1e}")
    P, ref, _ = case_reference(m_sc, t_sc, 1.0, "spacecraft")
    agreement(m_sc, p_sc, P, 0.1, 1.0)
    lie_methods = ["liemid", "liemid4", "liemid6", "liemid8"]
    ns = {"liemid": geometric(2500, 2, 12), "liemid4": geometric(250, 2, 10),
          "liemid6": geometric(250, 2, 9), "liemid8": geometric(250, 2, 8)}
    ns_mj = {"rk4": geometric(250, 2, 10), "implicitfast": geometric(2500, 2, 12),
             "euler": geometric(2500, 2, 12)}
    curves = work_precision("spacecraft", m_sc, p_sc, t_sc, 1.0, [1e-6], ref, lie_methods, ns, ns_mj, cap)
    evaluation_budget("spacecraft", curves, 1e-6, 10.0)
    for row in report_levels("spacecraft", curves, [1e-6]):
        results.append((f"spacecraft t={t_sc:g}", *row[:4], ">= 10x", row[4]))
    return results


def chain_and_rest(results, cap, cases):
    # 100-link chain ---------------------------------------------------------------------
    if "chain" in cases:
        results += chain_case(cap)
    else:
        say("\n(100-link chain skipped: VS_MUJOCO_CASES)")
    return dp_and_rest(results, cap)


def chain_reference(m, model_arg, t_end, length):
    """The 100-link chain's reference: liemid6 at h = 5e-5 (its own error from the run at
    2h: the difference / (2^6 - 1)), cross-checked against MuJoCo's RK4 at h = 5e-5 (DOP853
    in joint coordinates is too stiff here: over 6 CPU minutes for t = 0.2)."""
    h = float(os.environ.get("VS_MUJOCO_CHAIN_REF_H", "5e-5"))
    runs = {}
    for hh in (h, 2 * h):
        js, cpu, errtxt = liemid_run(model_arg, "liemid6", hh, t_end)
        if js is None:
            raise RuntimeError(errtxt)
        runs[hh] = (liemid_poses(js, m), cpu)
    ref, cpu = runs[h]
    diff = err(runs[2 * h][0], ref, length)
    x, c, _q, cpu_mj = mj_run(m, "rk4", int(round(t_end / h)), t_end)
    say(f"  reference: liemid6 h = {h:g} ({cpu:.1f} s CPU); liemid6 h = {2 * h:g} differs by {diff:.1e},"
        f" so the reference's own error is about {diff / 63:.1e} (order 6); MuJoCo RK4 h = {h:g}"
        f" ({cpu_mj:.1f} s CPU) differs from it by {err((x, c), ref, length):.1e}")
    return ref, diff / 63


def chain_case(cap):
    results = []
    n_links = 30 if QUICK else 100
    d_ch = chain(n_links)
    p_ch = write_model(d_ch)
    m_ch = mujoco.MjModel.from_xml_path(str(p_ch))
    t_ch = float(os.environ.get("VS_MUJOCO_CHAIN_T", "0.2"))
    say(f"\n== {n_links}-link ball-joint chain ({p_ch.relative_to(ROOT)}), t = {t_ch},"
        f" length 0.1 m (link) ==")
    ref, _ = chain_reference(m_ch, p_ch, t_ch, 0.1)
    agreement(m_ch, p_ch, PinModel(m_ch), 0.01, 0.1, dop=False)
    lie_methods = ["liemid", "liemid4", "liemid6"]
    ns = {"liemid": geometric(250, 2, 9), "liemid4": geometric(125, 2, 8), "liemid6": geometric(63, 2, 7)}
    ns_mj = {"rk4": geometric(125, 2, 8), "implicitfast": geometric(250, 2, 9),
             "euler": geometric(250, 2, 9)}
    curves = work_precision("chain", m_ch, p_ch, t_ch, 0.1, [1e-4], ref, lie_methods, ns, ns_mj, cap)
    for row in report_levels(f"chain-{n_links}", curves, [1e-4]):
        results.append((f"chain-{n_links} t={t_ch:g}", *row[:4], ">= 10x", row[4]))
    return results


def dp_and_rest(results, cap):

    # double pendulum --------------------------------------------------------------------
    d_dp = double_pendulum()
    p_dp = write_model(d_dp)
    m_dp = mujoco.MjModel.from_xml_path(str(p_dp))
    t_dp = 10.0
    say(f"\n== double pendulum ({p_dp.relative_to(ROOT)}), t = {t_dp}, length 1 m (link) ==")
    P_dp, ref, _ = case_reference(m_dp, t_dp, 1.0, "dp")
    agreement(m_dp, p_dp, P_dp, 0.1, 1.0)
    lie_methods = ["liemid", "liemid4", "liemid6"]
    # liemid4 from 160 steps (h = 0.0625): its runs must bracket 1e-3 for the interpolation.
    ns = {"liemid": geometric(1000, 2, 12), "liemid4": [160, 200] + geometric(250, 2, 10),
          "liemid6": geometric(125, 2, 9)}
    ns_mj = {"rk4": geometric(250, 2, 10), "implicitfast": geometric(1000, 2, 12),
             "euler": geometric(1000, 2, 12)}
    curves = work_precision("dp", m_dp, p_dp, t_dp, 1.0, [1e-3, 1e-6], ref, lie_methods, ns, ns_mj, cap)
    rows_dp = report_levels("double pendulum", curves, [1e-3, 1e-6])
    evaluation_budget("double pendulum", {k: curves[k] for k in ("mujoco-rk4", "liemid4")}, 1e-3, 1.0)
    goals = {1e-3: "liemid4 ahead of RK4", 1e-6: "liemid4 within 2x RK4"}
    for row in rows_dp:
        results.append((f"double-pendulum t={t_dp:g}", *row[:4], goals[row[0]], row[4]))
    rk4_vs_liemid4(rows_dp)

    summary_table(results)
    say("  double pendulum, liemid4 against MuJoCo RK4 (the goal's pair):")
    for level, _bl, _bm, _r, got in rows_dp:
        l4, r4 = got.get("liemid4", (None, 0)), got.get("mujoco-rk4", (None, 0))
        if l4[0] and r4[0]:
            say(f"    error {level:g}: RK4 / liemid4 = {r4[0] / l4[0]:.3g}x")

    # figures, cost (chain-10's long-run energy: benchmarks/vs_mujoco_energy.py) ---------
    write_model(chain(10))
    double_pendulum_figure(m_dp, p_dp, P_dp, t_long=20.0 if QUICK else 100.0)
    cost_study()

    if not QUICK:
        (DOCS / "vs-mujoco.txt").write_text("\n".join(OUT_LINES) + "\n")
        print("wrote docs/vs-mujoco.txt")


if __name__ == "__main__":
    main()
