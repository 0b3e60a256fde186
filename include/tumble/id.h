/* tumble/id.h: value ids. An id is an index into a per-world table plus a
   generation counter: a removed object's id goes stale and every call that
   gets it fails with TB_ERR_STALE_ID instead of touching another object.
   The all-zero id is null. Ids are plain values: copy and compare freely. */
#ifndef TUMBLE_ID_H
#define TUMBLE_ID_H

#include <stdint.h>

typedef struct tb_tracer_id   { uint32_t index1; uint32_t generation; } tb_tracer_id;
typedef struct tb_particle_id { uint32_t index1; uint32_t generation; } tb_particle_id;
typedef struct tb_spring_id   { uint32_t index1; uint32_t generation; } tb_spring_id;
typedef struct tb_body_id     { uint32_t index1; uint32_t generation; } tb_body_id;
typedef struct tb_shape_id    { uint32_t index1; uint32_t generation; } tb_shape_id;

#define TB_ID_IS_NULL(id) ((id).index1 == 0)
#define TB_ID_EQUAL(a, b) ((a).index1 == (b).index1 && (a).generation == (b).generation)

#endif
