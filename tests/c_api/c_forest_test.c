/* The C ABI's forest loading: names sharing a preset share one model, unused models are not
   built, hmsm_scene_load_forest_with builds the models later additions need. */
#include "c_check.h"

#include <hmsm/hmsm_c.h>

#include <stdio.h>
#include <string.h>

static int write_file(const char* path, const char* text) {
    FILE* f = fopen(path, "w");
    if (!f) return 0;
    fputs(text, f);
    return fclose(f) == 0;
}

int main(void) {
    const char* forest = "hmsm_c_forest_test.json";
    const char* names[] = {"c"};
    const char* unknown[] = {"birch"};
    hmsm_scene* scene = NULL;
    uint32_t models = 0, a = 99, b = 99, c = 99;
    CHECK(write_file("hmsm_c_forest_test_broken.json", "not a tree"));
    CHECK(write_file(forest, "{\"format\": \"hmsm-forest\", \"version\": 1, \"models\": {\"a\": \"preset:paper-1\", "
                             "\"b\": \"preset:paper-1\", \"c\": \"preset:paper-2\", "
                             "\"u\": \"hmsm_c_forest_test_broken.json\"}, "
                             "\"instances\": [{\"model\": \"a\"}, {\"model\": \"b\", \"origin\": [9, 0, 0]}]}"));

    CHECK_STATUS(HMSM_OK, hmsm_scene_load_forest(forest, &scene));
    CHECK_STATUS(HMSM_OK, hmsm_scene_model_count(scene, &models));
    CHECK(models == 1);
    CHECK_STATUS(HMSM_OK, hmsm_scene_find_model(scene, "a", &a));
    CHECK_STATUS(HMSM_OK, hmsm_scene_find_model(scene, "b", &b));
    CHECK(a == 0 && b == 0);
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_scene_find_model(scene, "c", &c));
    CHECK(strstr(hmsm_status_message(), "'c'") != NULL);
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_scene_find_model(scene, NULL, &c));
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_scene_find_model(scene, "a", NULL));
    hmsm_scene_destroy(scene);
    scene = NULL;

    CHECK_STATUS(HMSM_OK, hmsm_scene_load_forest_with(forest, names, 1, &scene));
    CHECK_STATUS(HMSM_OK, hmsm_scene_model_count(scene, &models));
    CHECK(models == 2);
    CHECK_STATUS(HMSM_OK, hmsm_scene_find_model(scene, "c", &c));
    CHECK(c == 1);
    hmsm_scene_destroy(scene);
    scene = NULL;

    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_scene_load_forest_with(forest, unknown, 1, &scene));
    CHECK(strstr(hmsm_status_message(), "birch") != NULL);
    CHECK(scene == NULL);
    CHECK_STATUS(HMSM_INVALID_ARGUMENT, hmsm_scene_load_forest_with(forest, NULL, 1, &scene));
    CHECK_STATUS(HMSM_OK, hmsm_scene_load_forest_with(forest, NULL, 0, &scene));
    hmsm_scene_destroy(scene);
    remove(forest);
    remove("hmsm_c_forest_test_broken.json");
    if (failures) fprintf(stderr, "%d check(s) failed\n", failures);
    return failures ? 1 : 0;
}
