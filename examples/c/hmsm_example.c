/* A tree in wind through hmsm's C ABI (include/hmsm/hmsm_c.h, docs/engine.md): generate the
 * paper-1 preset (or load an hmsm-tree file), simulate half a second of Y1 wind on the CPU
 * backend, and read the joint matrices an engine skins with and the vertex positions it draws;
 * then skin the last frame on the CPU from the joint matrices (hmsm_skin_vertices), as an
 * engine without GPU skinning would, and compare with the simulation's own vertices.
 *
 *   hmsm_example_c [TREE.json]
 *
 * Every call's status is checked; a failure prints hmsm's message, which names the offending
 * argument or item, and exits 1. Link against the shared library (libhmsm.so, hmsm_shared in the
 * build tree, hmsm::hmsm_shared or hmsm::hmsm when installed with BUILD_SHARED_LIBS).
 */
#include <hmsm/hmsm_c.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* Prints the failed call and hmsm's message; returns whether `status` is HMSM_OK. */
static int ok(hmsm_status status, const char* call) {
    if (status == HMSM_OK) return 1;
    fprintf(stderr, "hmsm_example_c: %s: %s: %s\n", call, hmsm_status_name(status), hmsm_status_message());
    return 0;
}

/* Reads a float output whole: queries its size, allocates, reads. NULL after a failure. */
static float* read_output(const hmsm_simulation* simulation, int32_t output, size_t* count) {
    if (!ok(hmsm_simulation_read_f32(simulation, output, NULL, 0, count), "hmsm_simulation_read_f32 (size)"))
        return NULL;
    float* values = malloc(*count * sizeof *values);
    if (values == NULL) {
        fprintf(stderr, "hmsm_example_c: out of memory for %zu floats\n", *count);
        return NULL;
    }
    if (!ok(hmsm_simulation_read_f32(simulation, output, values, *count, count), "hmsm_simulation_read_f32")) {
        free(values);
        return NULL;
    }
    return values;
}

/* Skins the tree (instance 0 of model 0) from `joints` on the CPU and returns the largest
 * distance to the simulation's `positions`, or -1 after a failure. */
static double skin_on_cpu(const hmsm_simulation* simulation, const float* joints, size_t joint_floats,
                          const float* positions) {
    double largest = -1.0;
    hmsm_skin* skin = NULL;
    float* skinned = NULL;
    uint64_t vertices = 0, chains = 0;
    size_t count = 0;
    if (!ok(hmsm_skin_create(simulation, 0, &skin), "hmsm_skin_create") ||
        !ok(hmsm_skin_sizes(skin, &vertices, &chains), "hmsm_skin_sizes"))
        goto done;
    skinned = malloc(3 * vertices * sizeof *skinned);
    if (skinned == NULL) goto done;
    /* Normals are optional (NULL); 0 threads = every hardware thread. */
    if (!ok(hmsm_skin_vertices(skin, joints, joint_floats, skinned, NULL, 3 * vertices, &count, 0),
            "hmsm_skin_vertices"))
        goto done;
    largest = 0.0;
    for (size_t i = 0; i < count; ++i) {
        const double d = fabs((double)skinned[i] - positions[i]);
        if (!(d <= largest)) largest = d; /* a NaN propagates */
    }
done:
    free(skinned);
    hmsm_skin_destroy(skin);
    return largest;
}

