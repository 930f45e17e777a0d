/* The C ABI (include/hmsm/hmsm_c.h) from a C99 program: every entry point with good and bad
 * arguments (NULL handles and outputs, too-small buffers, unknown enumerations, NaN), and a
 * simulation whose outputs are read back and checked. `c_api_test live` runs the live-control
 * part instead: it passes once hmsm::Simulation implements live control. */
#include "c_check.h"

#include <hmsm/hmsm_c.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void test_status_and_defaults(void) {
    hmsm_config config;
    hmsm_instance instance;
    hmsm_force_field field;
    uint32_t components = 0;
    CHECK(hmsm_abi_version() == HMSM_C_ABI_VERSION);
    CHECK(strcmp(hmsm_status_name(HMSM_OK), "ok") == 0);
    CHECK(strcmp(hmsm_status_name(HMSM_NO_DEVICE), "no_device") == 0);
    CHECK(strcmp(hmsm_status_name(12345), "unknown") == 0);
    HMSM_INIT(hmsm_config_init, &config);
    CHECK(config.backend == HMSM_BACKEND_AUTOMATIC);
    CHECK(config.model.ring_sides == 8);
    CHECK(fabs(config.parameters.dt - 1.0 / 120.0) < 1e-15);
    CHECK(config.wind.profile == HMSM_WIND_Y1 && config.wind.direction[0] == 1.0);
    HMSM_INIT(hmsm_instance_init, &instance);
    CHECK(instance.wind_scale == 1.0 && instance.active == 1);
    HMSM_INIT(hmsm_force_field_init, &field);
    CHECK(field.radius == 1.0);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_config_init(NULL, sizeof config));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_wind_init(NULL, sizeof(hmsm_wind)));
    CHECK_OK(hmsm_output_components(HMSM_OUTPUT_CHAIN_ROTATIONS, &components));
    CHECK(components == 9);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_output_components(HMSM_OUTPUT_COUNT, &components));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_output_components(-1, &components));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_output_components(0, NULL));
}

static void test_trees(void) {
    hmsm_tree* tree = NULL;
    uint64_t nodes = 0;
    const char* json = "{\"format\": \"hmsm-tree\", \"version\": 1, \"nodes\": []}";
    const int32_t parents[2] = {-1, 0};
    double positions[6] = {0, 0, 0, 0, 1, 0};
    const double radii[2] = {0.1, 0.1};

    CHECK_OK(hmsm_tree_preset("paper-1", 0, &tree));
    CHECK_OK(hmsm_tree_node_count(tree, &nodes));
    CHECK(nodes > 100);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_node_count(NULL, &nodes));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_node_count(tree, NULL));
    hmsm_tree_destroy(tree);
    hmsm_tree_destroy(NULL);

    tree = NULL;
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_preset("no-such-preset", 0, &tree));
    CHECK(tree == NULL);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_preset(NULL, 0, &tree));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_preset("paper-1", 0, NULL));
    CHECK_FAILS(HMSM_IO, hmsm_tree_load("/nonexistent/tree.json", &tree));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_load(NULL, &tree));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_load("tree.json", NULL));
    CHECK_FAILS(HMSM_INVALID_TREE, hmsm_tree_parse(json, strlen(json), &tree));
    CHECK_FAILS(HMSM_INVALID_TREE, hmsm_tree_parse("{", 1, &tree));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_parse(NULL, 0, &tree));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_parse(json, strlen(json), NULL));
    CHECK(tree == NULL);

    positions[4] = NAN;
    CHECK_FAILS(HMSM_INVALID_TREE, hmsm_tree_from_nodes(parents, positions, radii, 2, &tree));
    CHECK(strstr(hmsm_status_message(), "node") != NULL);
    positions[4] = 1.0;
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_from_nodes(NULL, positions, radii, 2, &tree));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_from_nodes(parents, NULL, radii, 2, &tree));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_from_nodes(parents, positions, NULL, 2, &tree));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_from_nodes(parents, positions, radii, 2, NULL));
    CHECK(tree == NULL);
}

