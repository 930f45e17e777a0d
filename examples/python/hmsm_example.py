#!/usr/bin/env python3
"""hmsm from Python through the C ABI (include/hmsm/hmsm_c.h) with ctypes, no other package.

Usage: hmsm_example.py [path/to/libhmsm.so]   (default: the HMSM_LIBRARY variable, else
"libhmsm.so" on the loader's path). Generates the paper-1 preset, places a small forest,
simulates one second of wind on the CPU, reads the skeleton and the mesh, skins one tree on the
CPU from the joint matrices, changes the wind and shows how errors come back. Exits non-zero if anything is not as expected (CTest runs it).
"""
import ctypes as C
import math
import os
import sys

# --- the C declarations, mirrored (keep in step with hmsm_c.h) ------------------------------
HMSM_C_ABI_VERSION = 2
OK, INVALID_ARGUMENT = 0, 1
BACKEND_CPU = 0
WIND_CONSTANT, WIND_Y1 = 1, 2
OUTPUT_NODE_POSITIONS, OUTPUT_VERTEX_POSITIONS, OUTPUT_JOINT_MATRICES = 0, 1, 6


class ModelOptions(C.Structure):
    _fields_ = [("grouping", C.c_int32), ("max_chain_segments", C.c_int32),
                ("ring_sides", C.c_int32), ("fix_weight", C.c_double)]


class Parameters(C.Structure):
    _fields_ = [(name, C.c_double) for name in
                ("density", "stiffness", "damping_ratio", "wind_gain", "max_angle", "dt",
                 "max_frequency")]


class Sized(C.Structure):
    """A sized struct (hmsm_c.h, "Sized structs"): struct_size first, set to this layout's size
    by the hmsm_*_init functions, which receive it from init() below."""

    def init(self, lib, init_function):
        check(lib, getattr(lib, init_function)(C.byref(self), C.sizeof(self)))
        return self


class Wind(Sized):
    _fields_ = [("struct_size", C.c_uint32), ("profile", C.c_int32), ("direction", C.c_double * 3), ("strength", C.c_double),
                ("frequency", C.c_double), ("front_speed", C.c_double),
                ("turbulence", C.c_double), ("seed", C.c_uint64)]


class Config(Sized):
    _fields_ = [("struct_size", C.c_uint32), ("backend", C.c_int32), ("composition", C.c_int32),
                ("vertex_layout", C.c_int32), ("profile_passes", C.c_int32), ("outputs", C.c_int32),
                ("model", ModelOptions), ("parameters", Parameters), ("wind", Wind)]


class Instance(Sized):
    _fields_ = [("struct_size", C.c_uint32), ("model", C.c_uint32), ("origin", C.c_double * 3), ("yaw", C.c_double),
                ("wind_scale", C.c_double), ("wind_phase", C.c_double), ("active", C.c_int32)]


class Counts(Sized):
    _fields_ = [("struct_size", C.c_uint32), ("instances", C.c_uint64), ("chains", C.c_uint64), ("nodes", C.c_uint64),
                ("vertices", C.c_uint64), ("steps_done", C.c_uint64), ("time", C.c_double)]