int main(int argc, char** argv) {
    if (argc > 2) {
        fprintf(stderr, "usage: hmsm_example_c [TREE.json]\n");
        return 2;
    }
    int result = 1;
    hmsm_tree* tree = NULL;
    hmsm_scene* scene = NULL;
    hmsm_simulation* simulation = NULL;
    float *rest = NULL, *positions = NULL, *joints = NULL;

    if (argc == 2 ? !ok(hmsm_tree_load(argv[1], &tree), "hmsm_tree_load")
                  : !ok(hmsm_tree_preset("paper-1", 0, &tree), "hmsm_tree_preset"))
        goto done;

    /* One instance of the tree at the origin. */
    uint32_t model = 0;
    hmsm_instance instance;
    if (!ok(HMSM_INIT(hmsm_instance_init, &instance), "hmsm_instance_init") ||
        !ok(hmsm_scene_create(&scene), "hmsm_scene_create") ||
        !ok(hmsm_scene_add_model(scene, tree, argc == 2 ? argv[1] : "paper-1", &model), "hmsm_scene_add_model"))
        goto done;
    instance.model = model;
    if (!ok(hmsm_scene_add_instance(scene, &instance), "hmsm_scene_add_instance")) goto done;

    /* The CPU backend (runs everywhere), Y1 wind along +x. */
    hmsm_config config;
    if (!ok(HMSM_INIT(hmsm_config_init, &config), "hmsm_config_init")) goto done;
    config.backend = HMSM_BACKEND_CPU;
    config.wind.profile = HMSM_WIND_Y1;
    config.wind.direction[0] = 1.0;
    config.wind.direction[1] = 0.0;
    config.wind.direction[2] = 0.0;
    if (!ok(hmsm_simulation_create(scene, &config, &simulation), "hmsm_simulation_create")) goto done;
    /* The simulation keeps its own copy of the scene. */
    hmsm_scene_destroy(scene);
    scene = NULL;
    hmsm_tree_destroy(tree);
    tree = NULL;

    /* Buffers sized once: the rest pose, then the positions and joint matrices of each frame. */
    size_t vertex_floats = 0, joint_floats = 0;
    rest = read_output(simulation, HMSM_OUTPUT_VERTEX_POSITIONS, &vertex_floats);
    if (rest == NULL) goto done;
    positions = read_output(simulation, HMSM_OUTPUT_VERTEX_POSITIONS, &vertex_floats);
    if (positions == NULL) goto done;
    joints = read_output(simulation, HMSM_OUTPUT_JOINT_MATRICES, &joint_floats);
    if (joints == NULL) goto done;

    /* Two fixed steps per 60 Hz frame, 30 frames; read what an engine reads each frame. */
    for (int frame = 0; frame < 30; ++frame) {
        size_t read = 0;
        if (!ok(hmsm_simulation_step(simulation, 2), "hmsm_simulation_step") ||
            !ok(hmsm_simulation_read_f32(simulation, HMSM_OUTPUT_VERTEX_POSITIONS, positions, vertex_floats, &read),
                "hmsm_simulation_read_f32 (vertex positions)") ||
            !ok(hmsm_simulation_read_f32(simulation, HMSM_OUTPUT_JOINT_MATRICES, joints, joint_floats, &read),
                "hmsm_simulation_read_f32 (joint matrices)"))
            goto done;
    }

    hmsm_counts counts;
    uint32_t joint_components = 0;
    if (!ok(HMSM_INIT(hmsm_counts_init, &counts), "hmsm_counts_init") ||
        !ok(hmsm_simulation_counts(simulation, &counts), "hmsm_simulation_counts") ||
        !ok(hmsm_output_components(HMSM_OUTPUT_JOINT_MATRICES, &joint_components), "hmsm_output_components"))
        goto done;

    /* The largest vertex displacement from the rest pose, and a check that all is finite. */
    double largest = 0.0;
    for (size_t v = 0; v + 2 < vertex_floats; v += 3) {
        const double dx = positions[v] - rest[v], dy = positions[v + 1] - rest[v + 1],
                     dz = positions[v + 2] - rest[v + 2];
        const double d = sqrt(dx * dx + dy * dy + dz * dz);
        if (!isfinite(d)) {
            fprintf(stderr, "hmsm_example_c: vertex %zu is not finite\n", v / 3);
            goto done;
        }
        if (d > largest) largest = d;
    }
    for (size_t j = 0; j < joint_floats; ++j) {
        if (!isfinite(joints[j])) {
            fprintf(stderr, "hmsm_example_c: joint matrix element %zu is not finite\n", j);
            goto done;
        }
    }
    if (!(largest > 0.0)) {
        fprintf(stderr, "hmsm_example_c: the tree did not move in %.2f s of wind\n", counts.time);
        goto done;
    }
    printf("%llu chains (%zu joint matrices of %u floats), %llu vertices, %llu steps = %.2f s of Y1 wind\n",
           (unsigned long long)counts.chains, joint_floats / joint_components, joint_components,
           (unsigned long long)counts.vertices, (unsigned long long)counts.steps_done, counts.time);
    printf("largest vertex displacement from rest: %.4f m\n", largest);

    /* The same frame skinned on the CPU from the joint matrices: the skin and pass 7 are the
     * same formula, so only float rounding separates them. */
    const double skin_error = skin_on_cpu(simulation, joints, joint_floats, positions);
    if (!(skin_error >= 0.0 && skin_error < 1e-3)) {
        fprintf(stderr, "hmsm_example_c: CPU skinning is %g m from the simulation's vertices\n", skin_error);
        goto done;
    }
    printf("skinned on the CPU from the joint matrices: within %.1e m of the simulation's vertices\n",
           skin_error);
    result = 0;

done:
    free(rest);
    free(positions);
    free(joints);
    hmsm_simulation_destroy(simulation);
    hmsm_scene_destroy(scene);
    hmsm_tree_destroy(tree);
    return result;
}
