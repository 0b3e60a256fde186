/* diagnostics.c: energies and momentum, computed on demand. */
#include "stepping/stepping.h"
#include "bodies/bodies.h"
#include "forces/forces.h"
#include "particles/particles.h"

tb_energy tb__energy_of(const tb_world *w, const double *y)
{
    tb_energy e = { 0, 0, 0, 0, 0, 0 };
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
        const tb_energy none = { 0, 0, 0, 0, 0, 0 };
        return none;
    }
    return tb__energy_of(w, w->y);
}

int tb__is_damped(const tb_world *w)
{
    size_t i;
    if (w->linear_drag > 0 || w->quadratic_drag > 0 || w->body_damped)
        return w->particle_count > 0 || w->body_damped;
    for (i = 0; i < w->spring_count; ++i)
        if (w->spring_c[i] > 0)
            return 1;
    return 0;
}

/* -(c1 + c2 |v|) |v|^2 per free particle (summed as the particles' one-pass
   kernel sums it, tb__particle_drag_power), -c ((v_a - v_b).n)^2 per spring,
   -c_lin |P|^2 / m and -c_ang w.L per body. */
double tb__damping_power(const tb_world *w)
{
    const double *x = w->y + w->off[TB__PARTICLE_POS], *v = w->y + w->off[TB__PARTICLE_VEL];
    double p = 0;
    size_t i;
    if (w->linear_drag > 0 || w->quadratic_drag > 0)
        p = tb__particle_drag_power(w);
    for (i = 0; i < w->spring_count; ++i) {
        const uint32_t a = w->spring_a[i], b = w->spring_b[i];
        const double *xb = b == TB__ANCHOR ? w->spring_anchor + 3 * i : x + 3 * b;
        const double d[3] = { x[3 * a] - xb[0], x[3 * a + 1] - xb[1], x[3 * a + 2] - xb[2] };
        const double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        double along = 0;
        int k;
        if (w->spring_c[i] == 0 || len == 0)
            continue;
        for (k = 0; k < 3; ++k)
            along += d[k] / len * (v[3 * a + k] - (b == TB__ANCHOR ? 0 : v[3 * b + k]));
        p -= w->spring_c[i] * along * along;
    }
    for (i = 0; w->body_damped && i < w->body_count; ++i) {
        const double *P = w->y + w->off[TB__BODY_MOM] + 3 * i, *L = w->y + w->off[TB__BODY_ANG] + 3 * i;
        const double *q = w->y + w->off[TB__BODY_ROT] + 4 * i;
        double omega[3];
        tb__through_inertia(q, w->body_inv_inertia + 3 * i, L, omega);
        p -= w->body_damping[2 * i] * (P[0] * P[0] + P[1] * P[1] + P[2] * P[2]) * w->body_inv_mass[i];
        p -= w->body_damping[2 * i + 1] * (omega[0] * L[0] + omega[1] * L[1] + omega[2] * L[2]);
    }
    return p;
}

/* The callbacks see the state as a step's evaluation would, write their
   forces into scratch (thrown away) and add their potential energy; the
   world is marked as stepping meanwhile, so they can change nothing. */
tb_status tb_world_energy_with_callbacks(tb_world *w, tb_energy *energy)
{
    tb_status st;
    double potential = 0;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if (!energy)
        return tb__null(w, "tb_world_energy_with_callbacks", "the energy to write");
    if ((st = tb__check_busy(w, "measure the energy")) != TB_OK)
        return st;
    if (w->forces.count) {
        w->stepping = 1;
        st = tb__force_potential(w, &potential);
        w->stepping = 0;
        if (st != TB_OK)
            return st;
    }
    *energy = tb__energy_of(w, w->y);
    energy->potential = potential;
    energy->total += potential;
    return TB_OK;
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
