#!/usr/bin/env python3
"""First sway frequency of a whole hmsm-tree as a clamped 3D frame of tapered circular beams.

An estimate independent of hmsm's coupled constants (docs/real-trees.md, "What sets the coupled
f0"): Rayleigh's quotient with the static deflection under a unit lateral load per unit mass
along z (small rotations, the root clamped). Each segment is a frustum; a side branch's first
segment takes its own end radius at both ends and the thickest child continues its parent (the
radii convention of docs/model.md 3.13, with "thickest" standing in for hmsm's grouping); leaf
cards weigh MU_L kg/m^2 at their node. Prints the frequency (Hz) with the branches rigid (as
coupled lumps them), bending, bending and twisting (G = E/16), and of the trunk path alone.

    tools/frame_frequency.py TREE.json [--modulus PA] [--density KG_M3] [--leaf-mass KG_M2]
"""
import argparse
import json
import math


def sub(a, b): return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
def add(a, b): return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
def scale(a, k): return [a[0] * k, a[1] * k, a[2] * k]
def dot(a, b): return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
def cross(a, b): return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def frequency(tree, modulus, density, leaf_mass, bending=True, torsion=False, trunk_only=False, pieces=4):
    nodes = tree["nodes"]
    pos = [n["position"] for n in nodes]
    radius = [n["radius"] for n in nodes]
    parent = [n["parent"] for n in nodes]
    children = [[] for _ in nodes]
    for i, p in enumerate(parent):
        if p >= 0:
            children[p].append(i)
    continuation = {p: max(kids, key=lambda k: radius[k]) for p, kids in enumerate(children) if kids}
    trunk = {0}
    n = 0
    while n in continuation:
        n = continuation[n]
        trunk.add(n)
    # Refined nodes: x, radius at the piece's start and end, parent, lumped mass, rigid or not.
    x, r0, r1, up, mass, rigid, at = [pos[0]], [radius[0]], [radius[0]], [-1], [0.0], [False], {0: 0}
    for i in range(1, len(nodes)):  # hmsm-tree lists parents before children
        p = parent[i]
        if trunk_only and i not in trunk:
            continue
        base = radius[p] if continuation[p] == i else radius[i]
        last = at[p]
        for k in range(1, pieces + 1):
            x.append(add(pos[p], scale(sub(pos[i], pos[p]), k / pieces)))
            r0.append(base + (radius[i] - base) * (k - 1) / pieces)
            r1.append(base + (radius[i] - base) * k / pieces)
            up.append(last)
            mass.append(0.0)
            rigid.append(not bending and i not in trunk)
            last = len(x) - 1
        at[i] = last
    for j in range(1, len(x)):
        length = math.sqrt(dot(sub(x[j], x[up[j]]), sub(x[j], x[up[j]])))
        m = density * math.pi * (r0[j] ** 2 + r0[j] * r1[j] + r1[j] ** 2) / 3.0 * length
        mass[j] += m / 2
        mass[up[j]] += m / 2
    for leaf in tree.get("leaves", []):
        if leaf["node"] in at:
            mass[at[leaf["node"]]] += leaf_mass * leaf["size"][0] * leaf["size"][1]
    # Subtree mass and first moment, then rotations and displacements from the root up.
    subtree, moment = mass[:], [scale(x[j], mass[j]) for j in range(len(x))]
    for j in range(len(x) - 1, 0, -1):
        subtree[up[j]] += subtree[j]
        moment[up[j]] = add(moment[up[j]], moment[j])
    load = [0.0, 0.0, 1.0]
    rotation = [[0.0, 0.0, 0.0] for _ in x]
    shift = [[0.0, 0.0, 0.0] for _ in x]
    for j in range(1, len(x)):
        d = sub(x[j], x[up[j]])
        length = math.sqrt(dot(d, d))
        t = scale(d, 1.0 / length)
        mid = scale(add(x[j], x[up[j]]), 0.5)
        inertia = math.pi * (0.5 * (r0[j] + r1[j])) ** 4 / 4.0
        m = cross(sub(moment[j], scale(mid, subtree[j])), load)
        twist = dot(m, t)
        turn = [0.0, 0.0, 0.0]
        if not rigid[j]:
            turn = scale(sub(m, scale(t, twist)), length / (modulus * inertia))
            if torsion:
                turn = add(turn, scale(t, twist * length / (modulus / 16.0 * 2.0 * inertia)))
        rotation[j] = add(rotation[up[j]], turn)
        shift[j] = add(shift[up[j]], cross(add(rotation[up[j]], scale(turn, 0.5)), d))
    work = sum(mass[j] * dot(shift[j], load) for j in range(len(x)))
    kinetic = sum(mass[j] * dot(shift[j], shift[j]) for j in range(len(x)))
    return math.sqrt(work / kinetic) / (2.0 * math.pi)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tree")
    parser.add_argument("--modulus", type=float, default=9.0e9)
    parser.add_argument("--density", type=float, default=900.0)
    parser.add_argument("--leaf-mass", type=float, default=0.2)
    a = parser.parse_args()
    with open(a.tree) as f:
        tree = json.load(f)
    material = (a.modulus, a.density, a.leaf_mass)
    print("rigid branches %.3f Hz, bending %.3f, bending and twisting %.3f, trunk alone %.3f" % (
        frequency(tree, *material, bending=False), frequency(tree, *material),
        frequency(tree, *material, torsion=True), frequency(tree, *material, trunk_only=True)))


if __name__ == "__main__":
    main()
