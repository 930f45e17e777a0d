/* The C ABI of hmsm (C99): for engines and languages that cannot use the C++ API (C#, Rust,
 * Python through ctypes, Godot, ...). docs/engine.md describes it with examples.
 *
 * Conventions:
 * - Objects are opaque handles created by hmsm_*_create/load/... and released by the matching
 *   hmsm_*_destroy (which accepts NULL). A simulation keeps its own copy of the scene, so trees
 *   and scenes may be destroyed once a simulation has been created from them.
 * - Every fallible function returns an hmsm_status: 0 (HMSM_OK) or one of the codes below, which
 *   are those of hmsm::ErrorCode. hmsm_status_message() returns the message of the last call
 *   made on the calling thread ("" after a success): it names the offending argument or item.
 *   A failed call changes nothing and writes no output (but the size, see below).
 * - Nothing crosses this boundary as an exception; nothing exits or aborts.
 * - Outputs are written to caller-owned arrays with an explicit capacity (in elements). Passing
 *   values = NULL and capacity = 0 only queries the size; a capacity that is too small fails
 *   with HMSM_INVALID_ARGUMENT. In both cases *count receives the number of elements needed.
 * - Enumerations are int32_t values; an unknown value fails with HMSM_INVALID_ARGUMENT. Booleans
 *   are int32_t, 0 or 1.
 * - Threading: as in C++ (include/hmsm/simulation.h): one thread at a time per simulation;
 *   functions taking a const handle may run concurrently with each other; distinct handles
 *   concurrently. The last-status message is per thread.
 * - Sized structs: every struct that crosses this boundary (hmsm_config, hmsm_wind,
 *   hmsm_instance, hmsm_force_field, hmsm_counts, hmsm_level_options,
 *   hmsm_instance_placement) begins with `uint32_t struct_size`, the size
 *   of the caller's definition of it. Fill a struct with its hmsm_*_init function and the
 *   caller's size, HMSM_INIT(hmsm_config_init, &config), which sets struct_size and hmsm's
 *   defaults; then change what you need. Every call that reads or fills a struct checks
 *   struct_size first. Fields are only ever appended, so every earlier layout of a struct is a
 *   prefix of the current one: a struct_size equal to the size of such a prefix (a struct from
 *   an older header) is served with only its fields read or written, the later ones taking
 *   hmsm's defaults. A struct_size of 0, smaller than the first field, larger than this
 *   library's struct (a newer header) or between two layouts fails with HMSM_INVALID_ARGUMENT,
 *   a message naming the struct and the sizes, and writes nothing. In an array, element 0's
 *   struct_size is the stride and every element must carry it (for an array that hmsm fills,
 *   initialise at least element 0). hmsm_model_options, hmsm_parameters and the hmsm_wind
 *   inside hmsm_config are parts of hmsm_config and covered by its size; the nested wind's own
 *   struct_size is set by hmsm_config_init and not read.
 */
#ifndef HMSM_HMSM_C_H
#define HMSM_HMSM_C_H

#include <hmsm/export.h>

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Bumped whenever a struct or a signature below changes incompatibly. */
#define HMSM_C_ABI_VERSION 2

/* Fills *object (a pointer to a sized struct) with hmsm's defaults for the caller's layout:
 * HMSM_INIT(hmsm_config_init, &config) is hmsm_config_init(&config, sizeof config). */
#define HMSM_INIT(init_function, object) init_function((object), sizeof *(object))

typedef int32_t hmsm_status;
enum {
    HMSM_OK = 0,
    HMSM_INVALID_ARGUMENT = 1, /* an argument out of its valid range (caller's fault) */
    HMSM_INVALID_TREE = 2,     /* a tree or forest violating docs/model.md 3.1 or 4 */
    HMSM_IO = 3,               /* a file could not be read */
    HMSM_NO_DEVICE = 4,        /* the requested backend has no usable device here */
    HMSM_DEVICE_ERROR = 5,     /* a device call failed */
    HMSM_OUT_OF_MEMORY = 6,
    HMSM_UNSUPPORTED = 7,      /* a limit of this build or device was exceeded */
    HMSM_INTERNAL = 8          /* a bug in hmsm */
};