static void test_scenes(void) {
    hmsm_tree* tree = small_tree();
    hmsm_scene* scene = NULL;
    hmsm_instance instance;
    uint32_t model = 99, models = 0;
    uint64_t instances = 0;

    CHECK_OK(hmsm_scene_create(&scene));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_scene_create(NULL));
    CHECK_OK(hmsm_scene_add_model(scene, tree, "small", &model));
    CHECK(model == 0);
    CHECK_OK(hmsm_scene_add_model(scene, tree, "again", NULL));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_scene_add_model(NULL, tree, "x", NULL));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_scene_add_model(scene, NULL, "x", NULL));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_scene_add_model(scene, tree, NULL, NULL));

    HMSM_INIT(hmsm_instance_init, &instance);
    instance.origin[0] = 5.0;
    CHECK_OK(hmsm_scene_add_instance(scene, &instance));
    instance.model = 2;
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_scene_add_instance(scene, &instance));
    CHECK(strstr(hmsm_status_message(), "model 2") != NULL);
    instance.model = 0;
    instance.origin[1] = NAN;
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_scene_add_instance(scene, &instance));
    instance.origin[1] = 0.0;
    instance.wind_scale = -1.0;
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_scene_add_instance(scene, &instance));
    instance.wind_scale = 1.0;
    instance.active = 2;
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_scene_add_instance(scene, &instance));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_scene_add_instance(scene, NULL));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_scene_add_instance(NULL, &instance));

    CHECK_OK(hmsm_scene_model_count(scene, &models));
    CHECK_OK(hmsm_scene_instance_count(scene, &instances));
    CHECK(models == 2 && instances == 1);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_scene_model_count(NULL, &models));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_scene_model_count(scene, NULL));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_scene_instance_count(NULL, &instances));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_scene_instance_count(scene, NULL));
    CHECK_FAILS(HMSM_IO, hmsm_scene_load_forest("/nonexistent/forest.json", &scene));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_scene_load_forest(NULL, &scene));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_scene_load_forest("forest.json", NULL));
    hmsm_scene_destroy(scene);
    hmsm_scene_destroy(NULL);
    hmsm_tree_destroy(tree);
}

/* One model, two instances: the second 10 m away with yaw; cpu backend, constant wind. */
static hmsm_simulation* small_simulation(void) {
    hmsm_tree* tree = small_tree();
    hmsm_scene* scene = NULL;
    hmsm_instance instance;
    hmsm_config config;
    hmsm_simulation* simulation = NULL;
    CHECK_OK(hmsm_scene_create(&scene));
    CHECK_OK(hmsm_scene_add_model(scene, tree, "small", NULL));
    HMSM_INIT(hmsm_instance_init, &instance);
    CHECK_OK(hmsm_scene_add_instance(scene, &instance));
    instance.origin[0] = 10.0;
    instance.yaw = 0.5;
    CHECK_OK(hmsm_scene_add_instance(scene, &instance));
    HMSM_INIT(hmsm_config_init, &config);
    config.backend = HMSM_BACKEND_CPU;
    config.wind.profile = HMSM_WIND_CONSTANT;
    CHECK_OK(hmsm_simulation_create(scene, &config, &simulation));
    /* The simulation keeps its own copy: the caller's objects can go. */
    hmsm_scene_destroy(scene);
    hmsm_tree_destroy(tree);
    return simulation;
}

