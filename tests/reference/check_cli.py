#!/usr/bin/env python3
"""Runs `hmsm simulate` and the independent Python model (hmsm_reference.py) on random trees,
forests and wind schedules, and compares node positions (--dump-nodes) and joint matrices
(--dump-chains): the maximum difference over tree height must stay below the tolerance
(1e-9 for cpu64, 1e-4 for the float backends). Exit 0 when every case agrees, 1 otherwise.

  check_cli.py HMSM_CLI [--backend cpu64] [--cases N] [--seed S] [--keep DIR]
"""
import argparse
import csv
import json
import math
import os
import random
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
REFERENCE = os.path.join(HERE, "hmsm_reference.py")


def random_tree(rng, nodes):
    """A random skeleton whose parents may come after their children in the input."""
    pos = [(0.0, 0.0, 0.0)]
    rad = [rng.uniform(0.1, 0.4)]
    par = [-1]
    for i in range(1, nodes):
        p = rng.randrange(i) if rng.random() < 0.6 else i - 1
        length = rng.uniform(0.3, 2.0)
        theta = rng.uniform(0.0, 1.2)
        az = rng.uniform(0.0, 2 * math.pi)
        d = (math.sin(theta) * math.cos(az), math.cos(theta), math.sin(theta) * math.sin(az))
        pos.append(tuple(pos[p][k] + length * d[k] for k in range(3)))
        rad.append(max(0.005, rad[p] * rng.uniform(0.6, 0.95)))
        par.append(p)
    order = list(range(nodes))
    rng.shuffle(order)  # input index of each generated node
    where = {g: i for i, g in enumerate(order)}
    out = [None] * nodes
    for g in range(nodes):
        out[where[g]] = {"parent": -1 if par[g] < 0 else where[par[g]],
                         "position": list(pos[g]), "radius": rad[g]}
    return {"format": "hmsm-tree", "version": 1, "nodes": out}


def random_wind_keys(rng):
    keys = {}
    if rng.random() < 0.6:
        keys["profile"] = rng.choice(["y1", "y2", "y3", "y4", "constant", "turbulent", "none"])
    if rng.random() < 0.5:
        keys["direction"] = [rng.uniform(-1, 1), rng.uniform(-0.3, 0.3), rng.uniform(-1, 1)]
        if sum(c * c for c in keys["direction"]) < 1e-3:
            keys["direction"] = [1, 0, 0]
    if rng.random() < 0.3:
        keys["speed"] = rng.uniform(0, 20)
    elif rng.random() < 0.5:
        keys["strength"] = rng.uniform(0, 6)
    if rng.random() < 0.4:
        keys["frequency"] = rng.uniform(0, 0.8)
    if rng.random() < 0.3:
        keys["front_speed"] = rng.choice([0, rng.uniform(0.5, 10)])
    if rng.random() < 0.3:
        keys["turbulence"] = rng.uniform(0, 2)
    if rng.random() < 0.3:
        keys["seed"] = rng.randrange(0, 2 ** 64)
    return keys or {"strength": 2.0}


def random_force(rng):
    f = {"center": [rng.uniform(-5, 5), rng.uniform(0, 6), rng.uniform(-5, 5)], "radius": rng.uniform(1, 8)}
    if rng.random() < 0.5:
        f["radial"] = rng.uniform(-5, 5)
    else:
        f["directional"] = [rng.uniform(-5, 5), rng.uniform(-1, 1), rng.uniform(-5, 5)]
    return f


def random_schedule(rng, steps, instances, model_names):
    events, count = [], instances
    for step in sorted(rng.sample(range(1, steps + 1), min(steps, rng.randint(1, 5)))):
        ev = {"step": step}
        if rng.random() < 0.7:
            ev["wind"] = random_wind_keys(rng)
        if rng.random() < 0.4:
            ev["forces"] = [random_force(rng) for _ in range(rng.randint(0, 3))]
        if count and rng.random() < 0.5:
            ev["instances"] = []
            for i in rng.sample(range(count), rng.randint(1, count)):
                change = {"instance": i}
                if rng.random() < 0.5:
                    change["wind_scale"] = rng.uniform(0, 2)
                if rng.random() < 0.5:
                    change["wind_phase"] = rng.uniform(-1, 1)
                if rng.random() < 0.5:
                    change["active"] = rng.random() < 0.5
                ev["instances"].append(change)
        if count > 1 and rng.random() < 0.3:
            ev["remove"] = rng.sample(range(count), rng.randint(1, count - 1))
            count -= len(ev["remove"])
        if rng.random() < 0.3:
            ev["add"] = [{"model": rng.choice(model_names), "origin": [rng.uniform(-9, 9), 0, rng.uniform(-9, 9)],
                          "yaw": rng.uniform(-3, 3)} for _ in range(rng.randint(1, 2))]
            count += len(ev["add"])
        events.append(ev)
    return {"format": "hmsm-schedule", "version": 1, "events": events}


