/* app.c: the program every consumer project builds: a ball dropped on a
   plane, 2 s at 60 Hz; it prints where the ball rests and exits 0 only if
   that is on the plane (its centre one radius up, within a millimetre). */
#include <math.h>
#include <stdio.h>
#include <tumble.h>

int main(void)
{
    tb_world_def def = tb_default_world_def();
    tb_body_def b = tb_default_body_def();
    tb_shape_def plane = tb_default_shape_def(), ball = tb_default_shape_def();
    tb_world *w;
    tb_body_id id;
    double x[3];
    int i;
    char message[TB_MESSAGE_SIZE];
    def.gravity[2] = -9.81;
    if (tb_world_create(&def, &w, message, sizeof message) != TB_OK)
        return fprintf(stderr, "%s\n", message), 1;
    plane.type = TB_SHAPE_PLANE;
    b.position[2] = 1;
    if (tb_world_add_shape(w, &plane, NULL) != TB_OK || tb_world_add_body(w, &b, &id) != TB_OK)
        return fprintf(stderr, "%s\n", tb_world_message(w)), 1;
    ball.body = id; /* the default shape: a sphere of 0.5 m */
    if (tb_world_add_shape(w, &ball, NULL) != TB_OK)
        return fprintf(stderr, "%s\n", tb_world_message(w)), 1;
    for (i = 0; i < 120; ++i)
        if (tb_world_step(w, 1.0 / 60) != TB_OK)
            return fprintf(stderr, "%s\n", tb_world_message(w)), 1;
    tb_body_position(w, id, x);
    printf("ball at z = %.4f m\n", x[2]);
    tb_world_destroy(w);
    return fabs(x[2] - 0.5) < 1e-3 ? 0 : 1;
}
