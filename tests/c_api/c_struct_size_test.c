/* Sized structs of the C ABI (include/hmsm/hmsm_c.h, "Sized structs"): a struct from an older
 * header (here: the current definition without its last field) is served through every call
 * that reads or fills it, and nothing past its end is written (guard bytes); a zero, too small,
 * too large or unknown struct_size is refused with a message naming the struct and changes
 * nothing. */
#include "c_check.h"

#include <hmsm/hmsm_c.h>

#include <stdio.h>
#include <string.h>

/* A refusal: HMSM_INVALID_ARGUMENT with a message naming `name` and "struct_size". */
#define CHECK_REFUSED(call, name)                                                         \
    do {                                                                                  \
        CHECK((call) == HMSM_INVALID_ARGUMENT);                                           \
        CHECK(strstr(hmsm_status_message(), name) != NULL);                               \
        CHECK(strstr(hmsm_status_message(), "struct_size") != NULL);                      \
    } while (0)

/* The layouts of an older header: each struct without its last field. */
typedef struct older_config {
    uint32_t struct_size;
    int32_t backend;
    int32_t composition;
    int32_t vertex_layout;
    int32_t profile_passes;
    int32_t outputs;
    hmsm_model_options model;
    hmsm_parameters parameters;
} older_config;
typedef struct older_wind {
    uint32_t struct_size;
    int32_t profile;
    double direction[3];
    double strength;
    double frequency;
    double front_speed;
    double turbulence;
} older_wind;
typedef struct older_instance {
    uint32_t struct_size;
    uint32_t model;
    double origin[3];
    double yaw;
    double wind_scale;
    double wind_phase;
} older_instance;
typedef struct older_force_field {
    uint32_t struct_size;
    int32_t kind;
    double center[3];
    double radius;
    double directional[3];
} older_force_field;
typedef struct older_counts {
    uint32_t struct_size;
    uint64_t instances;
    uint64_t chains;
    uint64_t nodes;
    uint64_t vertices;
    uint64_t steps_done;
} older_counts;

#define GUARD 0xA5
#define GUARD_BYTES 64

static int guard_intact(const unsigned char* guard) {
    int i;
    for (i = 0; i < GUARD_BYTES; ++i)
        if (guard[i] != GUARD) return 0;
    return 1;
}

static hmsm_scene* one_tree_scene(void) {
    hmsm_tree* tree = small_tree();
    hmsm_scene* scene = NULL;
    hmsm_instance instance;
    CHECK(hmsm_scene_create(&scene) == HMSM_OK);
    CHECK(hmsm_scene_add_model(scene, tree, "small", NULL) == HMSM_OK);
    CHECK(HMSM_INIT(hmsm_instance_init, &instance) == HMSM_OK);
    CHECK(hmsm_scene_add_instance(scene, &instance) == HMSM_OK);
    hmsm_tree_destroy(tree);
    return scene;
}

