/* The C ABI's stable instance handles and reserve_instances: ids survive removals of other
   instances and are never reused; a removed, unknown or repeated id is refused, naming it, and
   changes nothing. */
#include "c_check.h"

#include <hmsm/hmsm_c.h>

#include <string.h>

static hmsm_simulation* simulation_of_three(void) {
    hmsm_tree* tree = small_tree();
    hmsm_scene* scene = NULL;
    hmsm_instance instance;
    hmsm_config config;
    hmsm_simulation* simulation = NULL;
    int i;
    CHECK_STATUS(HMSM_OK, hmsm_scene_create(&scene));
    CHECK_STATUS(HMSM_OK, hmsm_scene_add_model(scene, tree, "small", NULL));
    HMSM_INIT(hmsm_instance_init, &instance);
    for (i = 0; i < 3; ++i) {
        instance.origin[0] = 8.0 * i;
        CHECK_STATUS(HMSM_OK, hmsm_scene_add_instance(scene, &instance));
    }
    HMSM_INIT(hmsm_config_init, &config);
    config.backend = HMSM_BACKEND_CPU;
    CHECK_STATUS(HMSM_OK, hmsm_simulation_create(scene, &config, &simulation));
    hmsm_scene_destroy(scene);
    hmsm_tree_destroy(tree);
    return simulation;
}

static uint64_t instance_count(const hmsm_simulation* simulation) {
    size_t count = 0;
    CHECK_STATUS(HMSM_OK, hmsm_simulation_instances(simulation, NULL, 0, &count));
    return count;
}

