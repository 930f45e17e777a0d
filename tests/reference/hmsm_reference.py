#!/usr/bin/env python3
"""An independent, plain-Python implementation of hmsm's model (docs/model.md 3.1-3.7, 3.9 and
the schedule file of section 4), written from the model document alone and sharing no code with
the library. tests/reference/check_cli.py runs it beside `hmsm simulate --backend cpu64` on
random trees, forests and schedules and compares node positions and joint matrices.

Double precision throughout; slow but small. Usage (see --help):
  hmsm_reference.py --forest F.json | --tree T.json [--origin X,Y,Z --yaw A]
                    [--wind-schedule S.json] [parameter and wind flags] --steps N
                    --dump-nodes nodes.csv --dump-chains chains.csv
"""
import argparse
import json
import math
import os
import sys

# --- small vector algebra (3-vectors as tuples, 3x3 matrices as row-major tuples of rows) ------


def add(a, b): return (a[0] + b[0], a[1] + b[1], a[2] + b[2])
def sub(a, b): return (a[0] - b[0], a[1] - b[1], a[2] - b[2])
def scale(a, s): return (a[0] * s, a[1] * s, a[2] * s)
def dot(a, b): return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
def norm(a): return math.sqrt(dot(a, a))
def unit(a): return scale(a, 1.0 / norm(a))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def mat_cols(x, y, z):
    return ((x[0], y[0], z[0]), (x[1], y[1], z[1]), (x[2], y[2], z[2]))


def mat_mul(a, b):
    return tuple(tuple(sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)) for i in range(3))


def mat_vec(a, v): return tuple(a[i][0] * v[0] + a[i][1] * v[1] + a[i][2] * v[2] for i in range(3))
def transpose(a): return tuple(tuple(a[j][i] for j in range(3)) for i in range(3))


IDENTITY = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return ((1.0, 0.0, 0.0), (0.0, c, -s), (0.0, s, c))


def rot_y(a):
    c, s = math.cos(a), math.sin(a)
    return ((c, 0.0, s), (0.0, 1.0, 0.0), (-s, 0.0, c))


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return ((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0))


# --- model: skeleton, chains, frames, constants (3.1-3.4) ------------------------------------


class Model:
    def __init__(self, tree, grouping, max_segments, params):
        nodes = tree["nodes"]
        self.n = len(nodes)
        self.p = [tuple(float(c) for c in nd["position"]) for nd in nodes]
        self.r = [float(nd["radius"]) for nd in nodes]
        self.parent = [int(nd["parent"]) for nd in nodes]
        self.children = [[] for _ in range(self.n)]
        for i, par in enumerate(self.parent):
            if par >= 0:
                self.children[par].append(i)  # ascending input index
        self.root = self.parent.index(-1)
        self.kappa = [self.continuation(i, grouping) for i in range(self.n)]
        self.build_chains(max_segments)
        self.build_frames()
        self.build_constants(params)
        ys = [q[1] for q in self.p]
        self.height = max(ys) - min(ys)

    def continuation(self, i, grouping):
        kids = self.children[i]
        if not kids:
            return -1
        best, best_score = -1, None
        if grouping == "direction":
            d_in = (0.0, 1.0, 0.0) if self.parent[i] < 0 else unit(sub(self.p[i], self.p[self.parent[i]]))
            for k in kids:
                score = dot(d_in, unit(sub(self.p[k], self.p[i])))
                if best < 0 or score > best_score:
                    best, best_score = k, score
        else:
            for k in kids:
                score = -abs(self.r[k] - self.r[i])
                if best < 0 or score > best_score:
                    best, best_score = k, score
        return best

    def follow(self, k, max_segments):
        out = [k]
        while self.kappa[out[-1]] >= 0 and (max_segments <= 0 or len(out) < max_segments):
            out.append(self.kappa[out[-1]])
        return out

    def build_chains(self, max_segments):
        # chain: dict(attach, members, parent, depth)
        self.chains = [dict(attach=self.root, members=self.follow(self.kappa[self.root], max_segments),
                            parent=-1, depth=0)]
        c = 0
        while c < len(self.chains):
            ch = self.chains[c]
            order = ([self.root] if c == 0 else []) + ch["members"]
            for idx, n in enumerate(order):
                for k in self.children[n]:
                    if k != self.kappa[n]:
                        self.chains.append(dict(attach=n, members=self.follow(k, max_segments),
                                                parent=c, depth=ch["depth"] + 1))
                if idx == len(order) - 1 and self.kappa[n] >= 0:
                    self.chains.append(dict(attach=n, members=self.follow(self.kappa[n], max_segments),
                                            parent=c, depth=ch["depth"] + 1))
            c += 1
        self.owner = [-1] * self.n
        self.owner[self.root] = 0
        for c, ch in enumerate(self.chains):
            for m in ch["members"]:
                self.owner[m] = c

    def build_frames(self):
        for ch in self.chains:
            a, m = ch["attach"], ch["members"][0]
            y = unit(sub(self.p[m], self.p[a]))
            ref = (0.0, 0.0, 1.0)
            if abs(dot(y, ref)) > 0.9:
                ref = (1.0, 0.0, 0.0)
            x = unit(cross(y, ref))
            z = cross(x, y)
            ch["B"] = mat_cols(x, y, z)
        for ch in self.chains:
            ch["Q"] = ch["B"] if ch["parent"] < 0 else mat_mul(transpose(self.chains[ch["parent"]]["B"]), ch["B"])
        self.local = [(0.0, 0.0, 0.0)] * self.n
        for n in range(self.n):
            if n == self.root:
                continue
            ch = self.chains[self.owner[n]]
            self.local[n] = mat_vec(transpose(ch["B"]), sub(self.p[n], self.p[ch["attach"]]))

    def build_constants(self, prm):
        f_max = min(prm.max_frequency, 1.0 / (4.0 * math.pi * prm.dt * max(1.0, prm.damping_ratio)))
        self.capped = 0
        for ch in self.chains:
            pts = [ch["attach"]] + ch["members"]
            L = sum(norm(sub(self.p[pts[i + 1]], self.p[pts[i]])) for i in range(len(pts) - 1))
            r = self.r[ch["members"][0]]
            I = prm.density * r * r * L ** 3
            K = prm.stiffness * r ** 4 / L
            I_cap = K / (2.0 * math.pi * f_max) ** 2
            if I_cap > I:
                I = I_cap
                self.capped += 1
            ch["I"], ch["K"] = I, K
            ch["D"] = 2.0 * prm.damping_ratio * math.sqrt(K * I)
            ch["A"] = prm.wind_gain * r * L * L


