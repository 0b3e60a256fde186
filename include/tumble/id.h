/* tumble/id.h: value ids.

   An id is an index into a per-world table plus a generation, which counts
   the lives of the table entry and carries a tag of the world that made the
   id. A removed object's id goes stale, and every call given a stale id, or
   an id made by another world, fails with TB_ERR_STALE_ID instead of
   touching another object. The all-zero id is null ({0} in C, {} in C++);
   an index of 0 is null whatever the generation. Ids are plain values: copy
   and compare them freely; their fields are not part of the contract. This
   header needs nothing else from tumble and may be included on its own. */
#ifndef TUMBLE_ID_H
#define TUMBLE_ID_H

#include <stdint.h>

typedef struct tb_tracer_id   { uint32_t index1; uint32_t generation; } tb_tracer_id;
typedef struct tb_particle_id { uint32_t index1; uint32_t generation; } tb_particle_id;
typedef struct tb_spring_id   { uint32_t index1; uint32_t generation; } tb_spring_id;
typedef struct tb_body_id     { uint32_t index1; uint32_t generation; } tb_body_id;
typedef struct tb_shape_id    { uint32_t index1; uint32_t generation; } tb_shape_id;
typedef struct tb_field_id    { uint32_t index1; uint32_t generation; } tb_field_id;
typedef struct tb_force_id    { uint32_t index1; uint32_t generation; } tb_force_id;
typedef struct tb_joint_id    { uint32_t index1; uint32_t generation; } tb_joint_id;

/* Whether an id is null; whether two ids of one type name the same object. */
#define TB_ID_IS_NULL(id) ((id).index1 == 0)
#define TB_ID_EQUAL(a, b) ((a).index1 == (b).index1 && (a).generation == (b).generation)

#endif