def load(path):
    lib = C.CDLL(path)
    P = C.c_void_p  # opaque handles
    sigs = {
        "hmsm_abi_version": (C.c_uint32, []),
        "hmsm_status_message": (C.c_char_p, []),
        "hmsm_status_name": (C.c_char_p, [C.c_int32]),
        "hmsm_config_init": (C.c_int32, [C.POINTER(Config), C.c_size_t]),
        "hmsm_wind_init": (C.c_int32, [C.POINTER(Wind), C.c_size_t]),
        "hmsm_instance_init": (C.c_int32, [C.POINTER(Instance), C.c_size_t]),
        "hmsm_counts_init": (C.c_int32, [C.POINTER(Counts), C.c_size_t]),
        "hmsm_tree_preset": (C.c_int32, [C.c_char_p, C.c_uint64, C.POINTER(P)]),
        "hmsm_tree_node_count": (C.c_int32, [P, C.POINTER(C.c_uint64)]),
        "hmsm_tree_destroy": (None, [P]),
        "hmsm_scene_create": (C.c_int32, [C.POINTER(P)]),
        "hmsm_scene_add_model": (C.c_int32, [P, P, C.c_char_p, C.POINTER(C.c_uint32)]),
        "hmsm_scene_add_instance": (C.c_int32, [P, C.POINTER(Instance)]),
        "hmsm_scene_destroy": (None, [P]),
        "hmsm_simulation_create": (C.c_int32, [P, C.POINTER(Config), C.POINTER(P)]),
        "hmsm_simulation_destroy": (None, [P]),
        "hmsm_simulation_step": (C.c_int32, [P, C.c_uint32]),
        "hmsm_simulation_read_f32": (C.c_int32, [P, C.c_int32, C.POINTER(C.c_float), C.c_size_t,
                                                 C.POINTER(C.c_size_t)]),
        "hmsm_simulation_counts": (C.c_int32, [P, C.POINTER(Counts)]),
        "hmsm_simulation_mesh_indices": (C.c_int32, [P, C.c_uint32, C.POINTER(C.c_uint32),
                                                     C.c_size_t, C.POINTER(C.c_size_t)]),
        "hmsm_simulation_set_wind": (C.c_int32, [P, C.POINTER(Wind)]),
        "hmsm_skin_create": (C.c_int32, [P, C.c_uint32, C.POINTER(P)]),
        "hmsm_skin_destroy": (None, [P]),
        "hmsm_skin_sizes": (C.c_int32, [P, C.POINTER(C.c_uint64), C.POINTER(C.c_uint64)]),
        "hmsm_skin_vertices": (C.c_int32, [P, C.POINTER(C.c_float), C.c_size_t, C.POINTER(C.c_float),
                                           C.POINTER(C.c_float), C.c_size_t, C.POINTER(C.c_size_t),
                                           C.c_uint32]),
    }
    for name, (restype, argtypes) in sigs.items():
        fn = getattr(lib, name)
        fn.restype, fn.argtypes = restype, argtypes
    return lib


class HmsmError(Exception):
    pass


def check(lib, status):
    """Raises with hmsm's message (per thread, of the last call) when a call failed."""
    if status != OK:
        raise HmsmError("%s: %s" % (lib.hmsm_status_name(status).decode(),
                                    lib.hmsm_status_message().decode()))