# --- wind (3.5) --------------------------------------------------------------------------------

MASK = (1 << 64) - 1


def splitmix64(x):
    z = (x + 0x9E3779B97F4A7C15) & MASK
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
    return z ^ (z >> 31)


def profile_value(w, x):
    pi = math.pi
    p = w["profile"]
    if p == "none":
        return 0.0
    if p == "constant":
        return 1.0
    if p == "y1":
        return math.cos(pi * x) * math.cos(3 * pi * x) * math.cos(5 * pi * x) * math.cos(7 * pi * x) - 0.1 * math.sin(25 * pi * x)
    if p == "y2":
        return (math.sin(pi * x) + math.sin(3 * pi * x) + math.sin(5 * pi * x) + math.sin(7 * pi * x)) / 4.0
    if p in ("y3", "y4"):
        c = math.cos(pi * x)
        return c * c * math.cos(3 * pi * x) * math.cos(5 * pi * x) - (0.02 if p == "y3" else 0.1) * math.sin(25 * pi * x)
    if p == "turbulent":
        m = [2.0 ** ((k - 8) / 4.0) for k in range(32)]
        b = [math.sqrt(mk) * (1.0 + mk) ** (-5.0 / 6.0) for mk in m]
        total = math.sqrt(sum(bk * bk for bk in b))
        y = 1.0
        for k in range(32):
            a = w["turbulence"] * math.sqrt(2.0) * b[k] / total
            u = (splitmix64((w["seed"] + k) & MASK) >> 11) * 2.0 ** -53
            y += a * math.cos(2.0 * math.pi * (m[k] * x + u))
        return y
    raise ValueError("unknown profile " + p)


DEFAULT_WIND = dict(profile="y1", direction=(1.0, 0.0, 0.0), strength=1.0, frequency=0.1,
                    front_speed=0.0, turbulence=0.3, seed=0)


# --- simulation (3.6, 3.7, 3.9) ------------------------------------------------------------------