enum { /* hmsm_config.backend */
    HMSM_BACKEND_CPU = 0,
    HMSM_BACKEND_CPU64 = 1,
    HMSM_BACKEND_VULKAN = 2,
    HMSM_BACKEND_CUDA = 3,
    HMSM_BACKEND_AUTOMATIC = 4,
    HMSM_BACKEND_CPU_PARALLEL = 5  /* the float passes over every host thread */
};
enum { /* hmsm_config.composition */
    HMSM_COMPOSITION_POINTER_JUMPING = 0, /* its dispatch form (rounds in one dispatch or one per round) by size */
    /* values 1, 2 and 4 are reserved: hmsm_simulation_create refuses them */
    HMSM_COMPOSITION_LEVEL_BY_LEVEL = 3,
    HMSM_COMPOSITION_PATH_WALK = 5, /* each chain walks its ancestors: 4 dispatches per step */
    HMSM_COMPOSITION_AUTOMATIC = 6  /* the default: path walk on a GPU, else pointer jumping */
};
enum { HMSM_VERTEX_LAYOUT_SEPARATE = 0, HMSM_VERTEX_LAYOUT_PACKED = 1 };
/* hmsm_config.instance_layout (hmsm::InstanceLayout) */
enum { HMSM_INSTANCE_LAYOUT_PACKED = 0, HMSM_INSTANCE_LAYOUT_PLACED = 1 };
enum { HMSM_GROUPING_DIRECTION = 0, HMSM_GROUPING_WIDTH = 1 };
/* hmsm_config.dynamics (hmsm::Dynamics, docs/model.md 3.7 and 3.13) */
enum { HMSM_DYNAMICS_PAPER = 0, HMSM_DYNAMICS_COUPLED = 1 };
/* hmsm_config.exchange (hmsm::Exchange, docs/model.md 3.13): HMSM_DYNAMICS_COUPLED only */
enum { HMSM_EXCHANGE_HELD = 0, HMSM_EXCHANGE_ARTICULATED = 1 };
enum { /* hmsm_wind.profile (docs/model.md 3.5) */
    HMSM_WIND_NONE = 0,
    HMSM_WIND_CONSTANT = 1,
    HMSM_WIND_Y1 = 2,
    HMSM_WIND_Y2 = 3,
    HMSM_WIND_Y3 = 4,
    HMSM_WIND_Y4 = 5,
    HMSM_WIND_TURBULENT = 6,
    HMSM_WIND_ATMOSPHERIC = 7
};
/* What hmsm_simulation_read_* returns, components per element in brackets (as hmsm::Output):
 * node positions [3], vertex positions [3], vertex normals [3], chain rotations [9,
 * column-major], chain origins [3], chain angles [4: theta_x, theta_z and their rates], joint
 * matrices [12: [R | O] row by row, r00 r01 r02 ox r10 ... oz].
 * Instance-major. HMSM_OUTPUT_COUNT is one past the last value. */
enum {
    HMSM_OUTPUT_NODE_POSITIONS = 0,
    HMSM_OUTPUT_VERTEX_POSITIONS = 1,
    HMSM_OUTPUT_VERTEX_NORMALS = 2,
    HMSM_OUTPUT_CHAIN_ROTATIONS = 3,
    HMSM_OUTPUT_CHAIN_ORIGINS = 4,
    HMSM_OUTPUT_CHAIN_ANGLES = 5,
    HMSM_OUTPUT_JOINT_MATRICES = 6,
    HMSM_OUTPUT_COUNT = 7
};
enum { HMSM_FORCE_FIELD_DIRECTIONAL = 0, HMSM_FORCE_FIELD_RADIAL = 1 };
/* hmsm::Outputs: joints only (passes 1-5), plus node positions (6), plus mesh vertices (7). */
enum { HMSM_OUTPUTS_JOINTS = 0, HMSM_OUTPUTS_JOINTS_AND_NODES = 1, HMSM_OUTPUTS_ALL = 2 };

typedef struct hmsm_tree hmsm_tree;             /* a validated tree model */
typedef struct hmsm_scene hmsm_scene;           /* models and their instances */
typedef struct hmsm_simulation hmsm_simulation; /* a running simulation */