static void test_simulation(void) {
    hmsm_simulation* simulation = small_simulation();
    hmsm_counts counts;
    size_t count = 0, needed = 0;
    float small[4];
    float* nodes = NULL;
    double* nodes64 = NULL;
    uint32_t* indices = NULL;
    int32_t backend = -1;
    char name[256];
    size_t i;

    CHECK(simulation != NULL);
    if (!simulation) return;
    CHECK_OK(HMSM_INIT(hmsm_counts_init, &counts));
    CHECK_OK(hmsm_simulation_counts(simulation, &counts));
    CHECK(counts.instances == 2 && counts.nodes == 6 && counts.chains == 2);
    CHECK(counts.vertices > 0 && counts.steps_done == 0);
    CHECK_OK(hmsm_simulation_step(simulation, 60));
    CHECK_OK(hmsm_simulation_counts(simulation, &counts));
    CHECK(counts.steps_done == 60 && fabs(counts.time - 0.5) < 1e-12);

    /* size query, too-small buffer (count still reported, nothing written), full read */
    CHECK_OK(hmsm_simulation_read_f32(simulation, HMSM_OUTPUT_NODE_POSITIONS, NULL, 0, &needed));
    CHECK(needed == 18);
    small[0] = 42.0f;
    CHECK_FAILS(HMSM_INVALID_ARGUMENT,
                hmsm_simulation_read_f32(simulation, HMSM_OUTPUT_NODE_POSITIONS, small, 4, &count));
    CHECK(count == 18 && small[0] == 42.0f);
    nodes = (float*)malloc(needed * sizeof *nodes);
    nodes64 = (double*)malloc(needed * sizeof *nodes64);
    CHECK_OK(hmsm_simulation_read_f32(simulation, HMSM_OUTPUT_NODE_POSITIONS, nodes, needed, &count));
    CHECK_OK(hmsm_simulation_read_f64(simulation, HMSM_OUTPUT_NODE_POSITIONS, nodes64, needed, &count));
    for (i = 0; i < needed; ++i) CHECK(isfinite(nodes[i]) && fabs(nodes[i] - nodes64[i]) < 1e-5);
    CHECK(nodes[6] > 0.3f);                      /* the tip of instance 0 bends downwind (+x) */
    CHECK(fabs(nodes[9] - 10.0f) < 1e-6);        /* instance 1's root stays at its origin */
    CHECK_FAILS(HMSM_INVALID_ARGUMENT,
                hmsm_simulation_read_f32(simulation, HMSM_OUTPUT_COUNT, nodes, needed, &count));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_read_f32(simulation, -1, nodes, needed, &count));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_read_f32(simulation, 0, nodes, needed, NULL));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_read_f32(simulation, 0, NULL, needed, &count));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_read_f32(NULL, 0, nodes, needed, &count));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_read_f64(NULL, 0, nodes64, needed, &count));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_read_f64(simulation, 0, nodes64, 3, &count));
    CHECK_OK(hmsm_simulation_read_f32(simulation, HMSM_OUTPUT_CHAIN_ANGLES, NULL, 0, &count));
    CHECK(count == counts.chains * 4);

    /* asynchronous read: the values at the request, though the simulation stepped since */
    CHECK_FAILS(HMSM_INVALID_ARGUMENT,
                hmsm_simulation_take_read_f32(simulation, HMSM_OUTPUT_NODE_POSITIONS, nodes, needed, &count));
    CHECK_OK(hmsm_simulation_request_read(simulation, HMSM_OUTPUT_NODE_POSITIONS));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_request_read(simulation, HMSM_OUTPUT_COUNT));
    CHECK_OK(hmsm_simulation_step(simulation, 5));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT,
                hmsm_simulation_take_read_f32(simulation, HMSM_OUTPUT_NODE_POSITIONS, small, 4, &count));
    CHECK(count == needed);
    CHECK_OK(hmsm_simulation_take_read_f64(simulation, HMSM_OUTPUT_NODE_POSITIONS, nodes64, needed, &count));
    for (i = 0; i < needed; ++i) CHECK(nodes64[i] == (double)nodes[i]);
    CHECK_OK(hmsm_simulation_read_f64(simulation, HMSM_OUTPUT_NODE_POSITIONS, nodes64, needed, &count));
    CHECK(nodes64[6] != (double)nodes[6]); /* the tip moved in those 5 steps */

    CHECK_OK(hmsm_simulation_backend(simulation, &backend));
    CHECK(backend == HMSM_BACKEND_CPU);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_backend(simulation, NULL));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_backend(NULL, &backend));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_device_name(simulation, name, 1, &count));
    CHECK(count > 1);
    CHECK_OK(hmsm_simulation_device_name(simulation, name, sizeof name, &count));
    CHECK(strlen(name) + 1 == count);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_device_name(NULL, name, sizeof name, &count));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_device_name(simulation, name, sizeof name, NULL));

    CHECK_OK(hmsm_simulation_mesh_indices(simulation, 0, NULL, 0, &needed));
    CHECK(needed > 0 && needed % 3 == 0);
    indices = (uint32_t*)malloc(needed * sizeof *indices);
    CHECK_OK(hmsm_simulation_mesh_indices(simulation, 0, indices, needed, &count));
    for (i = 0; i < needed; ++i) CHECK(indices[i] < counts.vertices / 2);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_mesh_indices(simulation, 1, indices, needed, &count));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_mesh_indices(NULL, 0, indices, needed, &count));

    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_step(NULL, 1));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_counts(NULL, &counts));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_counts(simulation, NULL));
    free(indices);
    free(nodes64);
    free(nodes);
    hmsm_simulation_destroy(simulation);
    hmsm_simulation_destroy(NULL);
}