class Instance:
    def __init__(self, model, origin, yaw, wind_scale=1.0, wind_phase=0.0, active=True):
        self.model, self.origin, self.yaw = model, origin, yaw
        self.wind_scale, self.wind_phase, self.active = wind_scale, wind_phase, active
        nc = len(model.chains)
        self.S = [[0.0, 0.0] for _ in range(nc)]
        self.V = [[0.0, 0.0] for _ in range(nc)]
        self.pose()

    def pose(self):
        m = self.model
        yaw = rot_y(self.yaw)
        T = []
        for c, ch in enumerate(m.chains):
            t = mat_mul(ch["Q"], mat_mul(rot_z(self.S[c][1]), rot_x(self.S[c][0])))
            T.append(mat_mul(yaw, t) if c == 0 else t)
        self.R = [None] * len(m.chains)
        self.O = [None] * len(m.chains)
        for c, ch in enumerate(m.chains):  # parents come before children (breadth-first ids)
            self.R[c] = T[c] if ch["parent"] < 0 else mat_mul(self.R[ch["parent"]], T[c])
        u = [mat_vec(self.R[m.owner[n]], m.local[n]) for n in range(m.n)]
        for c, ch in enumerate(m.chains):
            self.O[c] = self.origin if ch["parent"] < 0 else add(self.O[ch["parent"]], u[ch["attach"]])
        self.W = [add(self.O[m.owner[n]], u[n]) for n in range(m.n)]


def field_force(fields, x):
    total = (0.0, 0.0, 0.0)
    for f in fields:
        dist = norm(sub(x, f["center"]))
        h = max(0.0, 1.0 - dist / f["radius"]) ** 2
        if "directional" in f:
            total = add(total, scale(f["directional"], h))
        elif dist >= 1e-9:
            total = add(total, scale(sub(x, f["center"]), h * f["radial"] / dist))
    return total


class Simulation:
    def __init__(self, models, instances, params, wind):
        self.models, self.instances, self.prm = models, instances, params
        self.wind = dict(wind)
        self.fields = []
        self.tau_b, self.n_b, self.n = 0.0, 1, 0  # n = steps done

    def tau(self, n):
        return self.tau_b + (self.wind["frequency"] * self.prm.dt) * (n - self.n_b)

    def set_wind(self, wind):
        # tau is continuous: tau_b = tau at the coming step under the old wind.
        nxt = self.n + 1
        self.tau_b = self.tau(nxt)
        self.n_b = nxt
        self.wind = dict(wind)

    def step(self):
        self.n += 1
        n = self.n
        w = self.wind
        d = unit(w["direction"])
        tau = self.tau(n)
        dt = self.prm.dt
        for inst in self.instances:
            if not inst.active:
                continue
            m = inst.model
            phi = inst.wind_phase + (-w["frequency"] * dot(inst.origin, d) / w["front_speed"] if w["front_speed"] > 0 else 0.0)
            base = scale(d, inst.wind_scale * w["strength"] * profile_value(w, tau + phi))
            for c, ch in enumerate(m.chains):
                wc = add(base, field_force(self.fields, inst.O[c]))
                wl = mat_vec(transpose(inst.R[c]), wc)
                g = (ch["A"] * wl[2], -ch["A"] * wl[0])
                for j in range(2):
                    F = g[j] - ch["K"] * inst.S[c][j] - ch["D"] * inst.V[c][j]
                    inst.V[c][j] += dt / ch["I"] * F
                    inst.S[c][j] += dt * inst.V[c][j]
                    if abs(inst.S[c][j]) > self.prm.max_angle:
                        inst.S[c][j] = math.copysign(self.prm.max_angle, inst.S[c][j])
                        inst.V[c][j] = 0.0
            inst.pose()


# --- input files ---------------------------------------------------------------------------------


class Params:
    def __init__(self, a):
        self.density, self.stiffness, self.damping_ratio = a.density, a.stiffness, a.damping_ratio
        self.wind_gain, self.max_angle, self.dt, self.max_frequency = a.wind_gain, a.max_angle, a.dt, a.max_frequency


def vec(text):
    parts = [float(v) for v in text.split(",")]
    assert len(parts) == 3
    return tuple(parts)


def load_json(path):
    with open(path) as f:
        return json.load(f)