/* hmsm::ModelOptions */
typedef struct hmsm_model_options {
    int32_t grouping;
    int32_t max_chain_segments;
    int32_t ring_sides;
    double fix_weight;
} hmsm_model_options;

/* hmsm::Parameters (docs/model.md 3.4) */
typedef struct hmsm_parameters {
    double density;
    double stiffness;
    double damping_ratio;
    double wind_gain;
    double max_angle;
    double dt;
    double max_frequency;
} hmsm_parameters;

/* The coupled dynamics' wood, leaves and damping: hmsm::Material, hmsm::Foliage and
 * hmsm::Parameters' structural_damping and wood_drag_coefficient (docs/model.md 3.13). */
typedef struct hmsm_coupled_parameters {
    double modulus;               /* E (Pa) */
    double wood_density;          /* green density (kg/m^3) */
    double structural_damping;    /* zeta_s */
    double wood_drag_coefficient; /* C_d of branches */
    double leaf_mass_per_area;    /* kg per m^2 of leaf card */
    double leaf_drag_coefficient; /* drag area per m^2 of leaf card */
    int32_t leaves_on;            /* 1: leaf-on, 0: leaf-off */
} hmsm_coupled_parameters;

/* hmsm::Wind (docs/model.md 3.5) */
typedef struct hmsm_wind {
    uint32_t struct_size;
    int32_t profile;
    double direction[3];
    double strength;
    double frequency;
    double front_speed;
    double turbulence;
    uint64_t seed;
} hmsm_wind;

/* hmsm::SimulationConfig */
typedef struct hmsm_config {
    uint32_t struct_size;
    int32_t backend;
    int32_t composition;
    int32_t vertex_layout;
    int32_t profile_passes;
    int32_t outputs; /* HMSM_OUTPUTS_*: what a step produces */
    hmsm_model_options model;
    hmsm_parameters parameters;
    hmsm_wind wind;
    int32_t dynamics;                /* HMSM_DYNAMICS_*: the equations of motion */
    hmsm_coupled_parameters coupled; /* used by HMSM_DYNAMICS_COUPLED, validated always */
    /* Appended: HMSM_INSTANCE_LAYOUT_*, where the instances' elements lie in the device
     * buffers (hmsm::InstanceLayout; hmsm_simulation_instance_placement). */
    int32_t instance_layout;
    /* Appended: HMSM_EXCHANGE_*, how the coupled dynamics' chains exchange loads
     * (hmsm::ModelOptions::exchange; every backend runs both). 64 bits, so that
     * the struct grows past the layout that ends with instance_layout. */
    int64_t exchange;
} hmsm_config;

/* hmsm::Instance: a placed copy of model `model` (docs/model.md 3.6, 3.9) */
typedef struct hmsm_instance {
    uint32_t struct_size;
    uint32_t model;
    double origin[3];
    double yaw;
    double wind_scale;
    double wind_phase;
    int32_t active;
    /* Appended: the level of detail (hmsm::Instance::level) it starts on (add, create) or runs
     * on (hmsm_simulation_instances); 0 (the default) is the model as created. */
    uint64_t level;
} hmsm_instance;

/* hmsm::ForceField (docs/model.md 3.9) */
typedef struct hmsm_force_field {
    uint32_t struct_size;
    int32_t kind;
    double center[3];
    double radius;
    double directional[3];
    double radial;
} hmsm_force_field;

/* Sizes of a simulation, over all instances. */
typedef struct hmsm_counts {
    uint32_t struct_size;
    uint64_t instances;
    uint64_t chains;
    uint64_t nodes;
    uint64_t vertices;
    uint64_t steps_done;
    double time; /* simulated seconds */
} hmsm_counts;

/* --- status and defaults ------------------------------------------------------------------ */
HMSM_API uint32_t hmsm_abi_version(void);
/* The message of the calling thread's last call; valid until its next call. Never NULL. */
HMSM_API const char* hmsm_status_message(void);
/* "ok", "invalid_argument", ...; "unknown" for other values. */
HMSM_API const char* hmsm_status_name(hmsm_status status);
/* Each sets struct_size = `struct_size` (the caller's sizeof) and hmsm's defaults in the
 * fields of that layout; a NULL pointer or an unknown size fails and writes nothing. */
