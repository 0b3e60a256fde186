/* diagnostics.c: energies and momentum, computed on demand. */
#include "world.h"

tb_energy tb_world_energy(const tb_world *w)
{
    tb_energy e = { 0, 0, 0, 0 };
    const double *x = w->y ? w->y + w->off_particle_pos : NULL;
    const double *v = w->y ? w->y + w->off_particle_vel : NULL;
    const double *g = w->gravity;
    size_t i;
    for (i = 0; i < w->particle_count; ++i) {
        const double *xi = x + 3 * i, *vi = v + 3 * i;
        e.kinetic += 0.5 * w->mass[i] * (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]);
        e.gravity -= w->mass[i] * (g[0] * xi[0] + g[1] * xi[1] + g[2] * xi[2]);
    }
    e.spring = tb__spring_energy(w);
    e.total = e.kinetic + e.gravity + e.spring;
    return e;
}

void tb_world_momentum(const tb_world *w, double p[3])
{
    const double *v = w->y ? w->y + w->off_particle_vel : NULL;
    size_t i;
    p[0] = p[1] = p[2] = 0;
    for (i = 0; i < w->particle_count; ++i) {
        p[0] += w->mass[i] * v[3 * i];
        p[1] += w->mass[i] * v[3 * i + 1];
        p[2] += w->mass[i] * v[3 * i + 2];
    }
}