def apply_wind_keys(wind, keys):
    out = dict(wind)
    for k, v in keys.items():
        if k == "direction":
            out["direction"] = tuple(float(c) for c in v)
        elif k == "speed":
            out["strength"] = (float(v) / 6.0) ** 2
        elif k == "seed":
            out["seed"] = int(v)
        elif k == "profile":
            out["profile"] = v
        else:
            out[k] = float(v)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    src = ap.add_mutually_exclusive_group(required=True)
    src.add_argument("--tree")
    src.add_argument("--forest")
    ap.add_argument("--origin", default="0,0,0")
    ap.add_argument("--yaw", type=float, default=0.0)
    ap.add_argument("--grouping", default="direction")
    ap.add_argument("--max-chain-segments", type=int, default=0)
    ap.add_argument("--dt", type=float, default=1.0 / 120.0)
    ap.add_argument("--density", type=float, default=1.0)
    ap.add_argument("--stiffness", type=float, default=1.0e7)
    ap.add_argument("--damping-ratio", type=float, default=0.1)
    ap.add_argument("--wind-gain", type=float, default=0.2)
    ap.add_argument("--max-angle", type=float, default=0.8)
    ap.add_argument("--max-frequency", type=float, default=4.0)
    ap.add_argument("--wind", default="y1")
    ap.add_argument("--wind-dir", default="1,0,0")
    ap.add_argument("--wind-strength", type=float)
    ap.add_argument("--wind-speed", type=float)
    ap.add_argument("--wind-frequency", type=float, default=0.1)
    ap.add_argument("--front-speed", type=float, default=0.0)
    ap.add_argument("--turbulence", type=float, default=0.3)
    ap.add_argument("--wind-seed", type=int, default=0)
    ap.add_argument("--wind-schedule")
    ap.add_argument("--steps", type=int, default=120)
    ap.add_argument("--dump-nodes")
    ap.add_argument("--dump-chains")
    a = ap.parse_args()

    prm = Params(a)
    strength = a.wind_strength if a.wind_strength is not None else 1.0
    if a.wind_speed is not None:
        strength = (a.wind_speed / 6.0) ** 2
    wind = dict(profile=a.wind, direction=vec(a.wind_dir), strength=strength, frequency=a.wind_frequency,
                front_speed=a.front_speed, turbulence=a.turbulence, seed=a.wind_seed)

    models, instances = {}, []
    if a.tree:
        models["tree"] = Model(load_json(a.tree), a.grouping, a.max_chain_segments, prm)
        instances.append(Instance(models["tree"], vec(a.origin), a.yaw))
    else:
        forest = load_json(a.forest)
        base = os.path.dirname(os.path.abspath(a.forest))
        for name, path in forest["models"].items():
            models[name] = Model(load_json(os.path.join(base, path)), a.grouping, a.max_chain_segments, prm)
        for it in forest["instances"]:
            instances.append(Instance(models[it["model"]], tuple(float(c) for c in it.get("origin", (0, 0, 0))),
                                      float(it.get("yaw", 0.0)), float(it.get("wind_scale", 1.0)),
                                      float(it.get("wind_phase", 0.0)), bool(it.get("active", True))))
    sim = Simulation(models, instances, prm, wind)

    events = load_json(a.wind_schedule)["events"] if a.wind_schedule else []
    for n in range(1, a.steps + 1):
        for ev in events:
            if ev["step"] != n:
                continue
            if "wind" in ev:
                sim.set_wind(apply_wind_keys(sim.wind, ev["wind"]))
            if "forces" in ev:
                sim.fields = [dict(center=tuple(map(float, f["center"])), radius=float(f["radius"]),
                                   **({"directional": tuple(map(float, f["directional"]))} if "directional" in f
                                      else {"radial": float(f["radial"])})) for f in ev["forces"]]
            for ch in ev.get("instances", []):
                inst = sim.instances[ch["instance"]]
                inst.wind_scale = float(ch.get("wind_scale", inst.wind_scale))
                inst.wind_phase = float(ch.get("wind_phase", inst.wind_phase))
                inst.active = bool(ch.get("active", inst.active))
            if "remove" in ev:
                gone = set(ev["remove"])
                sim.instances = [inst for i, inst in enumerate(sim.instances) if i not in gone]
            for it in ev.get("add", []):
                sim.instances.append(Instance(models[it["model"]], tuple(float(c) for c in it.get("origin", (0, 0, 0))),
                                              float(it.get("yaw", 0.0)), float(it.get("wind_scale", 1.0)),
                                              float(it.get("wind_phase", 0.0)), bool(it.get("active", True))))
        sim.step()

    if a.dump_nodes:
        with open(a.dump_nodes, "w") as f:
            f.write("instance,node,x,y,z\n")
            for i, inst in enumerate(sim.instances):
                for n, w in enumerate(inst.W):
                    f.write("%d,%d,%.17g,%.17g,%.17g\n" % (i, n, w[0], w[1], w[2]))
    if a.dump_chains:
        with open(a.dump_chains, "w") as f:
            f.write("instance,chain,ox,oy,oz,r00,r10,r20,r01,r11,r21,r02,r12,r22\n")
            for i, inst in enumerate(sim.instances):
                for c in range(len(inst.R)):
                    R, O = inst.R[c], inst.O[c]
                    cols = [R[row][col] for col in range(3) for row in range(3)]
                    f.write("%d,%d," % (i, c) + ",".join("%.17g" % v for v in (O[0], O[1], O[2], *cols)) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