HMSM_API hmsm_status hmsm_config_init(hmsm_config* config, size_t struct_size);
HMSM_API hmsm_status hmsm_wind_init(hmsm_wind* wind, size_t struct_size);
HMSM_API hmsm_status hmsm_instance_init(hmsm_instance* instance, size_t struct_size);
HMSM_API hmsm_status hmsm_force_field_init(hmsm_force_field* field, size_t struct_size);
HMSM_API hmsm_status hmsm_counts_init(hmsm_counts* counts, size_t struct_size); /* zeros */
HMSM_API hmsm_status hmsm_output_components(int32_t output, uint32_t* components);

/* --- trees -------------------------------------------------------------------------------- */
HMSM_API hmsm_status hmsm_tree_load(const char* path, hmsm_tree** tree);
/* hmsm-tree JSON v1 text of `length` bytes. */
HMSM_API hmsm_status hmsm_tree_parse(const char* json, size_t length, hmsm_tree** tree);
/* A preset (paper-1 ... paper-5); seed 0 = the preset's own. */
HMSM_API hmsm_status hmsm_tree_preset(const char* name, uint64_t seed, hmsm_tree** tree);
/* From arrays of `count` nodes: parent index (-1 for the root), position (x, y, z) and radius. */
HMSM_API hmsm_status hmsm_tree_from_nodes(const int32_t* parents, const double* positions,
                                          const double* radii, size_t count, hmsm_tree** tree);
HMSM_API hmsm_status hmsm_tree_node_count(const hmsm_tree* tree, uint64_t* count);
HMSM_API void hmsm_tree_destroy(hmsm_tree* tree);

/* --- a tree's wood and leaves under the coupled dynamics (docs/model.md 3.13, 4.1) ---------- */
/* Without them the simulation's hmsm_parameters (material, leaves_on) decide. They change the
 * tree only: a model added to a scene afterwards carries them (hmsm_scene_add_model copies). */
enum { /* hmsm_tree leaf state (hmsm::TreeModel::leaves_on) */
    HMSM_LEAF_STATE_FROM_PARAMETERS = 0,
    HMSM_LEAF_STATE_ON = 1,
    HMSM_LEAF_STATE_OFF = 2
};
/* The wood species presets (data/species.json): their number, and the key of preset `index`
 * ("sugar-maple"), a string owned by the library for its lifetime. */
HMSM_API hmsm_status hmsm_species_count(uint64_t* count);
HMSM_API hmsm_status hmsm_species_name(uint64_t index, const char** name);
/* The tree's material from a species preset; an unknown name fails naming the known ones. */
HMSM_API hmsm_status hmsm_tree_set_species(hmsm_tree* tree, const char* name);
/* The tree's material by value: modulus E (Pa) and green density (kg/m^3), range-checked. */
HMSM_API hmsm_status hmsm_tree_set_material(hmsm_tree* tree, double modulus, double density);
HMSM_API hmsm_status hmsm_tree_clear_material(hmsm_tree* tree);
/* *has_material = 1 and its values, or 0 and zeros when the tree carries none. */
HMSM_API hmsm_status hmsm_tree_material(const hmsm_tree* tree, int32_t* has_material, double* modulus,
                                        double* density);
HMSM_API hmsm_status hmsm_tree_set_leaf_state(hmsm_tree* tree, int32_t state); /* HMSM_LEAF_STATE_* */
HMSM_API hmsm_status hmsm_tree_leaf_state(const hmsm_tree* tree, int32_t* state);

/* --- scenes ------------------------------------------------------------------------------- */
HMSM_API hmsm_status hmsm_scene_create(hmsm_scene** scene);
/* An hmsm-forest JSON v1 file (docs/model.md 4): builds the models its instances place. */
HMSM_API hmsm_status hmsm_scene_load_forest(const char* path, hmsm_scene** scene);
/* As hmsm_scene_load_forest, also building the `count` models named in `names` (those that
 * hmsm_simulation_add_instances will add later); a name the forest lacks is an error. */