static void test_bad_configs(void) {
    hmsm_tree* tree = small_tree();
    hmsm_scene* scene = NULL;
    hmsm_instance instance;
    hmsm_config config;
    hmsm_simulation* simulation = NULL;
    CHECK_OK(hmsm_scene_create(&scene));
    CHECK_OK(hmsm_scene_add_model(scene, tree, "small", NULL));
    HMSM_INIT(hmsm_instance_init, &instance);
    CHECK_OK(hmsm_scene_add_instance(scene, &instance));

#define CHECK_CONFIG_FAILS(field, value)                                                       \
    do {                                                                                       \
        HMSM_INIT(hmsm_config_init, &config);                                                             \
        config.backend = HMSM_BACKEND_CPU;                                                     \
        config.field = (value);                                                                \
        CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_create(scene, &config, &simulation)); \
        CHECK(simulation == NULL);                                                             \
    } while (0)
    CHECK_CONFIG_FAILS(backend, 99);
    CHECK_CONFIG_FAILS(backend, -1);
    CHECK_CONFIG_FAILS(composition, HMSM_COMPOSITION_AUTOMATIC + 1);
    CHECK_CONFIG_FAILS(composition, -1);
    CHECK_CONFIG_FAILS(composition, 4); /* reserved */
    CHECK(strstr(hmsm_status_message(), "config.composition: unknown value 4") != NULL);
    /* 1 and 2 are reserved too: pointer jumping chooses its dispatch form by size */
    CHECK_CONFIG_FAILS(composition, 1);
    CHECK(strstr(hmsm_status_message(), "config.composition: unknown value 1 (values 1, 2 and 4 are reserved)") != NULL);
    CHECK_CONFIG_FAILS(composition, 2);
    CHECK(strstr(hmsm_status_message(), "config.composition: unknown value 2") != NULL);
    /* The default is automatic, and the last two compositions are accepted. */
    HMSM_INIT(hmsm_config_init, &config);
    CHECK(config.composition == HMSM_COMPOSITION_AUTOMATIC);
    config.backend = HMSM_BACKEND_CPU;
    config.composition = HMSM_COMPOSITION_PATH_WALK;
    CHECK_OK(hmsm_simulation_create(scene, &config, &simulation));
    hmsm_simulation_destroy(simulation);
    simulation = NULL;
    config.composition = HMSM_COMPOSITION_AUTOMATIC;
    CHECK_OK(hmsm_simulation_create(scene, &config, &simulation));
    hmsm_simulation_destroy(simulation);
    simulation = NULL;
    CHECK_CONFIG_FAILS(vertex_layout, 2);
    CHECK_CONFIG_FAILS(profile_passes, 7);
    CHECK_CONFIG_FAILS(outputs, 3);
    CHECK_CONFIG_FAILS(model.grouping, 2);
    CHECK_CONFIG_FAILS(model.ring_sides, 2);
    CHECK_CONFIG_FAILS(parameters.dt, NAN);
    CHECK_CONFIG_FAILS(parameters.stiffness, -1.0);
    CHECK_CONFIG_FAILS(wind.profile, 8);
    CHECK_CONFIG_FAILS(wind.strength, NAN);
    CHECK_CONFIG_FAILS(wind.direction[0], 0.0);
    CHECK_CONFIG_FAILS(exchange, 2);
    CHECK(strstr(hmsm_status_message(), "config.exchange: unknown value 2") != NULL);
    /* the articulated exchange needs the coupled dynamics */
    CHECK_CONFIG_FAILS(exchange, HMSM_EXCHANGE_ARTICULATED);
    CHECK(strstr(hmsm_status_message(), "exchange articulated needs dynamics coupled") != NULL);
#undef CHECK_CONFIG_FAILS
    HMSM_INIT(hmsm_config_init, &config);
    CHECK(config.exchange == HMSM_EXCHANGE_HELD);
    config.backend = HMSM_BACKEND_CPU;
    config.dynamics = HMSM_DYNAMICS_COUPLED;
    config.exchange = HMSM_EXCHANGE_ARTICULATED;
    CHECK_OK(hmsm_simulation_create(scene, &config, &simulation));
    CHECK_OK(hmsm_simulation_step(simulation, 3));
    hmsm_simulation_destroy(simulation);
    simulation = NULL;

    HMSM_INIT(hmsm_config_init, &config);
    config.backend = HMSM_BACKEND_CPU;
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_create(NULL, &config, &simulation));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_create(scene, NULL, &simulation));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_create(scene, &config, NULL));
    hmsm_scene_destroy(scene);
    hmsm_tree_destroy(tree);
}

