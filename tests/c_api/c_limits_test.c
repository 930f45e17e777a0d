/* The C ABI's input limits (docs/model.md 3.11) and hmsm_simulation_reset_instances: values
   beyond float range are refused where they enter and change nothing; a reset instance returns
   exactly to the rest state of a fresh one, the others untouched. */
#include "c_check.h"

#include <hmsm/hmsm_c.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

enum { kCapacity = 64, kInstances = 2 };
static size_t angles_per_instance = 0; /* 4 per chain */

static hmsm_simulation* simulation_of_two(void) {
    hmsm_tree* tree = small_tree();
    hmsm_scene* scene = NULL;
    hmsm_instance instance;
    hmsm_config config;
    hmsm_simulation* simulation = NULL;
    CHECK_STATUS(HMSM_OK, hmsm_scene_create(&scene));
    CHECK_STATUS(HMSM_OK, hmsm_scene_add_model(scene, tree, "small", NULL));
    HMSM_INIT(hmsm_instance_init, &instance);
    CHECK_STATUS(HMSM_OK, hmsm_scene_add_instance(scene, &instance));
    instance.origin[0] = 10.0;
    CHECK_STATUS(HMSM_OK, hmsm_scene_add_instance(scene, &instance));
    HMSM_INIT(hmsm_config_init, &config);
    config.backend = HMSM_BACKEND_CPU;
    config.wind.profile = HMSM_WIND_CONSTANT;
    config.wind.strength = 40.0;
    CHECK_STATUS(HMSM_OK, hmsm_simulation_create(scene, &config, &simulation));
    hmsm_scene_destroy(scene);
    hmsm_tree_destroy(tree);
    return simulation;
}

static void read_angles(hmsm_simulation* simulation, float* angles) {
    size_t count = 0;
    CHECK_STATUS(HMSM_OK, hmsm_simulation_read_f32(simulation, HMSM_OUTPUT_CHAIN_ANGLES, angles, kCapacity, &count));
    CHECK(count > 0 && count % (4 * kInstances) == 0);
    angles_per_instance = count / kInstances;
}

static void test_values_beyond_float_range(hmsm_simulation* simulation) {
    hmsm_force_field field;
    hmsm_wind wind;
    HMSM_INIT(hmsm_force_field_init, &field);
    field.kind = HMSM_FORCE_FIELD_RADIAL;
    field.radius = 5.0;
    field.radial = 1e39; /* finite in double, inf in float */
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_force_fields(simulation, &field, 1));
    CHECK(strstr(hmsm_status_message(), "radial") != NULL && strstr(hmsm_status_message(), "1e+30") != NULL);
    field.radial = 1.0;
    field.center[0] = 1e308;
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_force_fields(simulation, &field, 1));
    CHECK(strstr(hmsm_status_message(), "center") != NULL);
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_instance_wind_scale(simulation, 0, 1e28));
    CHECK(strstr(hmsm_status_message(), "wind_scale") != NULL);
    CHECK_STATUS(HMSM_OK, HMSM_INIT(hmsm_wind_init, &wind));
    CHECK_STATUS(HMSM_OK, hmsm_simulation_get_wind(simulation, &wind));
    wind.frequency = 1e308;
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_set_wind(simulation, &wind));
    CHECK(strstr(hmsm_status_message(), "wind frequency") != NULL);
}

static void test_reset(hmsm_simulation* simulation) {
    float rest[kCapacity], moved[kCapacity], after[kCapacity];
    const uint32_t first = 0, bad[2] = {1, 2}, twice[2] = {1, 1};
    size_t k;
    int changed = 0;
    read_angles(simulation, rest);
    CHECK_STATUS(HMSM_OK, hmsm_simulation_step(simulation, 60));
    read_angles(simulation, moved);
    for (k = 0; k < kInstances * angles_per_instance; ++k) changed |= moved[k] != rest[k];
    CHECK(changed);
    /* Refused and nothing changes. */
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_reset_instances(simulation, bad, 2));
    CHECK(strstr(hmsm_status_message(), "instance 2") != NULL);
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_reset_instances(simulation, twice, 2));
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_reset_instances(simulation, NULL, 1));
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_reset_instances(NULL, &first, 1));
    read_angles(simulation, after);
    CHECK(memcmp(after, moved, kInstances * angles_per_instance * sizeof(float)) == 0);
    /* Instance 0 back at rest, instance 1 as it was. */
    CHECK_STATUS(HMSM_OK, hmsm_simulation_reset_instances(simulation, &first, 1));
    read_angles(simulation, after);
    CHECK(memcmp(after, rest, angles_per_instance * sizeof(float)) == 0);
    CHECK(memcmp(after + angles_per_instance, moved + angles_per_instance, angles_per_instance * sizeof(float)) == 0);
}

int main(void) {
    hmsm_simulation* simulation = simulation_of_two();
    if (simulation) {
        test_values_beyond_float_range(simulation);
        test_reset(simulation);
        hmsm_simulation_destroy(simulation);
    }
    if (failures) fprintf(stderr, "%d check(s) failed\n", failures);
    return failures ? 1 : 0;
}