HMSM_API hmsm_status hmsm_scene_load_forest_with(const char* path, const char* const* names, size_t count,
                                                 hmsm_scene** scene);
/* The index of the model called `name` (several forest names may share one model). */
HMSM_API hmsm_status hmsm_scene_find_model(const hmsm_scene* scene, const char* name, uint32_t* model);
/* Copies `tree` into the scene as a new model; *model receives its index (may be NULL). */
HMSM_API hmsm_status hmsm_scene_add_model(hmsm_scene* scene, const hmsm_tree* tree,
                                          const char* name, uint32_t* model);
HMSM_API hmsm_status hmsm_scene_add_instance(hmsm_scene* scene, const hmsm_instance* instance);
/* Runs model `model` at a level of detail (hmsm::Scene::joint_budgets, docs/model.md 3.13):
 * max_joints 0 runs the model whole (the default), N >= 1 its finest level with at most N
 * chains in its place; a negative max_joints fails with HMSM_INVALID_ARGUMENT. */
HMSM_API hmsm_status hmsm_scene_set_joint_budget(hmsm_scene* scene, uint32_t model, int32_t max_joints);
/* The joint budgets (each >= 1) of the levels of detail that instances of `model` may switch to
 * while a simulation runs (hmsm::Scene::lod_budgets, docs/driving.md): level 0 is the model as
 * created, level k the finest with at most budgets[k - 1] chains. A budget below 1 fails with
 * HMSM_INVALID_ARGUMENT and changes nothing. */
HMSM_API hmsm_status hmsm_scene_set_lod_budgets(hmsm_scene* scene, uint32_t model, const int32_t* budgets,
                                                size_t count);
HMSM_API hmsm_status hmsm_scene_model_count(const hmsm_scene* scene, uint32_t* count);
HMSM_API hmsm_status hmsm_scene_instance_count(const hmsm_scene* scene, uint64_t* count);
HMSM_API void hmsm_scene_destroy(hmsm_scene* scene);

/* --- simulations -------------------------------------------------------------------------- */
HMSM_API hmsm_status hmsm_simulation_create(const hmsm_scene* scene, const hmsm_config* config,
                                            hmsm_simulation** simulation);
HMSM_API void hmsm_simulation_destroy(hmsm_simulation* simulation);
HMSM_API hmsm_status hmsm_simulation_step(hmsm_simulation* simulation, uint32_t count);
/* Reads output `output` (HMSM_OUTPUT_*) into values[capacity]; *count = elements x components. */
HMSM_API hmsm_status hmsm_simulation_read_f32(const hmsm_simulation* simulation, int32_t output,
                                              float* values, size_t capacity, size_t* count);
HMSM_API hmsm_status hmsm_simulation_read_f64(const hmsm_simulation* simulation, int32_t output,
                                              double* values, size_t capacity, size_t* count);
/* Asynchronous readback (Simulation::request_read / take_read): request_read starts copying
 * `output` as the steps so far leave it and returns at once; take_read_* waits for that copy and
 * returns those values, as read_* (size query with values NULL and capacity 0 included). A
 * request stays until the next request of the same output, so a failed or repeated take_read
 * changes nothing. take_read without a request fails with HMSM_INVALID_ARGUMENT. */
HMSM_API hmsm_status hmsm_simulation_request_read(hmsm_simulation* simulation, int32_t output);
HMSM_API hmsm_status hmsm_simulation_take_read_f32(hmsm_simulation* simulation, int32_t output,
                                                   float* values, size_t capacity, size_t* count);
HMSM_API hmsm_status hmsm_simulation_take_read_f64(hmsm_simulation* simulation, int32_t output,
                                                   double* values, size_t capacity, size_t* count);
/* counts->struct_size must be set (hmsm_counts_init). */
HMSM_API hmsm_status hmsm_simulation_counts(const hmsm_simulation* simulation, hmsm_counts* counts);
/* The backend it runs on (HMSM_BACKEND_*, never AUTOMATIC). */
HMSM_API hmsm_status hmsm_simulation_backend(const hmsm_simulation* simulation, int32_t* backend);
/* The device name as a NUL-terminated string in name[capacity]; *length = bytes needed with
 * the NUL. */