def read_rows(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    return rows[0], [[float(v) for v in r] for r in rows[1:]]


def compare(a_path, b_path, height):
    ha, a = read_rows(a_path)
    hb, b = read_rows(b_path)
    if ha != hb:
        return math.inf, "headers differ: %s vs %s" % (ha, hb)
    if len(a) != len(b):
        return math.inf, "row counts differ: %d vs %d" % (len(a), len(b))
    worst = 0.0
    for ra, rb in zip(a, b):
        if ra[:2] != rb[:2]:
            return math.inf, "row keys differ: %s vs %s" % (ra[:2], rb[:2])
        for x, y in zip(ra[2:], rb[2:]):
            if math.isnan(x) or math.isnan(y):
                return math.inf, "NaN"
            worst = max(worst, abs(x - y))
    return worst / height, ""


def run_case(cli, backend, rng, work, case):
    """Returns (error over height, message); writes the inputs into `work`."""
    names = ["oak", "ash"][: rng.randint(1, 2)]
    heights = []
    for name in names:
        tree = random_tree(rng, rng.randint(2, 40))
        ys = [n["position"][1] for n in tree["nodes"]]
        heights.append(max(ys) - min(ys))
        with open(os.path.join(work, name + ".json"), "w") as f:
            json.dump(tree, f)
    instances = []
    for _ in range(rng.randint(1, 5)):
        inst = {"model": rng.choice(names), "origin": [rng.uniform(-9, 9), 0, rng.uniform(-9, 9)],
                "yaw": rng.uniform(-3, 3)}
        if rng.random() < 0.5:
            inst["wind_scale"] = rng.uniform(0, 2)
        if rng.random() < 0.5:
            inst["wind_phase"] = rng.uniform(-1, 1)
        if rng.random() < 0.2:
            inst["active"] = False
        instances.append(inst)
    forest = {"format": "hmsm-forest", "version": 1, "models": {n: n + ".json" for n in names},
              "instances": instances}
    with open(os.path.join(work, "forest.json"), "w") as f:
        json.dump(forest, f)
    steps = rng.randint(1, 150)
    schedule = random_schedule(rng, steps, len(instances), names)
    with open(os.path.join(work, "schedule.json"), "w") as f:
        json.dump(schedule, f)
    options = [("--steps", str(steps)), ("--wind", rng.choice(["y1", "y2", "turbulent", "constant"])),
               ("--wind-dir", "%r,%r,%r" % (rng.uniform(-1, 1), 0.1, rng.uniform(-1, 1))),
               ("--wind-strength", repr(rng.uniform(0, 4))), ("--wind-frequency", repr(rng.uniform(0, 0.5))),
               ("--turbulence", repr(rng.uniform(0, 1))), ("--wind-seed", str(rng.randrange(0, 2 ** 64))),
               ("--dt", repr(rng.choice([1 / 60, 1 / 120, 1 / 240]))),
               ("--max-frequency", repr(rng.choice([4.0, 2.0, 8.0]))),
               ("--damping-ratio", repr(rng.choice([0.1, 0.3, 1.5]))),
               ("--wind-gain", repr(rng.choice([0.2, 1.0, 5.0]))),
               ("--forest", os.path.join(work, "forest.json")),
               ("--wind-schedule", os.path.join(work, "schedule.json"))]
    if rng.random() < 0.3:
        options.append(("--max-chain-segments", str(rng.randint(1, 4))))
    if rng.random() < 0.3:
        options.append(("--grouping", "width"))
    # --flag=value: values such as "-0.5,0.1,0.3" must not read as flags.
    flags = ["%s=%s" % kv for kv in options]
    with open(os.path.join(work, "flags.txt"), "w") as f:
        f.write(" ".join(flags) + "\n")
    out = {k: os.path.join(work, k + ".csv") for k in ("nodes_cli", "chains_cli", "nodes_ref", "chains_ref")}
    cli_run = subprocess.run([cli, "simulate", "--backend", backend, "--no-progress", *flags,
                              "--dump-nodes", out["nodes_cli"], "--dump-chains", out["chains_cli"]],
                             capture_output=True, text=True)
    if cli_run.returncode != 0:
        return math.inf, "hmsm simulate failed (%d): %s" % (cli_run.returncode, cli_run.stderr.strip())
    ref_run = subprocess.run([sys.executable, REFERENCE, *flags, "--dump-nodes", out["nodes_ref"],
                              "--dump-chains", out["chains_ref"]], capture_output=True, text=True)
    if ref_run.returncode != 0:
        return math.inf, "reference failed: " + ref_run.stderr.strip()[-2000:]
    height = min(heights)
    worst, why = compare(out["nodes_cli"], out["nodes_ref"], height)
    if why:
        return worst, "nodes: " + why
    worst_chains, why = compare(out["chains_cli"], out["chains_ref"], height)
    if why:
        return worst_chains, "chains: " + why
    return max(worst, worst_chains), ""


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("cli")
    ap.add_argument("--backend", default="cpu64")
    ap.add_argument("--cases", type=int, default=12)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--keep", help="keep each case's inputs and outputs under this folder")
    a = ap.parse_args()
    tolerance = 1e-9 if a.backend == "cpu64" else 1e-4
    failures = 0
    for case in range(a.cases):
        rng = random.Random(a.seed * 1000003 + case)
        work = os.path.join(a.keep, "case%03d" % case) if a.keep else tempfile.mkdtemp(prefix="hmsm-ref-")
        os.makedirs(work, exist_ok=True)
        worst, why = run_case(a.cli, a.backend, rng, work, case)
        ok = not why and worst <= tolerance
        failures += not ok
        print("case %3d: %s max error / height %.3g%s" % (case, "ok  " if ok else "FAIL", worst,
                                                          (" (" + why + ")") if why else "") +
              ("" if ok else "  inputs in " + work))
    print("%d passed, %d failed" % (a.cases - failures, failures))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