/* Every call taking or filling a struct, each with the older layout and guard bytes after it. */
static void test_older_layouts(void) {
    struct { older_config config; unsigned char guard[GUARD_BYTES]; } config_box;
    struct { older_wind wind; unsigned char guard[GUARD_BYTES]; } wind_box;
    struct { older_instance items[2]; unsigned char guard[GUARD_BYTES]; } instance_box;
    struct { older_force_field field; unsigned char guard[GUARD_BYTES]; } field_box;
    struct { older_counts counts; unsigned char guard[GUARD_BYTES]; } counts_box;
    hmsm_scene* scene = one_tree_scene();
    hmsm_simulation* simulation = NULL;
    size_t count = 0;

    memset(&config_box, GUARD, sizeof config_box);
    CHECK(hmsm_config_init((hmsm_config*)&config_box.config, sizeof config_box.config) == HMSM_OK);
    CHECK(guard_intact(config_box.guard));
    CHECK(config_box.config.struct_size == sizeof(older_config));
    CHECK(config_box.config.backend == HMSM_BACKEND_AUTOMATIC && config_box.config.model.ring_sides == 8);
    config_box.config.backend = HMSM_BACKEND_CPU;
    CHECK(hmsm_simulation_create(scene, (const hmsm_config*)&config_box.config, &simulation) == HMSM_OK);
    if (!simulation) return;

    /* The wind the older config could not carry is hmsm's default (Y1 along +x); reading it
     * into an older wind writes that layout only. */
    memset(&wind_box, GUARD, sizeof wind_box);
    CHECK(hmsm_wind_init((hmsm_wind*)&wind_box.wind, sizeof wind_box.wind) == HMSM_OK);
    CHECK(guard_intact(wind_box.guard));
    wind_box.wind.profile = HMSM_WIND_NONE;
    CHECK(hmsm_simulation_get_wind(simulation, (hmsm_wind*)&wind_box.wind) == HMSM_OK);
    CHECK(guard_intact(wind_box.guard));
    CHECK(wind_box.wind.profile == HMSM_WIND_Y1 && wind_box.wind.direction[0] == 1.0);
    wind_box.wind.profile = HMSM_WIND_CONSTANT;
    wind_box.wind.strength = 3.0;
    CHECK(hmsm_simulation_set_wind(simulation, (const hmsm_wind*)&wind_box.wind) == HMSM_OK);
    CHECK(hmsm_simulation_get_wind(simulation, (hmsm_wind*)&wind_box.wind) == HMSM_OK);
    CHECK(wind_box.wind.profile == HMSM_WIND_CONSTANT && wind_box.wind.strength == 3.0);

    /* An array of older instances: the stride is their size; `active` defaults to 1. */
    memset(&instance_box, GUARD, sizeof instance_box);
    CHECK(hmsm_instance_init((hmsm_instance*)&instance_box.items[0], sizeof(older_instance)) == HMSM_OK);
    CHECK(hmsm_instance_init((hmsm_instance*)&instance_box.items[1], sizeof(older_instance)) == HMSM_OK);
    CHECK(guard_intact(instance_box.guard));
    instance_box.items[0].origin[0] = 4.0;
    instance_box.items[1].origin[2] = -6.0;
    CHECK(hmsm_simulation_add_instances(simulation, (const hmsm_instance*)instance_box.items, 2) == HMSM_OK);
    CHECK(hmsm_simulation_instances(simulation, (hmsm_instance*)instance_box.items, 2, &count) ==
          HMSM_INVALID_ARGUMENT); /* three instances now: capacity 2 is too small */
    CHECK(count == 3 && guard_intact(instance_box.guard));
    {
        struct { older_instance items[3]; unsigned char guard[GUARD_BYTES]; } list;
        memset(&list, GUARD, sizeof list);
        list.items[0].struct_size = sizeof(older_instance);
        CHECK(hmsm_simulation_instances(simulation, (hmsm_instance*)list.items, 3, &count) == HMSM_OK);
        CHECK(guard_intact(list.guard));
        CHECK(list.items[1].origin[0] == 4.0 && list.items[2].origin[2] == -6.0);
        CHECK(list.items[2].struct_size == sizeof(older_instance) && list.items[2].wind_scale == 1.0);
    }

    memset(&field_box, GUARD, sizeof field_box);
    CHECK(hmsm_force_field_init((hmsm_force_field*)&field_box.field, sizeof field_box.field) == HMSM_OK);
    CHECK(guard_intact(field_box.guard));
    field_box.field.kind = HMSM_FORCE_FIELD_DIRECTIONAL;
    field_box.field.radius = 2.0;
    field_box.field.directional[0] = 1.0;
    CHECK(hmsm_simulation_set_force_fields(simulation, (const hmsm_force_field*)&field_box.field, 1) ==
          HMSM_OK);

    CHECK(hmsm_simulation_step(simulation, 5) == HMSM_OK);
    memset(&counts_box, GUARD, sizeof counts_box);
    CHECK(hmsm_counts_init((hmsm_counts*)&counts_box.counts, sizeof counts_box.counts) == HMSM_OK);
    CHECK(counts_box.counts.steps_done == 0 && guard_intact(counts_box.guard));
    CHECK(hmsm_simulation_counts(simulation, (hmsm_counts*)&counts_box.counts) == HMSM_OK);
    CHECK(guard_intact(counts_box.guard));
    CHECK(counts_box.counts.instances == 3 && counts_box.counts.steps_done == 5);
    hmsm_simulation_destroy(simulation);
    hmsm_scene_destroy(scene);
}