HMSM_API hmsm_status hmsm_simulation_device_name(const hmsm_simulation* simulation, char* name,
                                                 size_t capacity, size_t* length);
/* Triangles (3 indices each, counter-clockwise from outside) of model `model`'s mesh, indexing
 * that model's vertices; instance i of the model uses its vertices at its own offset in
 * HMSM_OUTPUT_VERTEX_POSITIONS. */
HMSM_API hmsm_status hmsm_simulation_mesh_indices(const hmsm_simulation* simulation,
                                                  uint32_t model, uint32_t* indices,
                                                  size_t capacity, size_t* count);

/* --- live control (docs/model.md 3.9): from the next step on; a rejected call changes nothing */
HMSM_API hmsm_status hmsm_simulation_set_wind(hmsm_simulation* simulation, const hmsm_wind* wind);
HMSM_API hmsm_status hmsm_simulation_get_wind(const hmsm_simulation* simulation, hmsm_wind* wind);
/* Replaces every force field (count 0 removes them; fields may then be NULL). */
HMSM_API hmsm_status hmsm_simulation_set_force_fields(hmsm_simulation* simulation,
                                                      const hmsm_force_field* fields, size_t count);
HMSM_API hmsm_status hmsm_simulation_set_instance_wind_scale(hmsm_simulation* simulation,
                                                             uint64_t instance, double wind_scale);
HMSM_API hmsm_status hmsm_simulation_set_instance_wind_phase(hmsm_simulation* simulation,
                                                             uint64_t instance, double wind_phase);
HMSM_API hmsm_status hmsm_simulation_set_instance_active(hmsm_simulation* simulation,
                                                         uint64_t instance, int32_t active);
HMSM_API hmsm_status hmsm_simulation_add_instances(hmsm_simulation* simulation,
                                                   const hmsm_instance* instances, size_t count);
HMSM_API hmsm_status hmsm_simulation_remove_instances(hmsm_simulation* simulation,
                                                      const uint64_t* indices, size_t count);
/* Puts instances (current indices, no repeats) back at rest as right after adding them
   (Simulation::reset_instances): state zero, posed at rest, settings kept. A bad index changes
   nothing. */
HMSM_API hmsm_status hmsm_simulation_reset_instances(hmsm_simulation* simulation,
                                                     const uint32_t* indices, size_t count);
/* Room on the device for `count` instances in all (Simulation::reserve_instances): adding up to
 * that many then costs only what the added instances cost. */
HMSM_API hmsm_status hmsm_simulation_reserve_instances(hmsm_simulation* simulation, uint64_t count);
/* The same for a world of levels of detail (Simulation::reserve_instances(per_level)): room for
 * per_level[k] instances at level k, finest first, `count` levels. NULL with a non-zero count,
 * no levels or more levels than the scene's models have are refused and change nothing. */
HMSM_API hmsm_status hmsm_simulation_reserve_level_instances(hmsm_simulation* simulation,
                                                             const uint64_t* per_level, size_t count);
/* Stable instance handles (Simulation::index_of and friends, docs/driving.md): the instances of
 * the scene get ids 0 .. n-1, each added one the next unused id; an id stays valid while its
 * instance lives and is never given again. A removed, unknown or repeated id is refused, naming
 * it, and changes nothing. */
typedef uint64_t hmsm_instance_id;
/* hmsm_simulation_add_instances, and ids[count] receives the added instances' ids. */
HMSM_API hmsm_status hmsm_simulation_add_instances_with_ids(hmsm_simulation* simulation,
                                                            const hmsm_instance* instances, size_t count,
                                                            hmsm_instance_id* ids);
HMSM_API hmsm_status hmsm_simulation_remove_instances_by_id(hmsm_simulation* simulation,
                                                            const hmsm_instance_id* ids, size_t count);
/* Removes by id without keeping the order (Simulation::swap_remove_instances): each hole is
 * filled by the last surviving instances, so only as many instances move as are removed. */
HMSM_API hmsm_status hmsm_simulation_swap_remove_instances(hmsm_simulation* simulation,
                                                           const hmsm_instance_id* ids, size_t count);
HMSM_API hmsm_status hmsm_simulation_index_of(const hmsm_simulation* simulation, hmsm_instance_id id,
                                              uint64_t* index);
