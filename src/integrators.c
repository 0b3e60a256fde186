/* integrators.c: the stepping methods, each a short function over the
   state-vector primitives (derive, axpy) or the split primitives (prepare
   forces, sweep kicks and drifts). Adding a method touches this file only. */
#include "world.h"

#include <math.h>
#include <string.h>

/* y += h F(t, y). Writes y only after its one evaluation. */
static tb_status euler(tb_world *w, double h)
{
    tb_status st = tb__state_scratch(w, 1);
    double *dy;
    if (st != TB_OK)
        return st;
    dy = tb__scratch_vector(w, 0);
    if ((st = tb__derive(w, w->time, w->y, dy)) != TB_OK)
        return st;
    tb__state_axpy(w, w->y, w->y, h, dy);
    tb__project(w, w->y);
    return TB_OK;
}

/* Classic RK4 with three scratch vectors: a stage state, a stage slope and
   the running sum k1 + 2 k2 + 2 k3 + k4. Writes y only at the end, then
   projects it (unit quaternions). Stage states are not projected: the
   quaternion equation q' = (0, w) q / 2, with w computed from q / |q|, keeps
   |q| by itself, and projecting stages perturbs them by O(h^2), which costs
   RK4 its order (measured on the flip: 4.5e-4 rad with stage projection,
   see test_bodies for the figure without). When nothing couples objects,
   the world steps them one block at a time through all four stages
   (tb__fused_rk4), with these very operations: the same bits, without the
   passes over the whole state. */
static tb_status rk4(tb_world *w, double h)
{
    const double t = w->time;
    double *stage, *k, *sum;
    tb_status st;
    if (tb__fused_rk4(w, h))
        return TB_OK;
    if ((st = tb__state_scratch(w, 3)) != TB_OK)
        return st;
    stage = tb__scratch_vector(w, 0);
    k = tb__scratch_vector(w, 1);
    sum = tb__scratch_vector(w, 2);
    if ((st = tb__derive(w, t, w->y, sum)) != TB_OK)
        return st;
    tb__state_axpy(w, stage, w->y, h / 2, sum);
    if ((st = tb__derive(w, t + h / 2, stage, k)) != TB_OK)
        return st;
    tb__state_axpy(w, sum, sum, 2, k);
    tb__state_axpy(w, stage, w->y, h / 2, k);
    if ((st = tb__derive(w, t + h / 2, stage, k)) != TB_OK)
        return st;
    tb__state_axpy(w, sum, sum, 2, k);
    tb__state_axpy(w, stage, w->y, h, k);
    if ((st = tb__derive(w, t + h, stage, k)) != TB_OK)
        return st;
    tb__state_axpy(w, sum, sum, 1, k);
    tb__state_axpy(w, w->y, w->y, h / 6, sum);
    tb__project(w, w->y);
    return TB_OK;
}

/* Kick with the forces at the start, then drift with the new velocity.
   Anisotropic bodies turn with w frozen at the start of the drift (first
   order), as in ODE. */
static tb_status symplectic_euler(tb_world *w, double h)
{
    const tb__split_op kick_drift[2] = { { 0, h, TB__ROTATE_FROZEN }, { 1, h, TB__ROTATE_FROZEN } };
    tb_status st = tb__split_prepare(w, w->time, NULL);
    if (st != TB_OK)
        return st;
    tb__split_sweep(w, kick_drift, 2);
    return TB_OK;
}

/* Kick h/2, drift h, evaluate the forces again, kick h/2. The second
   evaluation comes after the state moved: tb_world_step snapshots it when a
   callback could fail there.
   Velocity-dependent forces (drag, damping, callbacks) are evaluated for the
   closing kick at the predicted end velocity v_n + h a_n = 2 v_half - v_n,
   not at v_half: that keeps the method second order with damping (on
   v' = -k v it multiplies by 1 - kh + (kh)^2 / 2 per step) at no extra
   evaluation. Position-only forces never see the difference.
   `rotation` is how the drift turns anisotropic bodies through their free
   motion: "verlet" uses the symmetric axis splitting (second order, keeps
   the energy error bounded), "verlet_exact" the accurate kernel. */
static tb_status verlet_with(tb_world *w, double h, tb__rotation_kind rotation)
{
    const tb__split_op kick_drift[2] = { { 0, h / 2, rotation }, { 1, h, rotation } };
    const tb__split_op kick[1] = { { 0, h / 2, rotation } };
    double *predicted = NULL;
    tb_status st;
    if (tb__split_velocity_dependent(w)) {
        if ((st = tb__state_scratch(w, 1)) != TB_OK)
            return st;
        predicted = tb__scratch_vector(w, 0);
        tb__state_copy(w, predicted, w->y);
    }
    if ((st = tb__split_prepare(w, w->time, NULL)) != TB_OK)
        return st;
    tb__split_sweep(w, kick_drift, 2);
    if (predicted)
        tb__split_extrapolate(w, predicted);
    st = tb__split_prepare(w, w->time + h, predicted);
    if (st == TB_OK)
        tb__split_sweep(w, kick, 1);
    w->kick_seen = NULL;
    return st;
}

static tb_status verlet(tb_world *w, double h)
{
    return verlet_with(w, h, TB__ROTATE_SPLIT2);
}

static tb_status verlet_exact(tb_world *w, double h)
{
    return verlet_with(w, h, TB__ROTATE_ACCURATE);
}

/* name, order, split, updates before its last evaluation, scratch vectors */
/* Linearised backward Euler (implicit.c): one conjugate-gradient solve per
   step; stable at any step on springs and drag, and dissipative. */
static tb_status implicit_euler(tb_world *w, double h)
{
    return tb__implicit_step(w, h);
}

/* Stability limits (|h lambda|): explicit Euler's region |1 + z| <= 1 never
   reaches the imaginary axis; the split methods are bounded for h w < 2 and
   damp a decay for h k < 2; RK4's region reaches 2 sqrt 2 on the imaginary
   axis and 2.785 on the negative real axis. */
static const tb__method methods[] = {
    { "euler", 1, 0, 0, 1, euler, 0, 2 },
    { "symplectic_euler", 1, 1, 0, 0, symplectic_euler, 2, 2 },
    { "verlet", 2, 1, 1, 1, verlet, 2, 2 },
    { "rk4", 4, 0, 0, 3, rk4, 2.8284271247461903, 2.785293563405282 },
    { "verlet_exact", 2, 1, 1, 1, verlet_exact, 2, 2 },
    { "implicit_euler", 1, 1, 0, 4, implicit_euler, INFINITY, INFINITY },
};
#define METHOD_COUNT ((int)(sizeof methods / sizeof methods[0]))

const tb__method *tb__method_find(const char *name)
{
    int i;
    for (i = 0; name && i < METHOD_COUNT; ++i)
        if (strcmp(methods[i].name, name) == 0)
            return &methods[i];
    return NULL;
}

const tb__method *tb__method_at(int index)
{
    return index >= 0 && index < METHOD_COUNT ? &methods[index] : NULL;
}

int tb_integrator_count(void)
{
    return METHOD_COUNT;
}

const char *tb_integrator_name(int index)
{
    return index >= 0 && index < METHOD_COUNT ? methods[index].name : NULL;
}

int tb_integrator_order(int index)
{
    return index >= 0 && index < METHOD_COUNT ? methods[index].order : 0;
}
