/* The C ABI of a tree's wood and leaf state: species presets by index, a material by species
   or by value, the leaf state; bad values are refused naming them and change nothing, and what
   is set reaches a coupled simulation of the tree. */
#include "c_check.h"

#include <hmsm/hmsm_c.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

enum { kCapacity = 4 * 1000 }; /* paper-5 under coupled: 409 chains with the trunk links */

static void test_species_list(void) {
    uint64_t count = 0;
    const char* name = NULL;
    CHECK_OK(hmsm_species_count(&count));
    CHECK(count > 0);
    CHECK_OK(hmsm_species_name(0, &name));
    CHECK(name != NULL && strlen(name) > 0);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_species_name(count, &name));
    CHECK(strstr(hmsm_status_message(), "index") != NULL);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_species_name(0, NULL));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_species_count(NULL));
}

static void test_material_and_leaves(void) {
    hmsm_tree* tree = small_tree();
    int32_t has = -1, state = -1;
    double modulus = -1.0, density = -1.0;
    CHECK_OK(hmsm_tree_material(tree, &has, &modulus, &density));
    CHECK(has == 0 && modulus == 0.0 && density == 0.0);
    /* Unknown species and out-of-range values: refused, naming them, nothing set. */
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_set_species(tree, "mahogany-of-atlantis"));
    CHECK(strstr(hmsm_status_message(), "mahogany-of-atlantis") != NULL);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_set_material(tree, -9e9, 800.0));
    CHECK(strstr(hmsm_status_message(), "modulus") != NULL);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_set_material(tree, 9e9, NAN));
    CHECK(strstr(hmsm_status_message(), "density") != NULL);
    CHECK_OK(hmsm_tree_material(tree, &has, &modulus, &density));
    CHECK(has == 0);
    /* A species, then a value, then none. */
    CHECK_OK(hmsm_tree_set_species(tree, "sugar-maple"));
    CHECK_OK(hmsm_tree_material(tree, &has, &modulus, &density));
    CHECK(has == 1 && modulus > 1e9 && density > 100.0);
    CHECK_OK(hmsm_tree_set_material(tree, 7e9, 650.0));
    CHECK_OK(hmsm_tree_material(tree, &has, &modulus, &density));
    CHECK(has == 1 && modulus == 7e9 && density == 650.0);
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_set_species(tree, NULL));
    CHECK_OK(hmsm_tree_material(tree, &has, &modulus, &density));
    CHECK(modulus == 7e9);
    CHECK_OK(hmsm_tree_clear_material(tree));
    CHECK_OK(hmsm_tree_material(tree, &has, &modulus, &density));
    CHECK(has == 0);
    /* Leaf state. */
    CHECK_OK(hmsm_tree_leaf_state(tree, &state));
    CHECK(state == HMSM_LEAF_STATE_FROM_PARAMETERS);
    CHECK_OK(hmsm_tree_set_leaf_state(tree, HMSM_LEAF_STATE_OFF));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_set_leaf_state(tree, 3));
    CHECK(strstr(hmsm_status_message(), "state 3") != NULL);
    CHECK_OK(hmsm_tree_leaf_state(tree, &state));
    CHECK(state == HMSM_LEAF_STATE_OFF);
    CHECK_OK(hmsm_tree_set_leaf_state(tree, HMSM_LEAF_STATE_ON));
    CHECK_OK(hmsm_tree_leaf_state(tree, &state));
    CHECK(state == HMSM_LEAF_STATE_ON);
    /* NULL handles and outputs. */
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_set_species(NULL, "sugar-maple"));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_set_material(NULL, 9e9, 800.0));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_clear_material(NULL));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_material(tree, NULL, &modulus, &density));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_set_leaf_state(NULL, HMSM_LEAF_STATE_ON));
    CHECK_FAILS(HMSM_INVALID_ARGUMENT, hmsm_tree_leaf_state(tree, NULL));
    hmsm_tree_destroy(tree);
}

/* Chain angles of paper-5 under the coupled dynamics after 30 steps of wind, with the tree's
   material and leaf state set as given (material_modulus 0: none). */
static size_t coupled_angles(double material_modulus, int32_t leaf_state, float* angles) {
    hmsm_tree* tree = NULL;
    hmsm_scene* scene = NULL;
    hmsm_instance instance;
    hmsm_config config;
    hmsm_simulation* simulation = NULL;
    size_t count = 0;
    CHECK_OK(hmsm_tree_preset("paper-5", 0, &tree));
    if (material_modulus > 0.0) CHECK_OK(hmsm_tree_set_material(tree, material_modulus, 800.0));
    CHECK_OK(hmsm_tree_set_leaf_state(tree, leaf_state));
    CHECK_OK(hmsm_scene_create(&scene));
    CHECK_OK(hmsm_scene_add_model(scene, tree, "tree", NULL));
    hmsm_tree_destroy(tree); /* the scene holds its own copy */
    HMSM_INIT(hmsm_instance_init, &instance);
    CHECK_OK(hmsm_scene_add_instance(scene, &instance));
    HMSM_INIT(hmsm_config_init, &config);
    config.backend = HMSM_BACKEND_CPU;
    config.dynamics = HMSM_DYNAMICS_COUPLED;
    config.wind.profile = HMSM_WIND_CONSTANT;
    config.wind.strength = 4.0;
    CHECK_OK(hmsm_simulation_create(scene, &config, &simulation));
    hmsm_scene_destroy(scene);
    if (!simulation) return 0;
    CHECK_OK(hmsm_simulation_step(simulation, 30));
    CHECK_OK(hmsm_simulation_read_f32(simulation, HMSM_OUTPUT_CHAIN_ANGLES, angles, kCapacity, &count));
    hmsm_simulation_destroy(simulation);
    return count;
}

static int same(const float* a, const float* b, size_t count) { return memcmp(a, b, count * sizeof(float)) == 0; }

static void test_reaches_the_simulation(void) {
    static float by_parameters[kCapacity], stiff[kCapacity], again[kCapacity], leaf_off[kCapacity],
        leaf_on[kCapacity];
    const size_t count = coupled_angles(0.0, HMSM_LEAF_STATE_FROM_PARAMETERS, by_parameters);
    CHECK(count > 0 && count <= kCapacity);
    CHECK(coupled_angles(0.0, HMSM_LEAF_STATE_FROM_PARAMETERS, again) == count);
    CHECK(same(by_parameters, again, count)); /* deterministic, so differences below are the inputs' */
    coupled_angles(2e10, HMSM_LEAF_STATE_FROM_PARAMETERS, stiff);
    CHECK(!same(by_parameters, stiff, count));
    coupled_angles(0.0, HMSM_LEAF_STATE_OFF, leaf_off);
    coupled_angles(0.0, HMSM_LEAF_STATE_ON, leaf_on);
    CHECK(!same(leaf_off, leaf_on, count));
}

int main(void) {
    test_species_list();
    test_material_and_leaves();
    test_reaches_the_simulation();
    if (failures) fprintf(stderr, "%d check(s) failed\n", failures);
    return failures ? 1 : 0;
}