HMSM_API hmsm_status hmsm_simulation_id_of(const hmsm_simulation* simulation, uint64_t index,
                                           hmsm_instance_id* id);
/* Where instance `id`'s elements begin in the state and output buffers
 * (hmsm::Simulation::instance_placement): in HMSM_INSTANCE_LAYOUT_PLACED its slot, else its
 * packed place. An engine skinning from a shared GPU buffer reads the instance's joint
 * matrices from first_chain on. placement->struct_size must be set
 * (hmsm_instance_placement_init). */
typedef struct hmsm_instance_placement {
    uint32_t struct_size;
    uint64_t first_chain;
    uint64_t first_node;
    uint64_t first_vertex;
} hmsm_instance_placement;
HMSM_API hmsm_status hmsm_instance_placement_init(hmsm_instance_placement* placement, size_t struct_size); /* zeros */
HMSM_API hmsm_status hmsm_simulation_instance_placement(const hmsm_simulation* simulation, hmsm_instance_id id,
                                                        hmsm_instance_placement* placement);
/* Levels of detail at run time (hmsm::Simulation::set_instance_lods and friends,
 * docs/driving.md): runs instance ids[k] on levels[k], all in one reshape, keeping each
 * instance's id, index and settings and carrying the state of the chains both levels keep. An
 * unknown or repeated id or a level the model lacks fails, naming it, and changes nothing. */
HMSM_API hmsm_status hmsm_simulation_set_instance_lods(hmsm_simulation* simulation, const hmsm_instance_id* ids,
                                                       const uint32_t* levels, size_t count);
HMSM_API hmsm_status hmsm_simulation_instance_lod(const hmsm_simulation* simulation, hmsm_instance_id id,
                                                  uint32_t* level);
/* Distance bands for hmsm_simulation_update_lod (hmsm::LodBands): edges[count] in metres,
 * strictly increasing and positive; hysteresis a fraction of an edge in [0, 1). */
HMSM_API hmsm_status hmsm_simulation_set_lod_bands(hmsm_simulation* simulation, const double* edges, size_t count,
                                                   double hysteresis);
/* The fade of coarsening switches (hmsm::LodBands::fade_steps and fade_bound_m): steps (0 to
 * 65536; 0 switches at once) steps of relaxing the chains the coarser level folds, then the
 * switch; an instance that deflects no vertex by more than bound_m metres (in [0, 1]) at the
 * request switches at once (measured with a read of its state; 0: nothing is read, every
 * coarsening fades). Keeps
 * the edges and hysteresis; hmsm_simulation_set_lod_bands keeps the fade. */
HMSM_API hmsm_status hmsm_simulation_set_lod_fade(hmsm_simulation* simulation, uint32_t steps, double bound_m);
/* Chooses every instance's level from its distance to viewer (x, y, z metres): finer levels
 * switch at once, coarser ones fade (hmsm_simulation_set_lod_fade); *switched (may be NULL)
 * receives how many instances changed level or target. Once per frame, before stepping. */
HMSM_API hmsm_status hmsm_simulation_update_lod(hmsm_simulation* simulation, const double viewer[3],
                                                uint64_t* switched);
/* The current instance list into instances[capacity]; *count = the number of instances.
 * instances[0].struct_size gives the layout of every element written. */
HMSM_API hmsm_status hmsm_simulation_instances(const hmsm_simulation* simulation,
                                               hmsm_instance* instances, size_t capacity,
                                               size_t* count);

/* --- skins (docs/skinning.md): a model's skinned mesh, for engines that draw trees from the
 * joint matrices (HMSM_OUTPUT_JOINT_MATRICES) as a bone palette, on the GPU or with
 * hmsm_skin_vertices. Vertex order and triangles are those of hmsm_simulation_mesh_indices.
 * Instance i's joints start at chain_base(i) = the sum of the chain counts of the instances
 * before it (a forest of one model: i x chains). */