def read_f32(lib, sim, output):
    """Two calls: the size query, then the read into a buffer of that size."""
    count = C.c_size_t(0)
    check(lib, lib.hmsm_simulation_read_f32(sim, output, None, 0, C.byref(count)))
    values = (C.c_float * count.value)()
    check(lib, lib.hmsm_simulation_read_f32(sim, output, values, count.value, C.byref(count)))
    return values


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("HMSM_LIBRARY", "libhmsm.so")
    lib = load(path)
    assert lib.hmsm_abi_version() == HMSM_C_ABI_VERSION, "ABI version mismatch"

    tree, scene, sim = C.c_void_p(), C.c_void_p(), C.c_void_p()
    check(lib, lib.hmsm_tree_preset(b"paper-1", 0, C.byref(tree)))
    nodes_per_tree = C.c_uint64()
    check(lib, lib.hmsm_tree_node_count(tree, C.byref(nodes_per_tree)))

    check(lib, lib.hmsm_scene_create(C.byref(scene)))
    check(lib, lib.hmsm_scene_add_model(scene, tree, b"paper-1", None))
    for i in range(3):  # three trees in a row, 8 m apart, each turned a little
        instance = Instance().init(lib, "hmsm_instance_init")
        instance.origin[0] = 8.0 * i
        instance.yaw = 0.4 * i
        check(lib, lib.hmsm_scene_add_instance(scene, C.byref(instance)))

    config = Config().init(lib, "hmsm_config_init")
    config.backend = BACKEND_CPU
    config.wind.profile = WIND_CONSTANT
    config.wind.direction[:] = (1.0, 0.0, 0.0)
    check(lib, lib.hmsm_simulation_create(scene, C.byref(config), C.byref(sim)))
    lib.hmsm_scene_destroy(scene)  # the simulation keeps its own copy
    lib.hmsm_tree_destroy(tree)

    rest = list(read_f32(lib, sim, OUTPUT_NODE_POSITIONS))
    check(lib, lib.hmsm_simulation_step(sim, 120))  # one second at dt = 1/120 s
    counts = Counts().init(lib, "hmsm_counts_init")
    check(lib, lib.hmsm_simulation_counts(sim, C.byref(counts)))
    nodes = read_f32(lib, sim, OUTPUT_NODE_POSITIONS)
    vertices = read_f32(lib, sim, OUTPUT_VERTEX_POSITIONS)
    index_count = C.c_size_t()
    check(lib, lib.hmsm_simulation_mesh_indices(sim, 0, None, 0, C.byref(index_count)))

    assert counts.instances == 3 and counts.nodes == 3 * nodes_per_tree.value
    assert len(nodes) == 3 * counts.nodes and len(vertices) == 3 * counts.vertices
    assert all(math.isfinite(v) for v in vertices)
    moved = max(abs(a - b) for a, b in zip(nodes, rest))
    drift_x = sum(nodes[0::3]) / counts.nodes - sum(rest[0::3]) / counts.nodes
    print("%d trees, %d nodes, %d vertices, %d triangles per tree; after %.2f s the largest "
          "node displacement is %.3f m, mean x drift %+.3f m (wind along +x)"
          % (counts.instances, counts.nodes, counts.vertices, index_count.value // 3,
             counts.time, moved, drift_x))
    assert moved > 1e-3 and drift_x > 0.0, "the wind did not move the trees downwind"

    # CPU skinning of the second tree from its joint matrices (docs/skinning.md): it starts at
    # chain base 1 x chains in the palette and at vertex 1 x vertices-per-tree in the output.
    skin = C.c_void_p()
    check(lib, lib.hmsm_skin_create(sim, 0, C.byref(skin)))
    skin_vertices, skin_chains = C.c_uint64(), C.c_uint64()
    check(lib, lib.hmsm_skin_sizes(skin, C.byref(skin_vertices), C.byref(skin_chains)))
    palette = read_f32(lib, sim, OUTPUT_JOINT_MATRICES)
    base = 12 * skin_chains.value
    floats = 3 * skin_vertices.value
    skinned, normals, count = (C.c_float * floats)(), (C.c_float * floats)(), C.c_size_t()
    check(lib, lib.hmsm_skin_vertices(skin, C.cast(C.addressof(palette) + 4 * base, C.POINTER(C.c_float)),
                                      len(palette) - base, skinned, normals, floats, C.byref(count), 0))
    lib.hmsm_skin_destroy(skin)
    skin_error = max(abs(a - b) for a, b in zip(skinned, vertices[floats:2 * floats]))
    print("tree 1 skinned on the CPU: %d vertices from %d joints, within %.1e m of the simulation"
          % (skin_vertices.value, skin_chains.value, skin_error))
    assert count.value == floats and skin_error < 1e-3, "CPU skinning disagrees with the simulation"

    # Errors come back as codes with a message naming the argument; nothing is changed.
    wind = Wind().init(lib, "hmsm_wind_init")
    wind.profile = WIND_Y1
    wind.direction[:] = (0.0, 0.0, 0.0)  # a zero direction is invalid
    wind.strength, wind.frequency = 1.0, 0.1
    status = lib.hmsm_simulation_set_wind(sim, C.byref(wind))
    message = lib.hmsm_status_message().decode()
    print("set_wind with a zero direction: %s (%s)" % (lib.hmsm_status_name(status).decode(), message))
    assert status == INVALID_ARGUMENT and "direction" in message
    bad_config = Config().init(lib, "hmsm_config_init")
    bad_config.backend = 42
    try:
        check(lib, lib.hmsm_simulation_create(C.c_void_p(), C.byref(bad_config), C.byref(C.c_void_p())))
        raise AssertionError("a NULL scene was accepted")
    except HmsmError as error:
        print("create with a NULL scene:", error)

    # A struct whose struct_size is not a layout hmsm knows is refused, never overwritten.
    unsized = Config()
    sized_scene = C.c_void_p()
    check(lib, lib.hmsm_scene_create(C.byref(sized_scene)))
    status = lib.hmsm_simulation_create(sized_scene, C.byref(unsized), C.byref(C.c_void_p()))
    message = lib.hmsm_status_message().decode()
    lib.hmsm_scene_destroy(sized_scene)
    print("create with struct_size 0: %s (%s)" % (lib.hmsm_status_name(status).decode(), message))
    assert status == INVALID_ARGUMENT and "hmsm_config" in message

    lib.hmsm_simulation_destroy(sim)
    print("python example: ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