/* Zero, too small, too large, between two layouts, garbage: refused, nothing changed. */
static void test_refused_sizes(void) {
    const uint32_t bad_sizes[] = {0, 4, 7, 168, (uint32_t)sizeof(hmsm_config) + 8, 0xDEADBEEFu};
    hmsm_scene* scene = one_tree_scene();
    hmsm_simulation* simulation = NULL;
    hmsm_config config, before;
    hmsm_wind wind, wind_before;
    hmsm_counts counts, counts_before;
    hmsm_instance list[2], list_before[2];
    size_t i, count = 0;

    for (i = 0; i < sizeof bad_sizes / sizeof bad_sizes[0]; ++i) {
        memset(&config, GUARD, sizeof config);
        before = config;
        CHECK_REFUSED(hmsm_config_init(&config, bad_sizes[i]), "hmsm_config");
        CHECK(memcmp(&config, &before, sizeof config) == 0);
        CHECK(HMSM_INIT(hmsm_config_init, &config) == HMSM_OK);
        config.backend = HMSM_BACKEND_CPU;
        config.struct_size = bad_sizes[i];
        CHECK_REFUSED(hmsm_simulation_create(scene, &config, &simulation), "hmsm_config");
        CHECK(simulation == NULL);
    }
    CHECK(strstr(hmsm_status_message(), "3735928559") != NULL); /* the size it was given */

    CHECK(HMSM_INIT(hmsm_config_init, &config) == HMSM_OK);
    config.backend = HMSM_BACKEND_CPU;
    CHECK(hmsm_simulation_create(scene, &config, &simulation) == HMSM_OK);
    if (!simulation) return;

    memset(&wind, GUARD, sizeof wind);
    wind.struct_size = 0;
    wind_before = wind;
    CHECK_REFUSED(hmsm_simulation_get_wind(simulation, &wind), "hmsm_wind");
    CHECK(memcmp(&wind, &wind_before, sizeof wind) == 0);
    CHECK(HMSM_INIT(hmsm_wind_init, &wind) == HMSM_OK);
    wind.profile = HMSM_WIND_CONSTANT;
    wind.struct_size = 12;
    CHECK_REFUSED(hmsm_simulation_set_wind(simulation, &wind), "hmsm_wind");
    CHECK(HMSM_INIT(hmsm_wind_init, &wind) == HMSM_OK);
    CHECK(hmsm_simulation_get_wind(simulation, &wind) == HMSM_OK);
    CHECK(wind.profile == HMSM_WIND_Y1); /* the refused set_wind changed nothing */

    memset(&counts, GUARD, sizeof counts);
    counts.struct_size = 0xDEADBEEFu;
    counts_before = counts;
    CHECK_REFUSED(hmsm_simulation_counts(simulation, &counts), "hmsm_counts");
    CHECK(memcmp(&counts, &counts_before, sizeof counts) == 0);

    /* Arrays: a bad element 0 or an element whose size differs from element 0's. */
    memset(list, GUARD, sizeof list);
    list[0].struct_size = 0;
    memcpy(list_before, list, sizeof list);
    CHECK_REFUSED(hmsm_simulation_instances(simulation, list, 2, &count), "hmsm_instance");
    CHECK(memcmp(list, list_before, sizeof list) == 0);
    CHECK(HMSM_INIT(hmsm_instance_init, &list[0]) == HMSM_OK);
    CHECK(HMSM_INIT(hmsm_instance_init, &list[1]) == HMSM_OK);
    list[1].struct_size = sizeof(older_instance);
    CHECK(hmsm_simulation_add_instances(simulation, list, 2) == HMSM_INVALID_ARGUMENT);
    CHECK(strstr(hmsm_status_message(), "[1]") != NULL);
    CHECK(HMSM_INIT(hmsm_counts_init, &counts) == HMSM_OK);
    CHECK(hmsm_simulation_counts(simulation, &counts) == HMSM_OK);
    CHECK(counts.instances == 1); /* nothing was added */
    list[0].struct_size = 0;
    CHECK_REFUSED(hmsm_scene_add_instance(scene, &list[0]), "hmsm_instance");
    {
        hmsm_force_field field;
        CHECK(HMSM_INIT(hmsm_force_field_init, &field) == HMSM_OK);
        field.struct_size = 1;
        CHECK_REFUSED(hmsm_simulation_set_force_fields(simulation, &field, 1), "hmsm_force_field");
        CHECK_REFUSED(hmsm_counts_init(&counts, 3), "hmsm_counts");
    }
    hmsm_simulation_destroy(simulation);
    hmsm_scene_destroy(scene);
}

int main(void) {
    test_older_layouts();
    test_refused_sizes();
    if (failures) fprintf(stderr, "%d check(s) failed\n", failures);
    else printf("all checks passed\n");
    return failures ? 1 : 0;
}