typedef struct hmsm_skin hmsm_skin; /* the skin of one model (hmsm::SkinTemplate) */
/* What hmsm_skin_read_* returns, components per element in brackets. */
enum {
    HMSM_SKIN_BIND_POSITIONS = 0, /* per vertex [3]: rest pose of an instance at the origin, yaw 0 */
    HMSM_SKIN_BIND_NORMALS = 1,   /* per vertex [3]: unit rest normals */
    HMSM_SKIN_JOINTS = 2,         /* per vertex [2], integers: chains of the model; -1 = unused */
    HMSM_SKIN_WEIGHTS = 3,        /* per vertex [2]: sum 1; 0 for an unused joint */
    HMSM_SKIN_INVERSE_BIND = 4,   /* per chain [12]: [B^T | -B^T p] row by row */
    HMSM_SKIN_BIND_MATRICES = 5,  /* per chain [12]: the rest joint matrix [B | p] row by row */
    HMSM_SKIN_CHAIN_PARENTS = 6,  /* per chain [1], integers: the parent chain, -1 for the trunk */
    HMSM_SKIN_SOURCE_CHAINS = 7,  /* per joint [1], integers: the model's chain that drives it */
    HMSM_SKIN_DATA_COUNT = 8
};
/* The skin of model `model` of the simulation (hmsm::build_skin); one skin serves every
 * instance of the model, including instances added later. */
HMSM_API hmsm_status hmsm_skin_create(const hmsm_simulation* simulation, uint32_t model,
                                      hmsm_skin** skin);
/* A level of detail (hmsm::build_level, docs/model.md 3.13): the finest level of the model with
 * at most max_joints joints (default 256); a max_joints at or above the model's chain count
 * gives the model itself, one below 1 fails with HMSM_INVALID_ARGUMENT. */
typedef struct hmsm_level_options {
    uint32_t struct_size;
    int32_t max_joints;
} hmsm_level_options;
HMSM_API hmsm_status hmsm_level_options_init(hmsm_level_options* options, size_t struct_size);
/* The skin of model `model` at the level of `options` (hmsm::build_skin with a DetailLevel):
 * the same vertices and triangles, with the level's chains as joints. Joint j moves as the
 * model's chain HMSM_SKIN_SOURCE_CHAINS[j]: its palette entry is that chain's joint matrix (for
 * hmsm_skin_vertices, gather them into a palette of `chains` entries). */
HMSM_API hmsm_status hmsm_skin_create_level(const hmsm_simulation* simulation, uint32_t model,
                                            const hmsm_level_options* options, hmsm_skin** skin);
HMSM_API void hmsm_skin_destroy(hmsm_skin* skin);
HMSM_API hmsm_status hmsm_skin_sizes(const hmsm_skin* skin, uint64_t* vertices, uint64_t* chains);
/* Reads `data` (HMSM_SKIN_*) into values[capacity]; *count = elements x components. The
 * integer data (JOINTS, CHAIN_PARENTS) is read with _i32, the rest with _f32 or _f64; the other
 * type fails with HMSM_INVALID_ARGUMENT. */
HMSM_API hmsm_status hmsm_skin_read_f32(const hmsm_skin* skin, int32_t data, float* values,
                                        size_t capacity, size_t* count);
HMSM_API hmsm_status hmsm_skin_read_f64(const hmsm_skin* skin, int32_t data, double* values,
                                        size_t capacity, size_t* count);
HMSM_API hmsm_status hmsm_skin_read_i32(const hmsm_skin* skin, int32_t data, int32_t* values,
                                        size_t capacity, size_t* count);
/* Linear-blend skinning of one instance on the CPU (hmsm::skin_vertices): joint_matrices points
 * at that instance's first joint matrix in HMSM_OUTPUT_JOINT_MATRICES, with joint_values >= 12 x
 * chains floats readable there. positions (and normals, unless NULL) receive xyz per vertex:
 * capacity in floats each, *count = 3 x vertices (positions = NULL with capacity 0 only queries
 * it). threads: 1 the calling thread, 0 every hardware thread, n at most n. */
HMSM_API hmsm_status hmsm_skin_vertices(const hmsm_skin* skin, const float* joint_matrices,
                                        size_t joint_values, float* positions, float* normals,
                                        size_t capacity, size_t* count, uint32_t threads);

#ifdef __cplusplus
}
#endif

#endif /* HMSM_HMSM_C_H */
