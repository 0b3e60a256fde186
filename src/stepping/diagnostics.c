/* diagnostics.c: energies and momentum, computed on demand. */
#include "stepping/stepping.h"
#include "bodies/bodies.h"
#include "forces/forces.h"
#include "particles/particles.h"

tb_energy tb__energy_of(const tb_world *w, const double *y)
{
    tb_energy e = { 0, 0, 0, 0, 0 };
    const double *x = y ? y + w->off[TB__PARTICLE_POS] : NULL;
    const double *v = y ? y + w->off[TB__PARTICLE_VEL] : NULL;
    const double *g = w->gravity;
    size_t i;
    for (i = 0; i < w->particle_count; ++i) {
        const double *xi = x + 3 * i, *vi = v + 3 * i;
        e.kinetic += 0.5 * w->particle_mass[i] * (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]);
        e.gravity -= w->particle_mass[i] * (g[0] * xi[0] + g[1] * xi[1] + g[2] * xi[2]);
    }
    if (w->spring_count)
        e.spring = tb__spring_energy(w, x);
    if (w->body_count)
        tb__body_energy(w, y, &e);
    e.total = e.kinetic + e.rotational + e.gravity + e.spring;
    return e;
}

tb_energy tb_world_energy(const tb_world *w)
{
    if (!w) {
        const tb_energy none = { 0, 0, 0, 0, 0 };
        return none;
    }
    return tb__energy_of(w, w->y);
}

/* Both momenta at once: particles m v and m x x v, then the bodies. */
static void momenta(const tb_world *w, double p[3], double l[3])
{
    const double *x = w->y ? w->y + w->off[TB__PARTICLE_POS] : NULL;
    const double *v = w->y ? w->y + w->off[TB__PARTICLE_VEL] : NULL;
    size_t i;
    p[0] = p[1] = p[2] = 0;
    l[0] = l[1] = l[2] = 0;
    for (i = 0; i < w->particle_count; ++i) {
        const double m = w->particle_mass[i], *xi = x + 3 * i, *vi = v + 3 * i;
        p[0] += m * vi[0];
        p[1] += m * vi[1];
        p[2] += m * vi[2];
        l[0] += m * (xi[1] * vi[2] - xi[2] * vi[1]);
        l[1] += m * (xi[2] * vi[0] - xi[0] * vi[2]);
        l[2] += m * (xi[0] * vi[1] - xi[1] * vi[0]);
    }
    if (w->body_count)
        tb__body_momenta(w, p, l);
}

void tb_world_momentum(const tb_world *w, double p[3])
{
    double l[3];
    if (w && p)
        momenta(w, p, l);
}

void tb_world_angular_momentum(const tb_world *w, double l[3])
{
    double p[3];
    if (w && l)
        momenta(w, p, l);
}