/* Live control: the argument checks of the C layer (these pass in every build). */
static void test_live_control_arguments(void) {
    hmsm_simulation* simulation = small_simulation();
    hmsm_wind wind;
    hmsm_force_field fields[17];
    hmsm_instance instance;
    uint64_t index = 0;
    size_t count = 0, i;
    if (!simulation) return;

    HMSM_INIT(hmsm_wind_init, &wind);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_wind(NULL, &wind));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_wind(simulation, NULL));
    wind.profile = -3;
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_wind(simulation, &wind));
    HMSM_INIT(hmsm_wind_init, &wind);
    wind.frequency = NAN;
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_wind(simulation, &wind));
    CHECK_OK(hmsm_simulation_get_wind(simulation, &wind));
    CHECK(wind.profile == HMSM_WIND_CONSTANT); /* unchanged by the rejected calls */
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_get_wind(NULL, &wind));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_get_wind(simulation, NULL));

    for (i = 0; i < 17; ++i) HMSM_INIT(hmsm_force_field_init, &fields[i]);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_force_fields(simulation, fields, 17));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_force_fields(simulation, NULL, 1));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_force_fields(NULL, fields, 1));
    fields[0].kind = 5;
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_force_fields(simulation, fields, 1));
    fields[0].kind = HMSM_FORCE_FIELD_RADIAL;
    fields[0].radius = NAN;
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_force_fields(simulation, fields, 1));
    fields[0].radius = 0.0;
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_force_fields(simulation, fields, 1));

    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_instance_wind_scale(simulation, 2, 1.0));
    CHECK(strstr(hmsm_status_message(), "instance 2") != NULL);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_instance_wind_scale(simulation, 0, NAN));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_instance_wind_scale(simulation, 0, -0.5));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_instance_wind_scale(NULL, 0, 1.0));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_instance_wind_phase(simulation, 0, INFINITY));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_instance_wind_phase(simulation, 9, 0.0));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_instance_wind_phase(NULL, 0, 0.0));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_instance_active(simulation, 0, 2));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_instance_active(simulation, 5, 1));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_instance_active(NULL, 0, 1));

    HMSM_INIT(hmsm_instance_init, &instance);
    instance.yaw = NAN;
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_add_instances(simulation, &instance, 1));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_add_instances(simulation, NULL, 1));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_add_instances(NULL, &instance, 1));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_remove_instances(simulation, NULL, 1));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_remove_instances(NULL, &index, 1));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_instances(NULL, &instance, 1, &count));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_instances(simulation, &instance, 1, NULL));
    hmsm_simulation_destroy(simulation);
}

/* Live control through the C ABI onto hmsm::Simulation: wind, instances, force fields. */
static void test_live_control(void) {
    hmsm_simulation* simulation = small_simulation();
    hmsm_wind wind;
    hmsm_force_field field;
    hmsm_instance list[4];
    hmsm_counts counts;
    uint64_t remove = 0;
    size_t count = 0;
    float before[18], after[18];
    if (!simulation) return;

    CHECK_OK(HMSM_INIT(hmsm_counts_init, &counts));
    CHECK_OK(HMSM_INIT(hmsm_instance_init, &list[0]));
    CHECK_OK(hmsm_simulation_instances(simulation, list, 4, &count));
    CHECK(count == 2 && list[1].origin[0] == 10.0 && list[1].yaw == 0.5);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_instances(simulation, list, 1, &count));

    HMSM_INIT(hmsm_wind_init, &wind);
    wind.profile = HMSM_WIND_CONSTANT;
    wind.direction[0] = 0.0;
    wind.direction[2] = 1.0;
    CHECK_OK(hmsm_simulation_set_wind(simulation, &wind));
    CHECK_OK(hmsm_simulation_get_wind(simulation, &wind));
    CHECK(wind.direction[2] == 1.0);
    CHECK_OK(hmsm_simulation_step(simulation, 120));
    CHECK_OK(hmsm_simulation_read_f32(simulation, HMSM_OUTPUT_NODE_POSITIONS, before, 18, &count));
    CHECK(before[8] > 0.0f); /* wind along +z bends the tip toward +z */

    CHECK_OK(hmsm_simulation_set_instance_active(simulation, 0, 0));
    CHECK_OK(hmsm_simulation_set_instance_wind_scale(simulation, 1, 0.5));
    CHECK_OK(hmsm_simulation_set_instance_wind_phase(simulation, 1, 0.25));
    CHECK_OK(hmsm_simulation_step(simulation, 10));
    CHECK_OK(hmsm_simulation_read_f32(simulation, HMSM_OUTPUT_NODE_POSITIONS, after, 18, &count));
    CHECK(memcmp(before, after, 9 * sizeof(float)) == 0); /* inactive: frozen */

    HMSM_INIT(hmsm_force_field_init, &field);
    field.kind = HMSM_FORCE_FIELD_RADIAL;
    field.radius = 3.0;
    field.radial = 5.0;
    CHECK_OK(hmsm_simulation_set_force_fields(simulation, &field, 1));
    CHECK_OK(hmsm_simulation_set_force_fields(simulation, NULL, 0));

    HMSM_INIT(hmsm_instance_init, &list[0]);
    list[0].origin[2] = -7.0;
    CHECK_OK(hmsm_simulation_add_instances(simulation, list, 1));
    CHECK_OK(hmsm_simulation_counts(simulation, &counts));
    CHECK(counts.instances == 3 && counts.nodes == 9);
    CHECK_OK(hmsm_simulation_remove_instances(simulation, &remove, 1));
    CHECK_OK(hmsm_simulation_instances(simulation, list, 4, &count));
    CHECK(count == 2 && list[0].origin[0] == 10.0 && list[1].origin[2] == -7.0);
    remove = 5;
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_simulation_remove_instances(simulation, &remove, 1));
    CHECK_OK(hmsm_simulation_step(simulation, 1));
    hmsm_simulation_destroy(simulation);
}

