// The Vulkan backend's run table, included by C++ and GLSL (shaders compile with -I
// src/common): how a launch that runs a run of dispatches together (step_program.h
// dispatch_batches; src/vulkan/run_table.h) finds each dispatch's constants. Only the
// preprocessor here.
//
// Its push constants (gpu_layout.h PassConstants) hold kind = HMSM_DISPATCH_RUN_TABLE,
// instance_begin = the run's first entry in the table, element_count = its entries, and the
// step's wind_slot. Entry e of the table (descriptor set HMSM_RUN_TABLE_SET) holds the
// PassConstants of one dispatch (binding HMSM_RUN_TABLE_CONSTANTS) and the launch's workgroup
// where that dispatch's workgroups begin (binding HMSM_RUN_TABLE_WORKGROUPS, a uint, ascending
// within a launch). The kind is no HMSM_DISPATCH_* of a program: a program never holds it.
#ifndef HMSM_RUN_TABLE_LAYOUT_H
#define HMSM_RUN_TABLE_LAYOUT_H

#define HMSM_DISPATCH_RUN_TABLE 0xffffu
#define HMSM_RUN_TABLE_SET 1
#define HMSM_RUN_TABLE_CONSTANTS 0
#define HMSM_RUN_TABLE_WORKGROUPS 1

#endif  // HMSM_RUN_TABLE_LAYOUT_H
