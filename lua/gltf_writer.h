/* gltf_writer.h: a run as binary glTF 2.0 (.glb), for `tumble run --gltf`.
   It reads the world through the public C API only: the shapes
   (tb_world_shape_at, tb_shape_definition), the springs
   (tb_world_spring_at, tb_spring_definition), and each recorded frame's
   bodies, particles and tracers. The layout (nodes, meshes, the
   animation, units, the z-up root) is in docs/command.md, "glTF".

   Use: gltf_begin before the first frame, gltf_record at every frame the
   trajectory records, gltf_write once at the end, gltf_free always. Every
   function that can fail returns 0 or -1 with a one-line reason in
   gltf_message(); none aborts. */
#ifndef GLTF_WRITER_H
#define GLTF_WRITER_H

#include <stdio.h>
#include "tumble.h"

typedef struct gltf_writer gltf_writer;

/* A writer for this world's objects as they are now (the set of objects
   must stay the same for the run). NULL when out of memory. */
gltf_writer *gltf_begin(const tb_world *w);
/* Add the world's state now as a frame at tb_world_time(w). A frame
   whose time rounds (as a float) to the previous frame's is skipped:
   glTF needs strictly increasing key times. */
int gltf_record(gltf_writer *g, const tb_world *w);
/* Write the whole file to f (binary). Write errors show in ferror(f). */
int gltf_write(gltf_writer *g, const tb_world *w, FILE *f);
/* The frames recorded so far (those kept). */
size_t gltf_frames(const gltf_writer *g);
const char *gltf_message(const gltf_writer *g);
void gltf_free(gltf_writer *g);

#endif