/* Skins from C: sizes, the joints of every vertex, and CPU skinning of instance 1 (from its chain
 * base) against the simulation's own vertices; tests/c_api/c_skin_test.cpp compares every value
 * with hmsm::build_skin(). */
static void test_skin(void) {
    hmsm_simulation* simulation = small_simulation();
    hmsm_skin* skin = NULL;
    uint64_t vertices = 0, chains = 0;
    size_t count = 0, i;
    int32_t joints[4096];
    float palette[48], simulated[6144], skinned[3072];
    if (!simulation) return;
    CHECK_OK(hmsm_simulation_step(simulation, 30));
    CHECK_OK(hmsm_skin_create(simulation, 0, &skin));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_skin_create(simulation, 1, &skin));
    CHECK_OK(hmsm_skin_sizes(skin, &vertices, &chains));
    CHECK(chains == 1 && vertices > 0 && 2 * vertices <= 4096); /* one chain per tree */
    CHECK_OK(hmsm_skin_read_i32(skin, HMSM_SKIN_JOINTS, joints, 4096, &count));
    CHECK(count == 2 * vertices);
    for (i = 0; i < count; ++i) CHECK(joints[i] >= -1 && joints[i] < (int32_t)chains);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_skin_read_f32(skin, HMSM_SKIN_JOINTS, skinned, 3072, &count));
    CHECK_OK(hmsm_simulation_read_f32(simulation, HMSM_OUTPUT_JOINT_MATRICES, palette, 48, &count));
    CHECK(count == 2 * 12 * chains);
    CHECK_OK(hmsm_simulation_read_f32(simulation, HMSM_OUTPUT_VERTEX_POSITIONS, simulated, 6144, &count));
    CHECK_OK(hmsm_skin_vertices(skin, palette + 12 * chains, 12 * chains, skinned, NULL, 3072, &count, 1));
    CHECK(count == 3 * vertices);
    for (i = 0; i < count; ++i) CHECK(fabs(skinned[i] - simulated[3 * vertices + i]) < 1e-4);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT,
                hmsm_skin_vertices(skin, palette, 12 * chains - 1, skinned, NULL, 3072, &count, 1));
    hmsm_skin_destroy(skin);
    hmsm_skin_destroy(NULL);
    hmsm_simulation_destroy(simulation);
}

int main(int argc, char** argv) {
    if (argc > 1 && strcmp(argv[1], "live") == 0) {
        test_live_control();
    } else {
        test_status_and_defaults();
        test_trees();
        test_scenes();
        test_simulation();
        test_bad_configs();
        test_live_control_arguments();
        test_skin();
    }
    if (failures) fprintf(stderr, "%d check(s) failed\n", failures);
    else printf("all checks passed\n");
    return failures ? 1 : 0;
}