int main(void) {
    hmsm_simulation* simulation = simulation_of_three();
    hmsm_instance added[2];
    hmsm_instance_id given[2] = {0, 0}, id = 0;
    const hmsm_instance_id first[] = {0}, removed_and_live[] = {2, 0}, unknown[] = {77}, twice[] = {1, 1};
    const hmsm_instance_id swap_first[] = {1};
    uint64_t index = 0;

    CHECK_STATUS(HMSM_OK, hmsm_simulation_reserve_instances(simulation, 16));
    CHECK_STATUS(HMSM_UNSUPPORTED, hmsm_simulation_reserve_instances(simulation, 1ull << 40));
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_reserve_instances(NULL, 4));
    {
        /* The scene has no levels of detail: one level count (level 0), no more. */
        const uint64_t per_level[] = {20, 5};
        CHECK_STATUS(HMSM_OK, hmsm_simulation_reserve_level_instances(simulation, per_level, 1));
        CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_reserve_level_instances(simulation, per_level, 2));
        CHECK(strstr(hmsm_status_message(), "at most 1 levels") != NULL);
        CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_reserve_level_instances(simulation, per_level, 0));
        CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_reserve_level_instances(simulation, NULL, 1));
        CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_reserve_level_instances(NULL, per_level, 1));
    }

    CHECK_STATUS(HMSM_OK, hmsm_simulation_id_of(simulation, 2, &id));
    CHECK(id == 2);
    CHECK_STATUS(HMSM_OK, hmsm_simulation_remove_instances_by_id(simulation, first, 1));
    CHECK_STATUS(HMSM_OK, hmsm_simulation_index_of(simulation, 2, &index));
    CHECK(index == 1);
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_index_of(simulation, 0, &index));
    CHECK(strstr(hmsm_status_message(), "instance id 0 was removed") != NULL);

    HMSM_INIT(hmsm_instance_init, &added[0]);
    HMSM_INIT(hmsm_instance_init, &added[1]);
    added[1].origin[2] = 5.0;
    CHECK_STATUS(HMSM_OK, hmsm_simulation_add_instances_with_ids(simulation, added, 2, given));
    CHECK(given[0] == 3 && given[1] == 4);
    CHECK_STATUS(HMSM_OK, hmsm_simulation_index_of(simulation, 4, &index));
    CHECK(index == 3);
    CHECK_STATUS(HMSM_OK, hmsm_simulation_step(simulation, 4));

    /* Refused, naming the id; nothing changes. */
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_remove_instances_by_id(simulation, removed_and_live, 2));
    CHECK(strstr(hmsm_status_message(), "instance id 0") != NULL);
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_remove_instances_by_id(simulation, unknown, 1));
    CHECK(strstr(hmsm_status_message(), "instance id 77") != NULL);
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_remove_instances_by_id(simulation, twice, 2));
    CHECK(strstr(hmsm_status_message(), "instance id 1 is listed twice") != NULL);
    CHECK(instance_count(simulation) == 4);
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_id_of(simulation, 4, &id));
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_add_instances_with_ids(simulation, added, 2, NULL));
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_remove_instances_by_id(simulation, NULL, 1));
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_index_of(simulation, 1, NULL));
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_id_of(NULL, 0, &id));
    CHECK(instance_count(simulation) == 4);

    /* A removed id is not given again. */
    CHECK_STATUS(HMSM_OK, hmsm_simulation_remove_instances_by_id(simulation, given + 1, 1));
    CHECK_STATUS(HMSM_OK, hmsm_simulation_add_instances_with_ids(simulation, added, 1, given));
    CHECK(given[0] == 5);
    CHECK(instance_count(simulation) == 4);

    /* Swap removal: the last instance (id 5) fills the hole of id 1 at index 0. */
    CHECK_STATUS(HMSM_OK, hmsm_simulation_swap_remove_instances(simulation, swap_first, 1));
    CHECK_STATUS(HMSM_OK, hmsm_simulation_index_of(simulation, 5, &index));
    CHECK(index == 0);
    CHECK_STATUS(HMSM_OK, hmsm_simulation_id_of(simulation, 1, &id));
    CHECK(id == 2);
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_swap_remove_instances(simulation, swap_first, 1));
    CHECK(strstr(hmsm_status_message(), "instance id 1 was removed") != NULL);
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_swap_remove_instances(simulation, unknown, 1));
    CHECK(strstr(hmsm_status_message(), "instance id 77") != NULL);
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_swap_remove_instances(simulation, NULL, 1));
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_swap_remove_instances(NULL, swap_first, 1));
    CHECK(instance_count(simulation) == 3);
    CHECK_STATUS(HMSM_OK, hmsm_simulation_step(simulation, 2));

    /* Placements: on the CPU the layout is packed, so instance 1 (id 2) begins where instance 0
       (id 5) ends, one tree's chains on. */
    {
        hmsm_instance_placement at_0, at_1, unset;
        hmsm_counts counts;
        CHECK(HMSM_INIT(hmsm_instance_placement_init, &at_0) == HMSM_OK);
        CHECK(HMSM_INIT(hmsm_instance_placement_init, &at_1) == HMSM_OK);
        CHECK(HMSM_INIT(hmsm_counts_init, &counts) == HMSM_OK);
        CHECK_STATUS(HMSM_OK, hmsm_simulation_counts(simulation, &counts));
        CHECK_STATUS(HMSM_OK, hmsm_simulation_instance_placement(simulation, 5, &at_0));
        CHECK_STATUS(HMSM_OK, hmsm_simulation_instance_placement(simulation, 2, &at_1));
        CHECK(at_0.first_chain == 0 && at_0.first_node == 0 && at_0.first_vertex == 0);
        CHECK(at_1.first_chain == counts.chains / 3 && at_1.first_vertex == counts.vertices / 3);
        CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_instance_placement(simulation, 1, &at_0));
        CHECK(strstr(hmsm_status_message(), "hmsm_simulation_instance_placement: instance id 1 was removed") != NULL);
        CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_instance_placement(simulation, 2, NULL));
        CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_instance_placement(NULL, 2, &at_0));
        memset(&unset, 0, sizeof unset);
        CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_simulation_instance_placement(simulation, 2, &unset));
        CHECK(strstr(hmsm_status_message(), "hmsm_instance_placement") != NULL);
    }
    hmsm_simulation_destroy(simulation);
    if (failures) fprintf(stderr, "%d check(s) failed\n", failures);
    return failures ? 1 : 0;
}
